"""The stairs scene: a ball launched above a flight of stairs bounces down it, one step a bounce.

Its scene object is `plugin.Stairs` (entry point `stairs` of the group `pdm_design.scenes`).
"""
