"""Numerical stability at the extremes: every case either matches an independent reference to a
stated tolerance or ends in a clear, named refusal - never NaN, inf, a hang or a traceback.

References are computed here, independently of the code under test: closed forms written out
afresh, mpmath quadrature at 30 digits for pendulum times (the simulator uses Carlson's R_F),
scipy's own brentq / elliprf for the pure-Python numerics.

Covered: restitution 0, near 0, near 1 and 1 (both scenes); mass ratios 1e-6 .. 1e6; alpha and
beta near 0 and near pi/2; lengths from millimetres to hundreds of metres and scale invariance;
long runs (thousands of manipulators here; the million-bounce stairs runs are in
tests/test_sim_stairs.py); hypothesis properties over wide ranges for the numerics, the
closed-form stage maps against the simulator, and the spec loader + command line.

Slow cases (`python -m pytest -m slow tests/test_extremes.py`): 100 000 manipulators, and many
more hypothesis examples.
"""

from __future__ import annotations

import json
import math
import random
import tomllib
from pathlib import Path

import mpmath
import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq as scipy_brentq
from test_fuzz_cli import dumps, leaves, replaced

from pdm_design.analysis import analyse
from pdm_design.cli import main
from pdm_design.scenes.manipulators.model import (
    Body,
    ManipulatorsDesign,
    ManipulatorsInitial,
    ManipulatorsScene,
    Palm,
)
from pdm_design.scenes.manipulators.sim import FAILURE_KINDS, handover_map, simulate_manipulators
from pdm_design.scenes.manipulators.sim import phases as ph
from pdm_design.scenes.stairs.model import Ball, StairsDesign, StairsInitial, StairsScene
from pdm_design.scenes.stairs.sim import FAILURE_KINDS as STAIRS_FAILURES
from pdm_design.scenes.stairs.sim import impact_map, impact_once, simulate_stairs
from pdm_design.sim.core import SimulationRefused
from pdm_design.sim.numerics import BRENT_RTOL, brentq, carlson_rf

G = 9.81
EPS = 2.220446049250313e-16
mpmath.mp.dps = 30
FAST = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])


# ============================================================ independent references

def fixed_point(alpha, beta, q, g=G, l=1.0):
    """s*^2 = 2 g l (cos a - cos b) / (1 - c), c = (q/(1+q))^2 cos^2(a + b); cos a - cos b as
    2 sin((a+b)/2) sin((b-a)/2) so that tiny angles keep their digits."""
    c = (q / (1.0 + q) * math.cos(alpha + beta)) ** 2
    gain = 2.0 * math.sin(0.5 * (alpha + beta)) * math.sin(0.5 * (beta - alpha))
    return math.sqrt(2.0 * g * l * gain / (1.0 - c)), c


def mp_swing_time(theta_a, theta_b, theta0, v0, g=G, l=1.0, *, turn=None):
    """int l dth / v(th), v^2 = v0^2 + 2 g l (cos th0 - cos th), by mpmath at 30 digits, split
    at 0 where the speed is smallest. turn: the (mpmath) turning angle, when it is one end: then
    th = turn + (other - turn) x^2 takes the 1/sqrt singularity out."""
    th0, v0, g, l = (mpmath.mpf(x) for x in (theta0, v0, g, l))

    def rate(th):
        return l / mpmath.sqrt(v0 ** 2 + 2 * g * l * (mpmath.cos(th0) - mpmath.cos(th)))

    if turn is not None:
        other = mpmath.mpf(theta_a if theta_b == turn else theta_b)
        span = other - turn

        def smooth(x):  # v^2 = 4 g l sin((th + turn)/2) sin((th - turn)/2), th - turn exact
            d = span * x * x
            v2 = 4 * g * l * mpmath.sin(turn + d / 2) * mpmath.sin(d / 2)
            return l / mpmath.sqrt(abs(v2)) * 2 * abs(span) * x if x else (
                l * 2 * mpmath.sqrt(abs(span)) / mpmath.sqrt(abs(2 * g * l * mpmath.sin(turn))))

        return float(mpmath.quad(smooth, [0, 1]))
    a, b = sorted((mpmath.mpf(theta_a), mpmath.mpf(theta_b)))
    points = [a, 0, b] if a < 0 < b else [a, b]
    return float(mpmath.quad(rate, points))


def mp_turning_angle(theta0, v0, g=G, l=1.0):
    c = mpmath.cos(mpmath.mpf(theta0)) + mpmath.mpf(v0) ** 2 / (2 * mpmath.mpf(g) * l)
    return -mpmath.acos(c)


def no_nan(result):
    """Every number a run reports is finite or None (failures may have empty states)."""
    for event in result.events:
        for state in (event.before, event.after):
            for value in state.values():
                assert math.isfinite(value), (event.kind, state)
        assert math.isfinite(event.time)
    for stage in result.stages:
        for value in stage.values():
            if isinstance(value, float):
                assert math.isfinite(value), stage


# ============================================================ the pure-Python numerics

S_BRENT = dict(root=st.floats(-10, 10), left=st.floats(1e-9, 10), right=st.floats(1e-9, 10),
               power=st.sampled_from([1, 3, 5]), tol=st.floats(1e-15, 1e-3),
               shape=st.sampled_from(["power", "exp", "atan", "step"]))


