"""`pdm-design init stairs`: a commented spec to start from, that optimizes as written. It leaves
landing_offset out: every landing is mid-tread.
"""

from __future__ import annotations


def stairs_template() -> str:
    return '''# A ball bouncing down stairs (pdm-design init stairs).
# Every key is in docs/spec.md; SI units: m, kg, s, rad. Run: pdm-design optimize THIS_FILE
name = "my_stairs"
description = "A ball on frictionless stairs: the largest step error it tolerates."

[scene]
kind = "stairs"
gravity = 9.81          # m/s^2
friction = 0.0          # between ball and tread; above 0 the ball spins (needs a radius)

[scene.ball]
radius = 0.05           # m

[initial]
drop_height = 1.0       # m, the ball's lowest point above tread 1 at the (horizontal) launch

[design]                # a number is fixed; { min, max, initial } is free for the optimizer
restitution = 0.8       # the ball keeps this fraction of its vertical speed at each bounce
launch_speed = { min = 0.5, max = 3.0, initial = 2.0 }   # m/s
# (a faster launch makes longer treads with more room for errors: the optimum sits at the
# largest speed you allow, and the report says so: "at a bound: launch_speed (max 3 m/s)")
# rise and tread left out: the periodic bounce's, (1 - restitution^2) drop_height and the
# distance of one bounce. landing_offset left out: every landing is mid-tread (free it, as
# { min = 0, max = 3 }, to let the optimizer choose where on the tread the ball lands).

[objective]             # the largest error of every step's rise and tread
max_offset_tolerance = 1.0

[requirements]          # minimum margins (0 = just holds); names in docs/spec.md section 7
riser_clearance = 0.02

[verification]
stages = 20             # bounces

[expect]                # what `pdm-design check` demands of this spec
feasible = true
'''
