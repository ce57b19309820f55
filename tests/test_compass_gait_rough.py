"""Rough ground for the compass gait: the yield's builds on the step map against the event
simulator (ramp and stairs), and the mean steps before a fall by forward flux sampling against
plain Monte Carlo of walkers walked until they fall, and its survival formula against the
geometric law's closed form."""

import math

import numpy as np
import pytest

from pdm_design.scenes.compass_gait import (
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    rough,
)
from pdm_design.scenes.compass_gait.builds import build_outcome, simulate_build, walk_builds
from pdm_design.tolerance_model import Tolerance

SCENE = CompassGaitScene(initial=CompassGaitInitial(-0.22, 0.32, 1.1, 0.4))
RAMP = CompassGaitDesign(slope=math.radians(3.0))
STAIRS = CompassGaitDesign(rise=0.028, tread=0.53)


@pytest.mark.parametrize("design, name", [(RAMP, "slope"), (STAIRS, "rise")])
def test_builds_on_the_step_map_are_the_event_simulators(design, name):
    rng = np.random.default_rng(5)
    stages, builds = 40, 6
    size = 0.004 if name == "slope" else 0.0016
    deviations = {name: rng.normal(0.0, size, (builds, stages)),
                  "start_stance_rate": rng.normal(0.0, 0.02, builds)}
    out = build_outcome(SCENE, design, deviations, stages)
    assert (out.failure != "").any() and (out.failure == "").any()
    for i in range(builds):
        one = {k: v[i:i + 1] for k, v in deviations.items()}
        sim = simulate_build(SCENE, design, one, stages, accuracy="precise").outcome
        assert sim.stages_passed == out.stages_passed[i]
        assert (sim.failure.kind if sim.failure else "") == out.failure[i]


def test_mean_steps_is_the_geometric_laws():
    """A constant hazard h (falls from A only): the mean steps made is (1 - h) / h."""
    h, n = 0.01, np.full(60, 1000.0)
    run = {"N": n, "D": h * n, "E": np.zeros(60)}
    assert rough.mean_steps(run, 0.3)[0] == pytest.approx((1 - h) / h, rel=1e-12)


def _monte_carlo(t, walkers, steps, seed=11):
    """Steps each walker made before its fall, walked until every one fell."""
    deviations = {"slope": np.random.default_rng(seed).normal(0.0, t / 3, (walkers, steps))}
    run = walk_builds(SCENE, RAMP, deviations, steps)
    assert np.all(run.fall >= 0)  # none still standing: the mean is not censored
    return run.steps.mean(), run.steps.std(ddof=1) / math.sqrt(walkers)


@pytest.mark.slow  # the Monte Carlo walkers: about 9 s
def test_flux_sampling_agrees_with_monte_carlo():
    """t = 0.012 rad: a mean of about 70 steps; levels forced (reach 0.5, the last stage once
    95 % fall) so that the splitting's nested product is what is compared."""
    found = rough.mfpt(SCENE, RAMP, (Tolerance("slope", "each", 0.012),), reach=0.5,
                       last=0.95)
    assert min(found["levels"]) >= 2
    mean, se = _monte_carlo(0.012, 800, 600)
    assert found["ci_low"] - 3 * se <= mean <= found["ci_high"] + 3 * se
    assert found["ci_high"] / found["ci_low"] < 1.5


@pytest.mark.slow  # 10,000 walkers of 100 steps and the flux sampling: about 13 s
def test_rare_falls_agree_with_the_yield_over_a_hundred_steps():
    """t = 0.007 rad: falls too rare for walkers walked until they fall (thousands of steps);
    over 100 steps the yield of 2000 walkers on the step map sees a few dozen. With the hazard
    settled after a few steps, P(a fall within 100 steps) = 1 - exp(-100 / mfpt) to within
    the transient (a few steps of 100): the two intervals overlap."""
    tolerances = (Tolerance("slope", "each", 0.007),)
    found = rough.mfpt(SCENE, RAMP, tolerances)
    assert min(found["levels"]) >= 3  # the splitting is at work
    deviations = {"slope": np.random.default_rng(2).normal(0.0, 0.007 / 3, (2000, 100))}
    fell = np.mean(walk_builds(SCENE, RAMP, deviations, 100).fall >= 0)
    se = math.sqrt(fell * (1 - fell) / 2000)
    most, least = (1 - math.exp(-100 / found[k]) for k in ("ci_low", "ci_high"))
    assert least - 3 * se <= fell <= most + 3 * se


def test_no_mfpt_where_a_builds_ground_is_off_as_a_whole():
    """A slope off once for a whole build (a lot) makes each build a walker of its own: the
    yield's JSON then has no `mfpt`."""
    from pdm_design.plugin import scene_kind
    from pdm_design.tolerance_model import Tolerances

    gait = scene_kind("compass_gait")
    lot = Tolerances((Tolerance("slope", "each", 0.01), Tolerance("slope", "lot", 0.01)))
    assert gait.yield_extras(SCENE, RAMP, lot, 10) == {}
