"""Steps before failure on a rough ramp: the Monte Carlo survival against an exact probability,
the Markov chain's mean first-passage time against Monte Carlo, and its speed on a long-lived
design."""

import math

import numpy as np
import pytest

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    rough,
)
from pdm_design.scenes.rimless_wheel.analysis import analyse_rimless_wheel

DESIGN = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=0.08)


def scene_at(speed, friction=1.0):
    return RimlessWheelScene(initial=RimlessWheelInitial(speed=speed), friction=friction)


def orbit_speed():
    return analyse_rimless_wheel(scene_at(1.0), DESIGN).periodic["post_impact_speed"]


def test_one_step_survival_against_the_exact_probability():
    """A point mass of 8 spokes on a 0.08 rad ramp, on its orbit, one step with the slope
    N(0.08, sigma): it stalls in the next stance (making 1 step, not 2) iff
    E_1 = eta^2 E* + b(beta) < 0, with eta^2 = cos^2(pi/4) = 1/2, rate = 2 g and
    b(beta) = 2 g (cos(beta - alpha) - 1 + (1 - cos(beta + alpha)) / 2): the threshold found
    here by bisection on that written-out formula."""
    g, alpha, gamma = 9.81, math.pi / 8, 0.08
    rate = 2 * g
    w2 = 0.5 * rate * 2 * math.sin(alpha) * math.sin(gamma) / 0.5  # omega*^2, eta^2 = 1/2
    e_star = w2 - rate * (1 - math.cos(gamma - alpha))

    def e_next(beta):
        return 0.5 * e_star + rate * (0.5 * (1 - math.cos(beta + alpha))
                                      - (1 - math.cos(beta - alpha)))

    lo, hi = gamma - 1.0, gamma
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if e_next(mid) > 0 else (mid, hi)
    tolerance = 0.12
    sigma = tolerance / 3
    exact = 0.5 * math.erfc((hi - gamma) / sigma / math.sqrt(2))  # P(beta > threshold)
    assert rough.survival_one_step_exact(scene_at(orbit_speed(), 50.0), DESIGN, tolerance) == \
        pytest.approx(exact, rel=1e-9)
    samples = 200_000
    mc = rough.monte_carlo(scene_at(orbit_speed(), 50.0), DESIGN, tolerance, steps=2,
                           samples=samples, seed=11)
    assert set(mc["failures"]) == {"stalled"} and mc["survival"][1] == 1.0
    se = math.sqrt(exact * (1 - exact) / samples)
    assert abs(mc["survival"][2] - exact) < 4.5 * se


@pytest.mark.parametrize("slope,tolerance,speed,kind", [
    (0.08, 0.045, 1.1, "stalled"), (0.08, 0.03, 1.1, "stalled"),
    (0.22, 0.09, 1.5, "flight"),  # steep: the fast steps leave the ground
])
def test_mfpt_agrees_with_monte_carlo(slope, tolerance, speed, kind):
    scene = scene_at(speed)
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=slope)
    chain = rough.mfpt(scene, design, tolerance, bins=200)
    mc = rough.monte_carlo(scene, design, tolerance, steps=2000, samples=3000, seed=5)
    assert set(mc["failures"]) == {kind}
    assert mc["censored"] == 0
    assert chain["ci_low"] <= chain["estimate"] <= chain["ci_high"]
    assert abs(chain["estimate"] - mc["mean"]) < 4.5 * mc["standard_error"] + (
        chain["ci_high"] - chain["ci_low"])
    # the survival curve's tail is geometric: the mean equals the curve's sum
    assert np.sum(mc["survival"][1:]) == pytest.approx(mc["mean"], rel=1e-12)


def test_a_ten_million_step_design_has_a_tight_interval():
    """Rare failures: estimates far past any Monte Carlo, each with a narrow interval (the
    time they take is results/bench_rimless_wheel.py's)."""
    out = rough.mfpt(scene_at(1.1), DESIGN, 0.012)
    assert out["estimate"] >= 1e6 and out["ci_low"] > 0.99 * out["estimate"]
    longer = rough.mfpt(scene_at(1.1), DESIGN, 0.0105)
    assert longer["estimate"] >= 1e7
    assert longer["ci_high"] - longer["ci_low"] < 0.01 * longer["estimate"]


def test_rough_statistics_are_for_a_ramp():
    scene = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.0), ground="stairs")
    with pytest.raises(ValueError, match="ramp"):
        rough.mfpt(scene, RimlessWheelDesign(spokes=8, leg_length=1.0, rise=0.1), 0.01)


def test_a_start_too_slow_to_vault_lasts_no_step():
    """E_0 = omega0^2 - 2 g (1 - cos(gamma - alpha)) < 0: the first stance stalls."""
    slow = math.sqrt(2 * 9.81 * (1 - math.cos(0.08 - math.pi / 8))) * 0.99
    assert rough.mfpt(scene_at(slow), DESIGN, 0.03)["estimate"] == 0.0
    mc = rough.monte_carlo(scene_at(slow), DESIGN, 0.03, steps=5, samples=100)
    assert mc["mean"] == 0.0 and mc["failures"] == {"stalled": 100}


def test_the_search_finds_the_slope_a_bounded_scalar_search_finds():
    """longest_lasting (a coarse look over every count at once, then a zoom and a parabola's
    vertex on the chain at bins / 2) against scipy's bounded scalar search of log mfpt over the
    whole slope range on the same chain, for the count it chooses."""
    from scipy.optimize import minimize_scalar

    from pdm_design.scenes.rimless_wheel.rough import chain_mfpt, longest_lasting

    scene = scene_at(1.5)
    found = longest_lasting(scene, range(6, 13), (0.01, 0.4), 1.0, 0.15, bins=200)
    n = found["spokes"]
    assert n in found["refined"]

    def minus_log(slope):
        wh = rough._wheel_at(scene, n, 1.0, slope)
        start = 1.5**2 - wh.rate * (1 - math.cos(slope - wh.alpha))
        return -math.log(max(chain_mfpt(wh, start, 0.05, 100), 1e-300))

    best = minimize_scalar(minus_log, bounds=(0.01, 0.4), method="bounded",
                           options={"xatol": 1e-6})
    assert found["slope"] == pytest.approx(best.x, abs=5e-4)
    assert found["by_count"][n][1] == pytest.approx(math.exp(-best.fun), rel=1e-3)
