"""The yield of rimless wheel builds against an exact probability (a one-quantity case), and the
builds' step map against the event simulator."""

import math

import numpy as np
import pytest

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
)
from pdm_design.scenes.rimless_wheel.builds import run_builds
from pdm_design.scenes.rimless_wheel.sim import simulate_rimless_wheel

SCENE = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.4), ground="stairs")


def test_one_step_yield_is_the_probability_of_a_short_enough_rise():
    """8 spokes of 1 m, rise 0.1 m, matched tread, the wheel starting 0.755 m from the back of
    tread 0: foothold 1 is s_1 = s_0 + sqrt(c^2 - (rise + e)^2) - tread, past tread 1's nose iff
    rise + e <= sqrt(c^2 - (2 tread - s_0)^2), c = 2 sin(pi / 8): the build fails iff e is below
    that threshold, probability Phi(threshold / sigma)."""
    c = 2 * math.sin(math.pi / 8)
    tread = math.sqrt(c**2 - 0.1**2)
    threshold = math.sqrt(c**2 - (2 * tread - 0.755) ** 2) - 0.1
    sigma = 0.03
    exact = 1 - 0.5 * math.erfc(-threshold / sigma / math.sqrt(2))
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=0.1, landing_offset=0.755)
    builds = 200_000
    run = run_builds(SCENE, design, {"rise": 3 * sigma}, stages=1, builds=builds, seed=3)
    assert set(run.failure) == {"", "missed_tread"}
    se = math.sqrt(exact * (1 - exact) / builds)
    assert abs(run.yield_ - exact) < 4.5 * se
    assert run.survival()[1] == run.yield_


def test_builds_agree_with_the_event_simulator():
    """The same drawn builds: the map's steps made and failure against the simulator's."""
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=0.1, landing_offset=0.5)
    tolerances = {"rise": 0.15, "tread": 0.15}
    run = run_builds(SCENE, design, tolerances, stages=30, builds=10, seed=7)
    rng = np.random.default_rng(7)  # the draws of run_builds, in its order
    rng.normal(0.0, 0.0, 10)  # the start speed (no tolerance)
    rises = rng.normal(0.0, 0.05, (10, 30))
    treads = rng.normal(0.0, 0.05, (10, 30))
    for b in range(10):
        # tread k's error is drawn in column k - 1 (tread 0 is as designed)
        errors = [{"step": k + 1, "rise": float(rises[b, k]),
                   "tread": float(treads[b, k])} for k in range(30)]
        sim = simulate_rimless_wheel(SCENE, design, stages=30, step_errors=errors)
        assert sim.outcome.stages_passed == run.passed[b]
        kind = sim.outcome.failure.kind if sim.outcome.failure else ""
        assert kind == run.failure[b]
    assert len(set(run.failure)) >= 3 and len(set(run.passed)) >= 3  # failures compared too


def test_unknown_quantity_is_refused():
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=0.1)
    with pytest.raises(ValueError, match="slope"):
        run_builds(SCENE, design, {"slope": 0.01}, stages=3, builds=2)