@FAST
@given(**S_BRENT)
def test_brentq_is_scipys_brentq_to_the_bit(root, left, right, power, tol, shape):
    funs = {"power": lambda x: (x - root) ** power, "exp": lambda x: math.expm1(x - root),
            "atan": lambda x: math.atan(5 * (x - root)) + (x - root) ** 3,
            "step": lambda x: math.floor(x - root) + 0.5}
    f = funs[shape]
    a, b = root - left, root + right
    assume(f(a) * f(b) < 0)
    expected = scipy_brentq(f, a, b, xtol=tol, rtol=BRENT_RTOL, maxiter=200)
    assert brentq(f, a, b, xtol=tol, maxiter=200) == expected


log_positive = st.floats(-200, 200).map(lambda e: 10.0 ** e)


S_RF = dict(x=log_positive | st.just(0.0), y=log_positive, z=log_positive)


@FAST
@given(**S_RF)
def test_carlson_rf_matches_mpmath_over_400_decades(x, y, z):
    # (scipy's elliprf gives nan for some of these; mpmath's works at any exponent)
    expected = float(mpmath.elliprf(mpmath.mpf(x), mpmath.mpf(y), mpmath.mpf(z)))
    assert carlson_rf(x, y, z) == pytest.approx(expected, rel=4e-15, abs=0)
    assert carlson_rf(y, x, z) == pytest.approx(carlson_rf(x, y, z), rel=4e-15)  # symmetric


def test_carlson_rf_refuses_what_diverges_or_is_negative():
    assert carlson_rf(0.0, 0.0, 1.0) == math.inf
    with pytest.raises(ValueError, match="non-negative"):
        carlson_rf(-1.0, 1.0, 1.0)


S_SWING = dict(theta0=st.floats(-1.5, 0.0), energy=st.floats(-6, 1), length=st.floats(-3, 2.5),
               gravity=st.floats(0.1, 100.0), reach=st.floats(0.0, 1.0))


@settings(max_examples=40, deadline=None)
@given(**S_SWING)
def test_swing_time_matches_30_digit_quadrature(theta0, energy, length, gravity, reach):
    """Swings that pass the top (E > 0, from 1e-6 to 10 above it) and swings that turn back
    (E < 0) over link lengths 1 mm .. 300 m: the closed form against mpmath."""
    l = 10.0 ** length
    e_gap = math.copysign(10.0 ** energy, reach - 0.5)  # E = v0^2/(2 g l) - 2 sin^2(th0/2)
    v2 = 2 * gravity * l * (e_gap + 2 * math.sin(0.5 * theta0) ** 2)
    assume(v2 > 0.0)
    v0 = math.sqrt(v2)
    turn = ph.turning_angle(theta0, v0, gravity=gravity, link_length=l)
    end = turn if turn is not None else theta0 + reach * (1.5 - theta0)
    assume(end - theta0 > 1e-9)
    got = ph.swing_time(theta0, end, theta0, v0, gravity=gravity, link_length=l, turn=turn)
    # to a turning point: the true one (30 digits), where the speed vanishes
    true_end = end if turn is None else mp_turning_angle(theta0, v0, gravity, l)
    expected = mp_swing_time(theta0, true_end, theta0, v0, gravity, l,
                             turn=None if turn is None else true_end)
    # Near the top the time grows like ln(1/|E|): |dT/dE| = 1/(2 omega |E|) to a turning point
    # just short of it, 1/(omega |E|) across it (mpmath agrees to 1e-6 at |E| ~ 1e-6). E is a
    # difference of terms of total size S, so its rounding alone moves the time by up to
    # eps S/(omega |E|), whatever the method: ~4e-11 of the time at |E| ~ 1e-6. Allowed: 1e-11
    # plus twice that, for swings that reach the top.
    size = v2 / (2 * gravity * l) + 2 * math.sin(0.5 * theta0) ** 2
    near_top = turn is not None or end >= 0.0
    conditioning = (2 * EPS * size / (math.sqrt(gravity / l) * abs(e_gap) * float(expected))
                    if near_top else 0.0)
    assert got == pytest.approx(expected, rel=1e-11 + conditioning)
    if turn is not None:
        assert turn == pytest.approx(float(true_end), rel=1e-13)


@pytest.mark.parametrize("gap", [1e-14, 1e-10, 1e-6])
def test_turning_point_a_hair_below_the_top(gap):
    """sin^2(th_t/2) = gap: the swing stops a hair below the top. Written as 2 asin(sqrt(gap)),
    the angle keeps the digits the inputs carry: gap = 2 sin^2(th0/2) - v0^2/(2 g l) is known to
    4 eps * (its two terms) absolutely, so th_t to half that relative to gap (acos(1 - 2 gap)
    would lose another 8 digits at gap = 1e-14)."""
    theta0, l = -0.3, 1.0
    v0 = math.sqrt(2 * G * l * (2 * math.sin(0.15) ** 2 - gap))
    true_gap = (2 * mpmath.sin(mpmath.mpf(theta0) / 2) ** 2 / 2
                - mpmath.mpf(v0) ** 2 / (4 * G * l))  # = -E/2 for the float inputs
    expected = -2 * float(mpmath.asin(mpmath.sqrt(true_gap)))
    turn = ph.turning_angle(theta0, v0, gravity=G, link_length=l)
    terms = 2 * math.sin(0.15) ** 2
    assert turn == pytest.approx(expected, rel=1e-15 + 2 * EPS * terms / gap, abs=0)
    t = ph.swing_time(theta0, turn, theta0, v0, gravity=G, link_length=l, turn=turn)
    expected_t = mp_swing_time(theta0, turn, theta0, v0, G, l, turn=mpmath.mpf(turn))
    assert math.isfinite(t) and t == pytest.approx(expected_t, rel=1e-9)


