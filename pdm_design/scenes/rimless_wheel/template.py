"""`pdm-design init rimless_wheel`: a commented spec to start from (as pdm_design/templates.py).

The template's wheel: eight spokes of 1 m, a point mass, on a ramp whose slope is free. Its start
speed vaults the first spoke on every slope in the bounds: the slowest start 1.25 rad/s has
1.5625 (rad/s)^2 against 2 g / l (1 - cos(0.02 - pi / 8)) = 1.347 at the shallowest.
"""

from __future__ import annotations

GRAVITY = 9.81


def rimless_wheel_template() -> str:
    return f'''# A rimless wheel rolling down a ramp (pdm-design init rimless_wheel).
# Every key is in docs/spec.md and docs/rimless_wheel.md; SI units: m, kg, s, rad.
# Run: pdm-design optimize THIS_FILE
name = "my_rimless_wheel"
description = "An eight-spoke wheel: the ramp slope for the largest per-step slope error."

[scene]
kind = "rimless_wheel"
gravity = {GRAVITY:g}           # m/s^2
friction = 1.0          # Coulomb, spoke tip on the ground
ground = "ramp"         # or "stairs" (then design rise, and tread / landing_offset)

[scene.wheel]
mass = 1.0              # kg, at the hub
gyration = 0.0          # m, the hub's radius of gyration (0: a point mass)
spoke_mass = 0.0        # kg, each spoke a uniform rod (0: massless spokes)

[initial]
speed = 1.3             # rad/s, just after an impact
speed_tolerance = 0.05  # rad/s: the start lies anywhere in speed +- this

[design]                # a number is fixed; {{ min, max, initial }} is free for the optimizer
spokes = 8              # an integer >= 3 (free: {{ min = 6, max = 12 }}, each count solved)
leg_length = 1.0        # m
slope = {{ min = 0.02, max = 0.3, initial = 0.1 }}   # rad, downhill

[objective]             # the largest error of every step's own slope, in rad
max_offset_tolerance = 1.0

[verification]
stages = 20             # steps

[expect]
feasible = true
'''
