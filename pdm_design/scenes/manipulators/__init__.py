"""The manipulators scene: an object passed along a row of passive parallelogram manipulators.

Its scene object is `plugin.Manipulators` (entry point `manipulators` of the group
`pdm_design.scenes`).
"""