# ============================================================ manipulators

def periodic_start(alpha, beta, q, *, l=1.0, g=G, mu=10.0, eps=0.0, speed=None, hop=0.05):
    """A scene whose object arrives on palm 1 (at rest at -alpha) as if handed over by a previous
    palm at beta with speed `speed` (default: the fixed point s*): a short ballistic hop ending
    at the palm's centre with velocity speed * t(beta). Sizes scale with l."""
    s_star, c = fixed_point(alpha, beta, q, g, l)
    s = s_star if speed is None else speed
    vx, vy = s * math.cos(beta), -s * math.sin(beta)
    x_land, y_land = -l * math.sin(alpha), l * math.cos(alpha)
    hop_time = min(hop * math.sqrt(l / g), abs(vy) / g)  # starts above the palm's top
    vy0 = vy + g * hop_time
    scene = ManipulatorsScene(
        body=Body(mass=1.0, width=0.05 * l, height=0.01 * l),
        palm=Palm(width=0.5 * l, thickness=0.01 * l, friction=mu, restitution=eps),
        initial=ManipulatorsInitial(position=(x_land - vx * hop_time,
                                              y_land - vy0 * hop_time + 0.5 * g * hop_time ** 2),
                                    velocity=(vx, vy0)),
        gravity=g)
    design = ManipulatorsDesign(alpha=alpha, beta=beta, link_length=l, mass_ratio=q)
    return scene, design, s_star


def carry_time(alpha, beta, q, speed, g=G, l=1.0):
    """Landing -> handover time of a stuck carry: u = q/(1+q) s cos(a + b) from -alpha to beta."""
    u = q / (1 + q) * speed * math.cos(alpha + beta)
    return mp_swing_time(-alpha, beta, -alpha, u, g, l)


# (alpha, beta, m/M, friction): corners of the design space where the periodic orbit exists.
FEASIBLE = {
    "paper": (0.2, 0.6, 10.0, 10.0),
    "alpha exactly 0 (palm rests on the top)": (0.0, 0.6, 10.0, 10.0),
    "alpha 1e-12": (1e-12, 0.6, 10.0, 10.0),
    "angles 1e-6, palm 1e6 times lighter": (1e-6, 2e-6, 1e6, 10.0),
    "mass ratio 1e-6 (palm 1e6 times heavier), from the top": (0.0, 0.6, 1e-6, 10.0),
    "mass ratio 1e-3, from the top": (0.0, 0.6, 1e-3, 10.0),
    "mass ratio 1": (0.05, 0.6, 1.0, 10.0),
    "mass ratio 1e6": (0.2, 0.6, 1e6, 10.0),
    "alpha 0.25, light palm": (0.25, 0.5, 1e3, 10.0),
}


def stage_tolerances(beta, s_star, carried, l=1.0, g=G):
    """Stated tolerances of one stage. The handover is where the carried object's height
    l cos th (a number near l) meets the next palm's top, so cos th is known to a few ulp(l):
    the angle to 4 eps / sin(beta) (5e-11 rad at beta = 2e-6; 1e-15 at the paper's 0.6), the
    speed to v dv = g l d(cos th), the time to l d(th) / v. Beyond that: 1e-12 on speeds and
    angles, 1e-11 on times (the closed forms and the quadrature are exact to rounding)."""
    angle = 4 * EPS / math.sin(beta) + 1e-12 * beta
    speed = 1e-12 + 4 * EPS * g * l / s_star ** 2
    time = 1e-11 * carried + l * angle / s_star
    return angle, speed, time


@pytest.mark.parametrize("case", FEASIBLE)
def test_periodic_orbit_at_the_corners_matches_the_closed_forms(case):
    """Handover speed s* (closed form), handover angle beta, carry time (30-digit quadrature),
    to the tolerances of `stage_tolerances`."""
    alpha, beta, q, mu = FEASIBLE[case]
    scene, design, s_star = periodic_start(alpha, beta, q, mu=mu)
    result = simulate_manipulators(scene, design, stages=4)
    no_nan(result)
    assert result.outcome.completed, result.outcome.failure
    expected_time = carry_time(alpha, beta, q, s_star)
    angle_tol, speed_tol, time_tol = stage_tolerances(beta, s_star, expected_time)
    for stage in result.stages[:-1]:
        assert stage["handover_speed"] == pytest.approx(s_star, rel=speed_tol, abs=0)
        assert stage["handover_angle"] == pytest.approx(beta, rel=0, abs=angle_tol)
        carried = stage["handover_time"] - stage["landing_time"]
        assert carried == pytest.approx(expected_time, rel=0, abs=time_tol)


def lift_off_angle(alpha, u, l=1.0, g=G):
    """v^2 = u^2 + 2 g l (cos a - cos th) = g l cos th  ->  cos th = (u^2/(g l) + 2 cos a) / 3."""
    return math.acos((u * u / (g * l) + 2 * math.cos(alpha)) / 3)


