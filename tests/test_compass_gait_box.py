"""The slope box of problems/compass_gait_robust.toml against the event simulator: the design
and box its NLP returns (hip_mass 5 kg and leg_com 0.3 m, both at their bounds; every step's
slope within +-0.009299 rad), walked from its periodic gait, the state the box is about, pass
every corner pattern (event simulator) and 500 random builds (the step map, within 1e-7 of
it); from the spec's [initial] guess, 0.4 rad/s of swing rate off the gait, the all-steeper
corner scuffs at step 6: the start, not a row, is what refuted the box before."""

import math

import numpy as np
import pytest

from pdm_design.scenes.compass_gait import CompassGaitDesign, fastmap
from pdm_design.scenes.compass_gait.ground import params_for
from pdm_design.scenes.compass_gait.plugin import box_start
from pdm_design.scenes.compass_gait.simulate import simulate_compass_gait
from pdm_design.spec import load_spec
from pdm_design.verify.tolerance import corner_patterns

SPEC = load_spec("problems/compass_gait_robust.toml")
DESIGN = CompassGaitDesign(slope=0.0523599, hip_mass=5.0, leg_com=0.3)
TAU, STAGES = 0.009299, 200


def _corners():
    seen = {}
    for name, signs in corner_patterns(STAGES):
        seen.setdefault(tuple(s for s, _ in signs), name)  # one axis: the slope's sign
    return [[TAU * s for s in signs] for signs in seen]


@pytest.mark.parametrize("errors", _corners())
def test_every_corner_pattern_walks_from_the_gait(errors):
    run = simulate_compass_gait(SPEC.scene, DESIGN, stages=STAGES, step_errors=errors,
                                start=box_start(SPEC.scene, DESIGN))
    assert run.outcome.completed


def test_random_builds_walk_from_the_gait_and_fail_beyond_the_box():
    params = params_for(SPEC.scene, DESIGN)
    start = np.tile(box_start(SPEC.scene, DESIGN), (500, 1))
    draws = np.random.default_rng(0).uniform(-1.0, 1.0, (500, STAGES))
    inside = fastmap.walk(params, start, DESIGN.slope, STAGES, SPEC.scene.friction, TAU * draws)
    assert np.all(inside.fall < 0)
    beyond = fastmap.walk(params, start, DESIGN.slope, STAGES, SPEC.scene.friction,
                          2.5 * TAU * draws)
    assert np.any(beyond.fall >= 0)  # the check can fail: the box is not far inside


def test_from_the_initial_guess_the_steeper_corner_scuffs():
    assert math.dist(SPEC.scene.initial.state(), box_start(SPEC.scene, DESIGN)) > 0.5
    run = simulate_compass_gait(SPEC.scene, DESIGN, stages=STAGES, step_errors=[TAU] * STAGES)
    assert not run.outcome.completed and run.outcome.failure.kind == "scuffed"
