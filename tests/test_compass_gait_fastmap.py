"""The vectorised RK4 step map against the event simulator (DOP853, located events): the same
states after a step, and the same steps and falls on rough ramps."""

import math

import numpy as np

from pdm_design.accuracy import accuracy
from pdm_design.scenes.compass_gait import (
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    fastmap,
)
from pdm_design.scenes.compass_gait.gait import find_gait
from pdm_design.scenes.compass_gait.ground import ground_of, params_for
from pdm_design.scenes.compass_gait.simulate import one_step, simulate_compass_gait

SCENE = CompassGaitScene(initial=CompassGaitInitial(-0.22, 0.32, 1.1, 0.4))
DESIGN = CompassGaitDesign(slope=math.radians(3.0))


def test_one_step_matches_the_event_simulator():
    gait = find_gait(SCENE, DESIGN)
    params = params_for(SCENE, DESIGN)
    ground = ground_of(DESIGN, params)
    rng = np.random.default_rng(3)
    starts = np.asarray(gait.state) + rng.normal(0, 0.01, (6, 4))
    fast = fastmap.walk(params, starts, DESIGN.slope, 1)
    for x, got in zip(starts, fast.state):
        out = one_step(params, ground, x, math.inf, accuracy("precise"))
        assert np.max(np.abs(got - out.after)) < 2e-7  # RK4 at 0.04 sqrt(l / g): 6e-8


def test_rough_ramp_walks_fail_alike():
    gait = find_gait(SCENE, DESIGN)
    params = params_for(SCENE, DESIGN)
    errors = np.random.default_rng(1).normal(0.0, 0.005, (8, 60))
    fast = fastmap.walk(params, np.tile(gait.state, (8, 1)), DESIGN.slope, 60,
                        friction=SCENE.friction, slope_errors=errors)
    for i in range(8):
        run = simulate_compass_gait(SCENE, DESIGN, stages=60, step_errors=errors[i],
                                    start=gait.state)
        assert run.outcome.stages_passed == fast.steps[i]
        kind = None if fast.fall[i] < 0 else fastmap.FALLS[fast.fall[i]]
        assert (run.outcome.failure.kind if run.outcome.failure else None) == kind
