"""The return map's Jacobian by AD (through the RK4 step and the heel-strike guard) against
central differences of the event simulator's return map (DOP853, events located)."""

import math

import numpy as np
import pytest

from pdm_design.accuracy import accuracy
from pdm_design.scenes.compass_gait import (
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    Walker,
)
from pdm_design.scenes.compass_gait.gait import find_gait
from pdm_design.scenes.compass_gait.ground import ground_of, params_for
from pdm_design.scenes.compass_gait.simulate import one_step
from pdm_design.scenes.compass_gait.stepmap import multipliers_of

CASES = [
    (Walker(hip_mass=10.0, leg_mass=5.0, leg_length=1.0, leg_com=0.5), 9.81, 0.0523599,
     (-0.22, 0.32, 1.1, 0.4)),
    (Walker(hip_mass=10.0, leg_mass=5.0, leg_length=1.0, leg_com=0.5), 9.81, 0.0785398,
     (-0.23, 0.39, 1.15, 0.13)),  # 4.5 deg: past the period doubling
    (Walker(hip_mass=8.0, leg_mass=2.0, leg_length=0.9, leg_com=0.35, leg_inertia=0.05), 9.81,
     0.06, (-0.22, 0.34, 1.2, 0.4)),
    (Walker(leg_length=1.0, leg_com=1.0, model="simplest"), 1.0, 0.009,
     (-0.19, 0.21, 0.2, 0.18)),
]


def simulated_map(params, ground, x):
    out = one_step(params, ground, np.asarray(x, dtype=float), math.inf, accuracy("precise"))
    assert out.kind == "step"
    return out.after


@pytest.mark.parametrize("walker,gravity,slope,start", CASES)
def test_ad_jacobian_matches_differences_of_the_simulator(walker, gravity, slope, start):
    scene = CompassGaitScene(initial=CompassGaitInitial(*start), walker=walker, gravity=gravity)
    design = CompassGaitDesign(slope=slope)
    gait = find_gait(scene, design)
    params = params_for(scene, design)
    ground = ground_of(design, params)
    x = np.asarray(gait.state)
    h = 1e-5
    fd = np.column_stack([(simulated_map(params, ground, x + h * e)
                           - simulated_map(params, ground, x - h * e)) / (2 * h)
                          for e in np.eye(4)])
    assert gait.jacobian == pytest.approx(fd, abs=2e-6 * max(1.0, np.abs(fd).max()))
    fd_multipliers = multipliers_of(fd)
    for ad, diff in zip(gait.multipliers, fd_multipliers):
        assert abs(ad - diff) < 1e-5
    assert gait.spectral_radius == pytest.approx(max(abs(m) for m in fd_multipliers), abs=1e-5)