# (alpha, beta, m/M, friction, the named failure, why)
REFUSED = {
    "beta a hair above alpha": (0.2, 0.2 + 1e-9, 10.0, 10.0, "stall",
                                "the orbit gains 1e-10 of height: too slow to pass the top"),
    "alpha + beta just above pi/2": (0.2, math.pi / 2 - 0.2 + 1e-9, 10.0, 2.0, "stall",
                                     "the landing pushes the palm into its back stop: the "
                                     "object slides to rest on the held palm"),
    "alpha near pi/2": (math.pi / 2 - 1e-6, math.pi / 2 - 1e-7, 10.0, 10.0, "stall",
                        "a palm lying flat cannot be carried over the top"),
    "beta near pi/2": (0.0, math.pi / 2 - 1e-9, 1e6, 1e6, "lift_off",
                       "the carry reaches v^2 = g l cos th long before beta"),
    "mass ratio 1e-6 with alpha 0.2": (0.2, 0.6, 1e-6, 10.0, "stall",
                                       "a palm 1e6 times heavier barely moves"),
}


@pytest.mark.parametrize("case", REFUSED)
def test_degenerate_corners_end_in_the_named_failure(case):
    alpha, beta, q, mu, kind, _ = REFUSED[case]
    scene, design, s_star = periodic_start(alpha, beta, q, mu=mu)
    result = simulate_manipulators(scene, design, stages=4)
    no_nan(result)
    failure = result.outcome.failure
    # a lift-off is not a failure: the object flies on, and the run ends in a named failure
    # later (or completes); the first of them is the one these corners predict
    first = next(e for e in result.events if e.failure or e.kind == "lift_off")
    assert first.kind == kind, first
    assert failure is None or (failure.kind in FAILURE_KINDS and failure.detail)
    u = q / (1 + q) * s_star * math.cos(alpha + beta)
    if kind == "lift_off":
        assert first.before["theta"] == pytest.approx(lift_off_angle(alpha, u), abs=1e-9)
        assert result.outcome.completed or failure is not None
    elif u > 0:  # the closed form agrees that the carry cannot pass the top
        assert u * u < 2 * G * (1 - math.cos(alpha))


@pytest.mark.parametrize("eps", [1e-300, 1e-12, 1e-8])
def test_restitution_near_0_is_the_plastic_orbit(eps):
    # separation slower than the Zeno speed 1e-4 sqrt(g l) ends in contact: the plastic closed form
    scene, design, s_star = periodic_start(0.2, 0.6, 10.0, eps=eps)
    result = simulate_manipulators(scene, design, stages=4)
    no_nan(result)
    assert result.outcome.completed
    for stage in result.stages[:-1]:
        assert stage["handover_speed"] == pytest.approx(s_star, rel=1e-12)


def dropped(eps, y0=2.5):
    """The object dropped straight onto palm 1, which its stop holds (tests/test_sim_manipulators
    uses the same drop with eps = 0.5 and 0.99, followed bounce by bounce)."""
    scene = ManipulatorsScene(
        body=Body(mass=1.0, width=0.4, height=0.2),
        palm=Palm(width=1.6, thickness=0.05, friction=0.8, restitution=eps),
        initial=ManipulatorsInitial(position=(-0.4, y0), velocity=(0.0, 0.0)), gravity=G)
    design = ManipulatorsDesign(alpha=0.2, beta=0.6, link_length=2.0, mass_ratio=10.0)
    return scene, design, math.sqrt(2 * G * (y0 - 2.0 * math.cos(0.2)))


@pytest.mark.parametrize("eps", [1 - 1e-4, 1 - 1e-9])
def test_restitution_near_1_hops_in_place_then_rests_at_the_closed_form_time(eps):
    # n hops leave faster than the Zeno speed: v0 eps^k > 1e-4 sqrt(g l), k = 1..n; they take
    # sum 2 v0 eps^k / g. Millions of hops, settled in closed form (not one event each).
    scene, design, v0 = dropped(eps)
    result = simulate_manipulators(scene, design, stages=1)
    no_nan(result)
    failure = result.outcome.failure
    assert failure.kind == "stall" and "hops in place" in failure.detail
    zeno = 1e-4 * math.sqrt(G * 2.0)
    n = math.floor(math.log(zeno / v0) / math.log(eps))  # hops k = 1..n
    airborne = sum(2 * v0 * float(mpmath.mpf(eps) ** k) / G for k in range(1, 4)) if n < 4 \
        else float(2 * mpmath.mpf(v0) * eps * (1 - mpmath.mpf(eps) ** n) / (G * (1 - eps)))
    t_drop = math.sqrt(2 * (2.5 - 2.0 * math.cos(0.2)) / G)
    assert failure.time == pytest.approx(t_drop + airborne, rel=1e-9)
    assert len(result.events) < 40


def test_restitution_1_is_refused_as_hopping_forever():
    scene, design, _ = dropped(1.0)
    result = simulate_manipulators(scene, design, stages=1)
    no_nan(result)
    failure = result.outcome.failure
    assert failure.kind == "stall" and "forever" in failure.detail
    assert len(result.events) < 40


