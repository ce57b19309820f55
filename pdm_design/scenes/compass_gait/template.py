"""`pdm-design init compass_gait`: a commented spec to start from (the classic walker on a 3
degree ramp; its [initial] is near its gait, which is found from it)."""

from __future__ import annotations


def compass_gait_template() -> str:
    return '''# A passive compass-gait walker on a ramp (pdm-design init compass_gait).
# Every key is in docs/spec.md and docs/compass_gait.md; SI units: m, kg, s, rad.
name = "my_walker"
description = "A two-legged passive walker: its gait, its stability, its margins."

[scene]
kind = "compass_gait"
gravity = 9.81          # m/s^2
friction = 1.0          # between foot and ground

[scene.walker]
hip_mass = 10.0         # kg
leg_mass = 5.0          # kg, each leg
leg_length = 1.0        # m
leg_com = 0.5           # m, each leg's centre of mass from the hip
leg_inertia = 0.0       # kg m^2 about that centre (0: point masses)
# model = "simplest"    # Garcia's simplest walker: light legs, mass at the feet

# The state just after a heel strike, a guess of the periodic gait (found from it). Each leg's
# angle is from the vertical, from its foot to the hip, positive downhill: the new stance leg
# leans back (< 0), the trailing swing leg forward (> 0).
[initial]
stance = -0.22          # rad
swing = 0.32            # rad
stance_rate = 1.1       # rad/s
swing_rate = 0.4        # rad/s

[design]                # a number is fixed; { min, max, initial } is free for the optimizer
slope = 0.0523599       # rad (3 degrees); or rise and tread for stairs
leg_com = { min = 0.3, max = 0.8, initial = 0.5 }

[objective]             # the most stable gait: the smallest spectral radius of the return map
min_spectral_radius = 1.0

[requirements]
max_spectral_radius = 0.9   # every disturbance shrinks by at least 10 % a step
stance_contact = 0.1        # the stance foot's normal force stays above 10 % of the weight

[verification]
stages = 50             # steps

[expect]
feasible = true
'''
