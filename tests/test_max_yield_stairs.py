"""The stairs' max_yield objective: the linearised rows against the yield map's own limits,
the linearised yield against the map's Monte Carlo yield, the NLP's term against the numeric
bound, and the optimised design against the worst-case optimum on the same builds."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ndtr
from test_max_yield import sign_test

from pdm_design.scenes.stairs.formulation.statistical import linearised_yield, row_reliability
from pdm_design.scenes.stairs.model import StairsDesign
from pdm_design.spec import load_spec
from pdm_design.spec.loader import parse_spec
from pdm_design.tolerances import Tolerance, Tolerances, run_builds
from pdm_design.tolerances.draw import draw
from pdm_design.tolerances.yield_ import wilson

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def _limit(scene, design, sign, stages, far=3.0):
    """The launch place deviation (sign +1 or -1) where the map's build first fails, by
    bisection: the map's own account of the rows the linearisation writes."""
    def passes(dev):
        return bool(run_builds(scene, design, {"launch_x": np.array([sign * dev])},
                               stages).passed[0])

    lo, hi = 0.0, far
    assert passes(lo) and not passes(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
    return 0.5 * (lo + hi)


def _scene_and_design(problem, radius=None):
    spec = load_spec(PROBLEMS / problem)
    scene = spec.scene
    if radius is not None:
        scene = dataclasses.replace(scene, ball=dataclasses.replace(scene.ball, radius=radius))
    return scene, spec.design_at()


@pytest.mark.parametrize("problem, radius", [
    ("stairs_yield.toml", None),            # a 5 cm ball, its disc clear of the riser
    ("paper_stairs_friction.toml", None),   # a 0.5 m ball (above the rise), rolling, spinning
    ("paper_stairs_frictionless.toml", 0.0),  # a point ball: over the nose, no disc
])
@pytest.mark.parametrize("stages", [1, 4])
def test_the_rows_meet_zero_where_the_map_fails_a_build(problem, radius, stages):
    # the launch place moves every landing alike (linear): each side's nearest row, its
    # reliability index times sigma, is the deviation at which the map fails the build, on
    # the nose side (overshooting the tread) and the riser side (the disc's back on the
    # nose above the riser: the grazing place, found by Newton's method in the rows, against
    # the map's root of the exact falling gap; a point ball's height over the nose)
    scene, design = _scene_and_design(problem, radius)
    sigma = 0.01
    tols = Tolerances((Tolerance("launch_x", "lot", 3.0 * sigma),))
    g, sd, names = row_reliability(scene, design, tols, stages)
    moved = sd > 1e-9
    reach = {name: (g / sd)[moved & (np.array(names) == name)].min() * sigma
             for name in ("skipped_step", "nose_hit")}
    assert reach["skipped_step"] == pytest.approx(_limit(scene, design, +1, stages), rel=1e-9)
    assert reach["nose_hit"] == pytest.approx(_limit(scene, design, -1, stages), rel=1e-9)


@pytest.mark.parametrize("problem, short, landing, friction", [
    ("stairs_yield.toml", 0.1, 1.3, None),             # a 5 cm ball, frictionless
    ("paper_stairs_friction.toml", 0.05, 1.0, 0.05),   # a 0.5 m ball rolling, spinning
])
def test_the_linearised_yield_is_the_monte_carlo_yield_where_one_row_dominates(
        problem, short, landing, friction):
    # a tread `short` of the orbit's: the landing moves that far towards the nose every
    # bounce, so the last landing's overshoot row dominates the failures (the one before is
    # about two of its standard deviations further off, a share of the bound below 1 %).
    # Every quantity varies, small: the launch speed (which moves every landing, linearly),
    # the boards' restitution (and friction), every step's rise and tread; the map's yield
    # over 200 000 builds must hold the linearised yield within its 95 % interval
    from pdm_design.scenes.stairs.sim import stairs_geometry

    spec = load_spec(PROBLEMS / problem)
    scene = spec.scene
    orbit = stairs_geometry(scene, spec.design_at()).tread
    design = StairsDesign(restitution=0.8, launch_speed=3.0, tread=orbit - short,
                          landing_offset=landing)
    items = [Tolerance("launch_speed", "lot", 0.02), Tolerance("restitution", "lot", 0.0003),
             Tolerance("rise", "each", 0.001), Tolerance("tread", "each", 0.001)]
    if friction:
        items.append(Tolerance("friction", "lot", friction))
    tols = Tolerances(tuple(items))
    stages, builds = 10, 200_000
    g, sd, names = row_reliability(scene, design, tols, stages)
    tails = ndtr(-g / sd)
    order = np.argsort(tails)[::-1]
    assert names[order[0]] == "skipped_step" and order[0] == max(
        i for i, n in enumerate(names) if n == "skipped_step")  # the last landing's
    assert tails[order[1]] < 1e-2 * tails[order[0]]
    lin = linearised_yield(scene, design, tols, stages)
    assert 0.95 < lin["yield"] < 0.999  # a yield a sample of this size resolves
    out = run_builds(scene, design, draw(tols, builds, stages, seed=5, scene=scene), stages)
    assert out.closed_form.all()
    low, high = wilson(out.passed.sum(), builds)
    assert low <= lin["yield"] <= high, (lin["yield"], low, high)
    # the failures are overshoots (beyond the tread, or onto its nose: the map names a disc
    # that overshoots by less than its radius and touches the nose nose_hit), nearly all the
    # last landing's
    failed = ~out.passed
    assert set(out.failure[failed]) <= {"skipped_step", "nose_hit"}
    assert np.mean(out.stages_passed[failed] == stages - 1) > 0.98
    print(f"linearised {lin['yield']:.5f}, map {out.passed.mean():.5f} ({low:.5f}-{high:.5f})")


def test_max_yield_is_accepted_on_stairs_at_given_tolerances():
    data = {"scene": {"kind": "stairs", "ball": {"radius": 0.05}},
            "initial": {"drop_height": 1.0},
            "design": {"restitution": 0.8, "launch_speed": 3.0,
                       "landing_offset": {"min": 0.0, "max": 3.0}},
            "objective": {"max_yield": 1.0}}
    from pdm_design.errors import SpecError

    with pytest.raises(SpecError, match="objective.max_yield"):
        parse_spec(data)
    data["tolerances"] = {"rise": {"allocate": True}}
    with pytest.raises(SpecError, match="a tolerance to allocate"):
        parse_spec(data)
    data["tolerances"] = {"rise": {"value": 0.005}}
    assert parse_spec(data).objective == {"max_yield": 1.0}


@pytest.mark.slow  # two optimisations and their yields (30-60 s): the slow suite, CI's own step
def test_the_max_yield_design_outyields_the_worst_case_optimum_on_the_same_builds():
    # stairs_yield_design (100 bounces): optimised for yield and for the worst-case box of the
    # steps, each design built with the same seed (the same deviations) and judged by the map
    # (every build stays in its closed forms here: asserted). Paired on the builds: of the
    # builds one design passes and the other fails, the max_yield design must win
    # significantly (exact one-sided sign test, p < 0.05)
    from pdm_design.solve import optimize

    spec = load_spec(PROBLEMS / "stairs_yield_design.toml")
    stages, builds = spec.verification.stages, 3000
    deviations = draw(spec.tolerances, builds, stages, seed=0, scene=spec.scene)
    passed = {}
    for objective in ("max_yield", "max_offset_tolerance"):
        asked = dataclasses.replace(spec, objective={objective: 1.0})
        found = optimize(asked, check_samples=0)
        assert found.status.name == "OPTIMAL"
        design = asked.design_at(found.design)
        if objective == "max_yield":  # the NLP's term (inlined SX) is the numeric bound's
            bound = linearised_yield(asked.scene, design, asked.tolerances, stages)
            assert found.objectives["max_yield"] == pytest.approx(
                -math.log10(bound["failure_bound"]), rel=1e-6)
            assert bound["failure_bound"] < bound["union_bound"]
        out = run_builds(asked.scene, design, deviations, stages)
        assert out.closed_form.all()
        passed[objective] = out.passed
    better, worse, p_value = sign_test(passed["max_yield"], passed["max_offset_tolerance"])
    print(f"builds only max_yield passes: {better}, only the worst case: {worse}, "
          f"p = {p_value:.2g}")
    assert better > worse and p_value < 0.05, (better, worse, p_value)


def test_max_yield_on_manipulators_takes_real_links_and_refuses_damping_in_words():
    # the manipulators' linearised yield takes the carry on real links and with pivot
    # friction (its closed forms); damped pivots, which have none, are refused (exit 2 at the
    # CLI) rather than optimised for a yield that leaves them out
    from pdm_design.errors import SpecError

    base = {"scene": {"kind": "manipulators", "body": {"mass": 1.0, "width": 0.4,
                                                       "height": 0.2},
                      "palm": {"width": 1.6, "thickness": 0.05, "friction": 0.8}},
            "initial": {"position": [-1.25, 3.05], "velocity": [3.0, 0.0]},
            "design": {"alpha": {"min": 0.0, "max": 0.6}, "beta": 0.5, "link_length": 2.0,
                       "mass_ratio": 10.0},
            "objective": {"max_yield": 1.0}, "tolerances": {"pivot_x": {"value": 0.01}}}
    assert parse_spec(base).objective == {"max_yield": 1.0}
    for extra in ({"links": {"mass": 0.5}}, {"pivots": {"friction_torque": 0.2}}):
        data = {**base, "scene": {**base["scene"], **extra}}
        assert parse_spec(data).objective == {"max_yield": 1.0}
    data = {**base, "scene": {**base["scene"], "pivots": {"damping": 0.1}}}
    with pytest.raises(SpecError, match="objective.max_yield.*undamped pivots"):
        parse_spec(data)


@pytest.mark.parametrize("eps", [0.05, 0.5, 0.99])
def test_the_linearised_yield_is_the_same_at_any_size_and_finite_at_extreme_restitutions(eps):
    # lengths x k, speeds x sqrt(k), length tolerances x k: the same staircase at another
    # size, the same yield (every row is divided by the tread); at restitution 0.05 the
    # nominal build already lands twice on a tread (the map fails every build): yield 0;
    # at 0.5 and 0.99 (30 bounces, about 99.8 % and 98.7 %) the Monte Carlo yield
    from pdm_design.scenes.stairs.model import Ball, StairsInitial, StairsScene

    def at(k):
        scene = StairsScene(initial=StairsInitial(drop_height=k), ball=Ball(radius=0.05 * k))
        design = StairsDesign(restitution=eps, launch_speed=3.0 * math.sqrt(k))
        tols = Tolerances((Tolerance("rise", "each", 0.005 * k),
                           Tolerance("tread", "each", 0.005 * k),
                           Tolerance("launch_speed", "lot", 0.015 * math.sqrt(k)),
                           Tolerance("restitution", "lot", min(0.0015, (1.0 - eps) / 3.0))))
        return scene, design, tols, linearised_yield(scene, design, tols, 30)

    scene, design, tols, unit = at(1.0)
    assert np.isfinite(unit["min_beta"]) and 0.0 <= unit["yield"] <= 1.0
    for k in (1e-3, 1e3):
        other = at(k)[3]
        assert other["min_beta"] == pytest.approx(unit["min_beta"], rel=1e-9)
        assert other["failure_bound"] == pytest.approx(unit["failure_bound"], rel=1e-8)
    builds = 40_000
    out = run_builds(scene, design, draw(tols, builds, 30, seed=1, scene=scene), 30)
    if eps == 0.05:
        assert unit["yield"] == 0.0 and not out.passed.any()
    else:  # and the map's yield over 40 000 builds holds it in its 95 % interval
        low, high = wilson(out.passed.sum(), builds)
        assert low <= unit["yield"] <= high, (unit, low, high)


def test_the_new_failure_probability_of_a_row_is_the_bivariate_normal_one():
    # log P(g_a >= 0, g_b < 0) (Hunter's bound's term, chain_moments.log_new_failure, by
    # Gauss-Legendre panels in logarithms) against scipy: the bivariate normal CDF where it is
    # accurate, adaptive quadrature of the same probability's integral into the far tail
    import casadi as ca
    from scipy.integrate import quad
    from scipy.stats import multivariate_normal, norm

    from pdm_design.formulation.chain_moments import log_new_failure

    a, b, r = ca.SX.sym("a"), ca.SX.sym("b"), ca.SX.sym("r")
    fn = ca.Function("d", [a, b, r], [log_new_failure(a, b, r)])
    for ba in (-1.0, 0.0, 2.0, 3.0, 5.0):
        for bb in (-1.0, 0.5, 2.0, 3.0, 5.0, 8.0):
            for rho in (-0.5, 0.0, 0.5, 0.9, 0.99, 0.999, 0.99999):
                got = math.exp(float(fn(ba, bb, rho)))
                s = math.sqrt(1.0 - rho * rho)
                want = quad(lambda z, ba=ba, rho=rho, s=s: norm.pdf(z) * norm.cdf(
                    (ba + rho * z) / s), -np.inf, -bb, epsabs=0.0, epsrel=1e-12,
                    limit=500)[0]
                if max(ba, bb) < 4.0:
                    both = multivariate_normal([0.0, 0.0], [[1.0, rho], [rho, 1.0]]).cdf(
                        [-ba, -bb])
                    assert norm.cdf(-bb) - both == pytest.approx(want, rel=1e-4, abs=1e-9)
                tol = 3e-3 if bb > 0.0 else 3e-2  # a row failing at the mean: 3 %
                assert got == pytest.approx(want, rel=tol), (ba, bb, rho, got, want)


def test_hunters_bound_on_a_long_staircase_is_the_monte_carlo_failure_rate():
    # stairs_yield, 100 bounces: the lot's restitution and launch speed drift every landing
    # alike, so the same row fails bounce after bounce and the union bound counts one build's
    # failure many times (a bound of 59 % where 4 % fail). Hunter's bound (each row's failures
    # less those it shares with its own one bounce before) is an upper bound, and here near
    # the map's failure rate over 20 000 builds
    spec = load_spec(PROBLEMS / "stairs_yield.toml")
    scene, design, tols = spec.scene, spec.design_at(), spec.tolerances
    stages, builds = 100, 20_000
    lin = linearised_yield(scene, design, tols, stages)
    out = run_builds(scene, design, draw(tols, builds, stages, seed=11, scene=scene), stages)
    assert out.closed_form.all()
    low, high = wilson(out.passed.sum(), builds)
    fail_low, fail_high = 1.0 - high, 1.0 - low
    assert lin["union_bound"] > 10.0 * fail_high  # the union bound: far above
    assert fail_low <= lin["failure_bound"] <= 1.25 * fail_high, (lin, fail_low, fail_high)