@pytest.mark.parametrize("scale", [1e-3, 1.0, 300.0])
def test_manipulator_lengths_from_millimetres_to_hundreds_of_metres(scale):
    """Lengths x k with g fixed: speeds x sqrt(k), times x sqrt(k). The dimensionless orbit is the
    same, and matches the closed forms at every scale (1e-12 speeds, 1e-11 times)."""
    alpha, beta, q = 0.2, 0.6, 10.0
    scene, design, s_star = periodic_start(alpha, beta, q, l=scale)
    result = simulate_manipulators(scene, design, stages=4)
    assert result.outcome.completed
    unit_speed, unit_time = math.sqrt(G * scale), math.sqrt(scale / G)
    expected_time = carry_time(alpha, beta, q, s_star / math.sqrt(scale), l=1.0)
    for stage in result.stages[:-1]:
        assert stage["handover_speed"] / unit_speed == pytest.approx(
            fixed_point(alpha, beta, q, G, 1.0)[0] / math.sqrt(G), rel=1e-12)
        carried = (stage["handover_time"] - stage["landing_time"]) / unit_time
        assert carried == pytest.approx(expected_time / math.sqrt(1.0 / G), rel=1e-11)


@pytest.mark.parametrize("n", [2000])
def test_thousands_of_manipulators_do_not_drift(n):
    """Stated tolerance (`_long_row`): the fixed point is attracting (c = 0.40), so nothing
    accumulates in the speeds; what grows is the size of the coordinates (pivot n is n pitches
    from the origin), whose rounding, 4 eps n (pitch_x + pitch_y), sets the handover height
    and through it the speed. Times: 10x that, on top of 1e-11. The offset of the object on
    its palm is neutrally stable, so its rounding adds up: 2 eps n^2 (pitch_x + pitch_y)."""
    _long_row(n)


@pytest.mark.slow
def test_a_hundred_thousand_manipulators_do_not_drift():
    _long_row(100_000)


def _long_row(n):
    alpha, beta, q = 0.2, 0.6, 10.0
    scene, design, s_star = periodic_start(alpha, beta, q)
    result = simulate_manipulators(scene, design, stages=n)
    assert result.outcome.completed and result.outcome.stages_passed == n
    coordinates = n * (math.sin(alpha) + math.sin(beta) + math.cos(alpha) - math.cos(beta))
    drift = 4 * EPS * coordinates  # relative to l = 1
    speeds = np.array([s["handover_speed"] for s in result.stages[:-1]])
    assert np.abs(speeds / s_star - 1).max() < 1e-12 + drift
    first_landing = result.stages[0]["landing_time"]
    per_stage = carry_time(alpha, beta, q, s_star)
    assert result.stages[-1]["handover_angle"] == pytest.approx(beta, abs=1e-12 + drift)
    complete = result.events[-1].time
    assert complete - first_landing == pytest.approx(n * per_stage, rel=1e-11 + 10 * drift)
    # positions: the offset on the palm is neutrally stable (like the stairs' landing position),
    # so the per-stage rounding of coordinates ~k pitches long adds up: at worst
    # sum_k 4 eps k (pitch_x + pitch_y) = 2 eps n^2 (pitch_x + pitch_y) (1e-5 m at 1e5 stages)
    walk = 2 * EPS * n * coordinates
    offsets = np.array([s["landing_offset"] for s in result.stages])
    assert np.abs(offsets).max() < 1e-12 + walk


S_STAGE = dict(alpha=st.floats(0.0, 1.2), span=st.floats(0.01, 0.99), q=st.floats(-6, 6),
               length=st.floats(-3, 2.5), speed=st.floats(0.3, 3.0))


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(**S_STAGE)
def test_a_stage_is_the_closed_form_stage_map_or_a_named_failure(alpha, span, q, length, speed):
    """Over m/M in 1e-6..1e6, l in 1 mm..300 m and any alpha < beta < pi/2 (friction high
    enough that nothing slips): a stage of the simulator either hands over at the speed the
    vectorised closed form `handover_map` gives (1e-11), or ends in the failure the closed forms
    predict (stall where the map says it cannot pass the top, lift-off where v^2 >= g l cos th
    on the arc); never anything else."""
    beta = alpha + span * (math.pi / 2 - alpha)
    q, l = 10.0 ** q, 10.0 ** length
    s_star, _ = fixed_point(alpha, beta, q, G, l)
    arrival = speed * s_star
    scene, design, _ = periodic_start(alpha, beta, q, l=l, mu=1e6, speed=arrival)
    result = simulate_manipulators(scene, design, stages=2)
    no_nan(result)
    expected = float(handover_map(arrival, alpha, beta, q, G, l))
    u = q / (1 + q) * arrival * math.cos(alpha + beta)
    # what else the closed forms predict (body 0.05 l wide, 0.01 l high, centred on the palm):
    # lift-off where v^2 >= g l cos th (largest at an end of the arc); tipping where the force
    # crosses the base beyond w/2: at the landing impulse (h/2 |px/py|, px, py from the
    # momentum change s t(beta) -> u t(-alpha)) or in the carry (h/2 tan th).
    lift = max(u * u - G * l * math.cos(alpha),
               u * u + 2 * G * l * (math.cos(alpha) - math.cos(beta)) - G * l * math.cos(beta))
    px = u * math.cos(alpha) - arrival * math.cos(beta)
    py = u * math.sin(alpha) + arrival * math.sin(beta)
    w_over_h = 5.0
    predicted = set()
    if lift >= -1e-9 * G * l:
        predicted.add("lift_off")
    if abs(px) >= (1 - 1e-9) * w_over_h * py or math.tan(beta) >= (1 - 1e-9) * w_over_h:
        predicted |= {"tip", "rock"}  # the onset: the object rocks from there (rocking.py)
    first = result.stages[0] if result.stages else {}
    # a lift-off or a tip onset is an event the run goes on from: the first failure, lift-off
    # or onset is judged
    stop = next((e for e in result.events if e.failure or e.kind in ("lift_off", "rock")),
                None)
    if math.isnan(expected):  # cannot pass the top: a stall, unless something comes first
        assert stop.kind in predicted | {"stall"}, stop
    elif predicted:
        assert stop is not None
        assert stop.kind in predicted | {"stall"}, stop
    else:
        assert first.get("handover_speed") is not None, result.outcome.failure
        assert first["handover_speed"] == pytest.approx(expected, rel=1e-11)


