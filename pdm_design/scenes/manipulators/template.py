"""`pdm-design init manipulators`: a commented spec to start from, that optimizes as written.

The template starts the object where its flight ends on the centre of palm 1's top surface: palm 1
rests at -alpha, so that centre is at (first_pivot_x - l sin alpha, first_pivot_y + l cos alpha)
(docs/spec.md, section 1), and an object launched horizontally at speed vx from a height `drop`
above it lands there after t = sqrt(2 drop / g), so it starts vx t behind it.
"""

from __future__ import annotations

import math

# The manipulators template: the paper's example 3 (section 4) with sizes of our choosing.
GRAVITY = 9.81
LINK, ALPHA = 2.0, 0.2  # m, rad: fixed, so that palm 1 does not move with the design
DROP, SPEED = 1.0, 3.0  # m above palm 1's top surface; m/s along the row


def manipulators_start(*, link=LINK, alpha=ALPHA, drop=DROP, speed=SPEED, gravity=GRAVITY,
                       pivot=(0.0, 0.0)) -> tuple[float, float]:
    """The start (x, y) whose horizontal launch at `speed` lands on palm 1's centre."""
    centre_x = pivot[0] - link * math.sin(alpha)
    centre_y = pivot[1] + link * math.cos(alpha)
    return centre_x - speed * math.sqrt(2.0 * drop / gravity), centre_y + drop


def manipulators_template() -> str:
    x0, y0 = manipulators_start()
    cx, cy = -LINK * math.sin(ALPHA), LINK * math.cos(ALPHA)
    return f'''# A row of passive parallelogram manipulators (pdm-design init manipulators).
# Every key is in docs/spec.md; SI units: m, kg, s, rad. Run: pdm-design optimize THIS_FILE
name = "my_manipulators"
description = "A 1 kg box passed along six manipulators: the largest pivot tolerance."

[scene]
kind = "manipulators"
gravity = {GRAVITY:g}           # m/s^2, acting in -y

[scene.body]            # the object carried
mass = 1.0              # kg
width = 0.4             # m, along the row
height = 0.2            # m

[scene.palm]
width = 1.6             # m, along the row: the object must land and stay within it
thickness = 0.05        # m
friction = 0.8          # Coulomb coefficient between object and palm
restitution = 0.0       # 0: the object lands without bouncing (the closed forms assume it)
front_stop = 1.5707963  # rad: where a palm that handed its object over is stopped

# The origin is the first manipulator's pivot; x runs along the row, y up. Palm 1 waits at
# -alpha, its top surface centred at (-link_length sin alpha, link_length cos alpha) =
# ({cx:.6g}, {cy:.6g}) m. The object is launched {DROP:g} m above it at {SPEED:g} m/s and
# falls for sqrt(2 x {DROP:g} / g) s: it lands on that centre. If you change alpha,
# link_length or the speed, move the start with them (the object must start above palm 1).
[initial]
position = [{x0:.9g}, {y0:.9g}]  # m, the centre of the object's base
velocity = [{SPEED!r}, 0.0]         # m/s

[design]                # a number is fixed; {{ min, max, initial }} is free for the optimizer
alpha = {ALPHA!r}             # rad, back-stop angle: fixed, since freeing it moves palm 1
beta = {{ min = 0.3, max = 1.0, initial = 0.6 }}   # rad, handover angle (beta > alpha)
link_length = {LINK!r}      # m
mass_ratio = {{ min = 2.0, max = 20.0, initial = 10.0 }}  # object mass / palm mass

[objective]             # the largest offset every pivot may be built off by, in x and y
max_offset_tolerance = 1.0

[requirements]          # minimum margins (0 = just holds); names in docs/spec.md section 7
landing = 0.05

[verification]
stages = 6              # manipulators the object must pass
samples = 16            # random builds inside the tolerance box, simulated

[expect]                # what `pdm-design check` demands of this spec
feasible = true
'''
