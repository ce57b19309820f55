"""Scenes: one package per kind of scene (a device and the object it moves), each behind the
scene interface (pdm_design.plugin.Scene) and registered as an entry point of the group
`pdm_design.scenes`; `common` holds the typed building blocks every scene's dataclasses use.

Nothing here imports a scene package: a command imports the one its spec names.
"""