def test_scales_double_precision_cannot_hold_are_refused():
    # The scene types bound every magnitude to [1e-6, 1e6]; the simulator still refuses, by
    # name, a scene spread over more than 1e12 (duck-typed scenes skip the types' checks).
    from types import SimpleNamespace

    from pdm_design.sim.core import check_scales

    with pytest.raises(SimulationRefused, match="initial y = 1e\\+13 is 1e\\+13 times"):
        check_scales(("the link length", 1.0), {"initial y": 1e13})
    with pytest.raises(SimulationRefused, match="the gravity"):
        check_scales(("the gravity", 1e-200), {})
    check_scales(("the link length", 1.0), {"initial y": 1e-300, "offset": 0.0})  # tiny is fine
    scene, design, _ = periodic_start(0.2, 0.6, 10.0)
    light = SimpleNamespace(**{k: getattr(design, k) for k in design.VARIABLES})
    light.mass_ratio = 1e13
    with pytest.raises(SimulationRefused, match="mass_ratio"):
        simulate_manipulators(scene, light, stages=2)


# ============================================================ stairs

def stairs(eps, *, h0=1.0, v0=2.0, radius=0.0, friction=0.0, inertia=0.0, mass=1.0,
           landing_offset=None, spin=0.0, g=G):
    scene = StairsScene(initial=StairsInitial(drop_height=h0, spin=spin),
                        ball=Ball(radius=radius, mass=mass, inertia=inertia),
                        friction=friction, gravity=g)
    return scene, StairsDesign(restitution=eps, launch_speed=v0, landing_offset=landing_offset)


def test_restitution_0_is_refused_by_name():
    scene, design = stairs(0.0)
    assert any("restitution 0" in p for p in analyse(scene, design).problems)
    result = simulate_stairs(scene, design, stages=5)
    assert result.outcome.failure.kind == "no_rebound"


@pytest.mark.parametrize("eps", [1e-6, 1e-3, 0.2])
def test_restitution_near_0_on_stairs_built_for_it(eps):
    """With rise (1 - eps^2) h0 the launch is only eps^2 h0 above the top landing, so the ball
    must be launched right over its nose: landing offset v0 sqrt(2 h0/g) minus a hair. Then every
    bounce is the closed-form orbit: impact speed hypot(v0, sqrt(2 g h0)), landing at the offset
    (1e-12 relative; 1e-9 m)."""
    h0, v0 = 1.0, 2.0
    t1 = math.sqrt(2 * h0 / G)
    hair = 0.1 * eps * v0 * math.sqrt(2 * h0 / G)  # drop to the nose << eps^2 h0
    scene, design = stairs(eps, landing_offset=v0 * t1 - hair)
    result = simulate_stairs(scene, design, stages=50)
    no_nan(result)
    assert result.outcome.completed, result.outcome.failure
    for stage in result.stages:
        assert stage["impact_speed"] == pytest.approx(math.hypot(v0, math.sqrt(2 * G * h0)),
                                                      rel=1e-12)
        assert stage["landing_x"] == pytest.approx(v0 * t1 - hair, abs=1e-9)


def test_restitution_near_0_with_the_default_landing_is_a_named_double_landing():
    # landing offset tread/2 puts the top landing's nose (1 - eps) v0 t1 / 2 ahead of the launch,
    # which falls h0 (1 - eps)^2 / 4 by then > eps^2 h0 for eps < 1/3: it lands on the top landing
    scene, design = stairs(1e-6)
    result = simulate_stairs(scene, design, stages=5)
    failure = result.outcome.failure
    assert (failure.kind, failure.after["step"]) == ("double_landing", 0)


@pytest.mark.parametrize("eps", [1 - 1e-15, 1 - 1e-9, 1.0])
@pytest.mark.parametrize("friction", [0.0, 0.5])
def test_restitution_near_and_at_1(eps, friction):
    """eps -> 1 flattens the stairs (rise (1 - eps^2) h0 -> 0; eps = 1 is a floor); the orbit
    keeps impact speed hypot(vx, sqrt(2 g h0)) with vx the rolling speed after the first impact."""
    ball = dict(radius=0.05, inertia=0.4 * 0.05 ** 2, friction=friction, spin=0.0)
    scene, design = stairs(eps, **ball)
    result = simulate_stairs(scene, design, stages=100)
    no_nan(result)
    assert result.outcome.completed, result.outcome.failure
    vx = 2.0 if friction == 0 else 2.0 * (1 - 0.4 / 1.4)  # rolling: (m r^2 vx) / (m r^2 + J)
    for stage in result.stages[1:]:
        assert stage["impact_speed"] == pytest.approx(math.hypot(vx, math.sqrt(2 * G)),
                                                      rel=1e-12)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 300.0])
def test_stairs_from_millimetres_to_hundreds_of_metres_are_one_dimensionless_run(scale):
    scene, design = stairs(0.8, h0=scale, v0=2.0 * math.sqrt(scale), radius=0.05 * scale,
                           friction=0.5, inertia=0.4 * (0.05 * scale) ** 2, spin=0.0)
    result = simulate_stairs(scene, design, stages=200)
    assert result.outcome.completed
    ref_scene, ref_design = stairs(0.8, h0=1.0, v0=2.0, radius=0.05, friction=0.5,
                                   inertia=0.4 * 0.05 ** 2)
    reference = simulate_stairs(ref_scene, ref_design, stages=200)
    for got, ref in zip(result.stages, reference.stages):
        assert got["landing_x"] / scale == pytest.approx(ref["landing_x"], rel=1e-12)
        assert got["impact_time"] / math.sqrt(scale) == pytest.approx(ref["impact_time"],
                                                                      rel=1e-12)
        assert got["impact_speed"] / math.sqrt(scale) == pytest.approx(ref["impact_speed"],
                                                                       rel=1e-12)


S_POINT = dict(eps=st.floats(0.34, 1.0), h0=st.floats(-3, 2), v0=st.floats(0.1, 10.0),
               gravity=st.floats(0.5, 50.0))


@FAST
@given(**S_POINT)
def test_point_ball_stairs_are_the_closed_form_orbit(eps, h0, v0, gravity):
    """Frictionless point ball, any restitution above 1/3 (below it the default landing is on
    the top landing, see above), drops 1 mm..100 m, any gravity: every impact at hypot(v0,
    sqrt(2 g h0)), every landing at tread/2 (1e-12 relative, 1e-12 tread)."""
    h0 = 10.0 ** h0
    v0 *= math.sqrt(gravity * h0)
    scene, design = stairs(eps, h0=h0, v0=v0, g=gravity)
    result = simulate_stairs(scene, design, stages=30)
    no_nan(result)
    assert result.outcome.completed, result.outcome.failure
    tread = v0 * (1 + eps) * math.sqrt(2 * h0 / gravity)
    for stage in result.stages:
        assert stage["impact_speed"] == pytest.approx(math.hypot(v0, math.sqrt(2 * gravity * h0)),
                                                      rel=1e-12)
        assert stage["landing_x"] == pytest.approx(tread / 2, abs=1e-12 * tread)


S_ANY_STAIRS = dict(eps=st.floats(0.0, 1.0), h0=st.floats(-3, 2), v0=st.floats(0.05, 20.0),
                    radius=st.floats(0.0, 0.5), friction=st.floats(0.0, 5.0),
                    spin=st.floats(-50, 50), inertia=st.floats(0.05, 1.0))


@FAST
@given(**S_ANY_STAIRS)
def test_any_stairs_run_is_a_result_or_a_named_refusal(eps, h0, v0, radius, friction, spin,
                                                       inertia):
    h0 = 10.0 ** h0
    r = radius * h0
    friction = friction if r > 0 else 0.0
    scene, design = stairs(eps, h0=h0, v0=v0 * math.sqrt(G * h0), radius=r, friction=friction,
                           inertia=inertia * r * r, spin=spin / max(r, h0) * math.sqrt(G * h0))
    try:
        result = simulate_stairs(scene, design, stages=40)
    except SimulationRefused as refusal:
        assert str(refusal)
        return
    no_nan(result)
    f = result.outcome.failure
    assert result.outcome.completed or (f.kind in STAIRS_FAILURES and f.detail)


S_IMPACT = dict(vx=st.floats(-1e3, 1e3), vy=st.floats(-1e3, -1e-3), omega=st.floats(-1e3, 1e3),
                eps=st.floats(0, 1), mu=st.floats(0, 10), r=st.floats(1e-3, 10),
                m=st.floats(1e-3, 1e3), j=st.floats(1e-6, 1e3))


@FAST
@given(**S_IMPACT)
def test_vectorised_impact_map_is_the_scalar_one(vx, vy, omega, eps, mu, r, m, j):
    got = impact_map(np.array([vx]), np.array([vy]), np.array([omega]), eps, mu, r, m, j)
    want = impact_once(vx, vy, omega, eps, mu, r, m, j)
    assert got.vx[0] == pytest.approx(want[0], rel=1e-12, abs=1e-12)
    assert got.vy[0] == pytest.approx(want[1], rel=1e-12, abs=1e-12)
    assert got.omega[0] == pytest.approx(want[2], rel=1e-12, abs=1e-9)
    assert bool(got.slipped[0]) == want[3]


# ============================================================ accuracy presets

def test_presets_and_custom_tolerances():
    from pdm_design.accuracy import ACCURACY_PRESETS, accuracy

    assert accuracy("fast") is ACCURACY_PRESETS["fast"]
    custom = accuracy({"base": "precise", "rtol": 1e-10})
    assert (custom.name, custom.rtol, custom.atol) == ("custom", 1e-10, 1e-14)
    assert accuracy(custom) is custom


@pytest.mark.parametrize("tolerances, key", [
    ({"rtol": 1e-16}, "rtol"), ({"atol": -1.0}, "atol"), ({"event_tol": math.nan}, "event_tol"),
    ({"agreement": 2.0}, "agreement"), ({"rtoll": 1e-9}, "rtoll"), ({"atol": "1e-9"}, "atol"),
])
def test_bad_tolerances_are_refused_by_name(tolerances, key):
    from pdm_design.accuracy import accuracy

    with pytest.raises(ValueError, match=key):
        accuracy(tolerances)


def test_verification_demands_the_presets_agreement():
    """verify_nominal compares the simulated handover speeds with the closed forms to the
    accuracy's `agreement`: the paper's design agrees to ~1e-16, so it passes every preset and
    fails only an agreement below that."""
    from pdm_design.accuracy import ACCURACY_PRESETS, accuracy
    from pdm_design.analysis import analyse
    from pdm_design.spec import load_spec
    from pdm_design.verify import verify_nominal

    spec = load_spec(Path(__file__).resolve().parents[1] / "problems" / "paper_manipulators.toml")
    point = spec.design_at()
    analysis = analyse(spec.scene, point)
    for preset in ACCURACY_PRESETS:
        report = verify_nominal(spec, point, analysis, accuracy=preset)
        assert report["passed"] and report["accuracy"] == preset
        assert report["agreement"]["relative_error"] < 1e-14
    strict = accuracy({"agreement": 1e-300})
    report = verify_nominal(spec, point, analysis, accuracy=strict)
    assert not report["passed"] and "disagree" in report["summary"]


# ============================================================ whole specs through the CLI

PAPER_SPECS = ("paper_manipulators", "paper_stairs_friction", "paper_stairs_frictionless")


def _spec_with(name, changes):
    root = Path(__file__).resolve().parents[1] / "problems"
    data = tomllib.loads((root / f"{name}.toml").read_text(encoding="utf-8"))
    numbers = [(p, v) for p, v in leaves(data) if isinstance(v, (int, float))
               and not isinstance(v, bool) and p[-1] != "stages"]
    for index, factor, sign in changes:
        path, value = numbers[index % len(numbers)]
        data = replaced(data, path, sign * abs(value or 1.0) * factor)
    return dumps(data)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(PAPER_SPECS),
       changes=st.lists(st.tuples(st.integers(0, 100), st.floats(-6, 6).map(lambda e: 10.0 ** e),
                                  st.sampled_from([1.0, 1.0, -1.0])), min_size=1, max_size=3))
def test_any_well_formed_spec_gives_a_report_or_a_clear_refusal(tmp_path_factory, name, changes):
    """Numbers 1e-6..1e6 times the paper's (either sign) anywhere in a spec: `optimize` exits 0,
    1 or 2, with strict JSON (no NaN, no inf) on 0/1 and a one-line message naming the file on
    2; never a traceback or an internal error."""
    spec = tmp_path_factory.mktemp("spec") / "extreme.toml"
    spec.write_text(_spec_with(name, changes), encoding="utf-8")
    result = CliRunner().invoke(main, ["optimize", str(spec), "--format", "json"])
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    assert "internal error" not in result.stderr
    assert result.exit_code in (0, 1, 2)
    if result.exit_code == 2:
        assert result.stderr.startswith(f"error: {spec}: ")
    else:
        doc = json.loads(result.stdout, parse_constant=_no_constant)
        assert doc["status"]


def _no_constant(name):
    raise AssertionError(f"{name} in the JSON document")


@pytest.mark.slow
def test_many_well_formed_specs_give_a_report_or_a_clear_refusal(tmp_path_factory):
    rng = random.Random(7)
    for _ in range(400):
        changes = [(rng.randrange(100), 10.0 ** rng.uniform(-6, 6), rng.choice([1.0, -1.0]))
                   for _ in range(rng.randint(1, 3))]
        test_any_well_formed_spec_gives_a_report_or_a_clear_refusal.hypothesis.inner_test(
            tmp_path_factory, rng.choice(PAPER_SPECS), changes)


# ============================================================ the full set (slow)

def _many(test, strategies, examples=1500):
    """A slow copy of a property test with many more examples."""

    @pytest.mark.slow
    @settings(max_examples=examples, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(**strategies)
    def many(**kwargs):
        test.hypothesis.inner_test(**kwargs)

    return many


test_brentq_many = _many(test_brentq_is_scipys_brentq_to_the_bit, S_BRENT)
test_carlson_rf_many = _many(test_carlson_rf_matches_mpmath_over_400_decades, S_RF)
test_swing_time_many = _many(test_swing_time_matches_30_digit_quadrature, S_SWING, 400)
test_stage_map_many = _many(test_a_stage_is_the_closed_form_stage_map_or_a_named_failure,
                            S_STAGE)
test_point_ball_stairs_many = _many(test_point_ball_stairs_are_the_closed_form_orbit, S_POINT)
test_any_stairs_many = _many(test_any_stairs_run_is_a_result_or_a_named_refusal, S_ANY_STAIRS)
test_impact_map_many = _many(test_vectorised_impact_map_is_the_scalar_one, S_IMPACT)
