"""Builds of a staircase: the vectorised map (run_builds) against the event simulator, build by
build, and yields against exact probabilities from the distributions' CDFs.

The thresholds of the exact cases are derived by hand below (the flight written out), or found
by an independent method (bounded minimisation of the sampled centre-to-corner distance and a
scalar root), never from the map's own output.
"""

import math

import numpy as np
import pytest
from scipy import optimize, stats

from pdm_design.scenes.stairs.model import Ball, StairsDesign, StairsInitial, StairsScene
from pdm_design.scenes.stairs.sim import FAILURE_KINDS, build_variation, simulate_stairs
from pdm_design.scenes.stairs.tolerances import FAILURES, march_builds, run_builds, simulate_build
from pdm_design.sim.core import SimulationRefused
from pdm_design.tolerances.outcome import BuildOutcome

G = 9.81
H0 = 1.0


def scene_of(radius=0.05, friction=0.0, spin=0.0, mass=1.0, inertia=0.0):
    return StairsScene(initial=StairsInitial(drop_height=H0, spin=spin),
                       ball=Ball(radius=radius, mass=mass, inertia=inertia), friction=friction)


ROBUST = StairsDesign(restitution=0.8, launch_speed=3.0, landing_offset=1.38)  # stairs_design
PAPER2 = dict(radius=0.5, mass=0.283, inertia=0.035, friction=0.5, spin=0.5)


def draws(rng, n, stages, scale, friction=False):
    dev = {"rise": rng.normal(0, 0.004 * scale, (n, stages)),
           "tread": rng.normal(0, 0.006 * scale, (n, stages)),
           "restitution": rng.normal(0, 0.004 * scale, (n, stages)),
           "launch_speed": rng.normal(0, 0.02 * scale, n),
           "launch_x": rng.normal(0, 0.01 * scale, n)}
    if friction:
        dev["friction"] = rng.normal(0, 0.1 * scale, (n, stages))
    return dev


def simulated(scene, design, dev, i, stages):
    result = simulate_build(scene, design, {k: v[i] for k, v in dev.items()}, stages)
    failure = result.outcome.failure
    return result, "" if failure is None else failure.kind


# --- the map and the simulator, build by build --------------------------------------------------

CASES = {
    "point ball": (scene_of(radius=0.0), StairsDesign(restitution=0.8, launch_speed=2.0), False),
    "small ball": (scene_of(), ROBUST, False),
    "friction and spin": (scene_of(**PAPER2), StairsDesign(restitution=0.8, launch_speed=3.0),
                          True),
}


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("scale", [1.0, 8.0])
def test_map_and_simulator_agree_build_by_build(case, scale):
    scene, design, friction = CASES[case]
    stages, n = 30, 120
    dev = draws(np.random.default_rng(7), n, stages, scale, friction)
    run = march_builds(scene, design, dev, stages)
    out = run.outcome
    assert out.closed_form.mean() > 0.9
    for i in np.flatnonzero(out.closed_form):
        result, kind = simulated(scene, design, dev, i, stages)
        assert (kind, result.outcome.stages_passed) == (out.failure[i], out.stages_passed[i]), i
        if result.stages:
            last = result.stages[-1]  # the state just after the last impact
            np.testing.assert_allclose(
                [run.landing[i], run.vx[i], run.vy[i], run.omega[i]],
                [last["landing_x"], last["vx"], last["vy_after"], last["spin_after"]],
                rtol=1e-9, atol=1e-9 * max(1.0, abs(last["spin_after"])))
    # the margin's sign is the verdict; the exact clearance agrees with it but at grazes
    failed = out.failure != ""
    assert np.array_equal(out.min_margin < 0.0, failed)
    assert np.all((run.raw_margin < 0.0) == failed | (np.abs(run.raw_margin) < 1e-9))
    assert np.all(np.abs(out.min_margin) <= 1.0)


def test_the_sample_meets_every_failure_the_map_names():
    seen = set()
    for scene, design, friction in CASES.values():
        for scale in (1.0, 8.0):
            dev = draws(np.random.default_rng(7), 120, 30, scale, friction)
            seen |= set(run_builds(scene, design, dev, 30).failure)
    assert {"", "double_landing", "skipped_step", "nose_hit"} <= seen


def test_an_unbuildable_step_fails_the_build_when_the_ball_gets_there():
    scene, stages = scene_of(), 6
    rise = np.zeros((3, stages))
    rise[0, 3] = -0.5           # step 4 goes up: the ball passes 3 steps
    rise[1, 0] = -0.5           # step 1: it passes none
    tread = np.zeros((3, stages))
    tread[2, 4] = -3.0          # step 5 has no tread
    dev = {"rise": rise, "tread": tread}
    out = run_builds(scene, ROBUST, dev, stages)
    assert list(out.failure) == ["unbuildable_step"] * 3
    assert list(out.stages_passed) == [3, 0, 4]
    assert np.all(out.min_margin < 0)
    for i in range(3):
        result, kind = simulated(scene, ROBUST, dev, i, stages)
        assert (kind, result.outcome.stages_passed) == ("unbuildable_step", out.stages_passed[i])


# --- the simulator's per-step materials and launch, against closed forms ------------------------

def test_each_step_bounces_with_its_own_restitution():
    scene = scene_of(radius=0.0)
    design = StairsDesign(restitution=0.6, launch_speed=2.0, rise=0.5, tread=3.0,
                          landing_offset=1.0)
    eps = [0.3, 0.7, 0.55]
    result = simulate_stairs(scene, design, stages=4, variation=build_variation(restitution=eps))
    v = math.sqrt(2 * G * H0)
    for n, record in enumerate(result.stages):
        e = eps[n] if n < 3 else 0.6    # beyond the list: the design's
        assert record["vy_before"] == pytest.approx(-v, rel=1e-12)
        assert record["vy_after"] == pytest.approx(e * v, rel=1e-12)
        v = math.sqrt((e * v) ** 2 + 2 * G * 0.5)  # falls one rise to the next tread


def test_each_tread_grips_with_its_own_friction():
    # first impact slides on step 1 (friction 0.05): vx+ = vx - mu (1 + eps) |vy| (Coulomb's
    # whole impulse, sliding throughout)
    scene = scene_of(**PAPER2)
    design = StairsDesign(restitution=0.8, launch_speed=3.0)
    variation = build_variation(friction=[0.05], radius=0.5)
    first = simulate_stairs(scene, design, stages=1, variation=variation).stages[0]
    vy = math.sqrt(2 * G * H0)
    assert first["slipped"]
    assert first["vx"] == pytest.approx(3.0 - 0.05 * 1.8 * vy, rel=1e-12)


def test_the_launch_lands_where_its_speed_and_place_put_it():
    scene, design = scene_of(), ROBUST
    t1 = math.sqrt(2 * H0 / G)
    dv, dx = 0.04, -0.03
    result = simulate_stairs(scene, design, stages=1,
                             variation=build_variation(launch_speed=3.0 + dv, launch_x=dx))
    assert result.stages[0]["landing_x"] == pytest.approx(1.38 + dx + dv * t1, abs=1e-12)
    dev = {"launch_speed": np.array([dv]), "launch_x": np.array([dx])}
    assert march_builds(scene, design, dev, 1).landing[0] == pytest.approx(1.38 + dx + dv * t1,
                                                                            abs=1e-12)


@pytest.mark.parametrize("kwargs, words", [
    (dict(restitution=[0.5, 1.2]), "step 2: restitution 1.2 is not in [0, 1]"),
    (dict(friction=[-0.1]), "step 1: friction -0.1 is negative"),
    (dict(friction=[0.1]), "needs a ball radius > 0"),
    (dict(launch_x=math.nan), "launch x nan is not a finite number"),
])
def test_impossible_materials_are_refused_in_words(kwargs, words):
    with pytest.raises(SimulationRefused, match=words.replace("[", r"\[").replace("]", r"\]")):
        build_variation(**kwargs)


# --- yields against the exact probability ---------------------------------------------------------

# a point ball launched at 2 m/s onto tread 1 (landing 0.5 m from its back, tread 1 m, rise
# 0.75 m): stage 2 is the flight from tread 1 with the lot's restitution e, up = e v1, v1 =
# sqrt(2 g h0). It comes down on tread 1 (double landing) iff L1 + v0 2 e v1 / g <= tread:
#     e <= e_lo = g (tread - L1) / (2 v0 v1);
# it passes tread 2 (skipped step) iff L1 + v0 (e v1 + sqrt(e^2 v1^2 + 2 g rise)) / g > 2 tread,
# squared out with q = g (2 tread - L1) / v0:   e > e_hi = (q^2 - 2 g rise) / (2 v1 q).
# Both sides increase with e, so the passing builds are exactly e_lo < e <= e_hi.
INTERVAL = StairsDesign(restitution=0.45, launch_speed=2.0, rise=0.75, tread=1.0,
                        landing_offset=0.5)


def point_ball_interval():
    v1 = math.sqrt(2 * G * H0)
    e_lo = G * (1.0 - 0.5) / (2 * 2.0 * v1)
    q = G * (2 * 1.0 - 0.5) / 2.0
    return e_lo, (q * q - 2 * G * 0.75) / (2 * v1 * q)


def _nose_gap(e, r):
    """Least distance (less r) from tread 1's nose corner to the centre of a ball of radius r
    leaving tread 1 at L1 = 0.5 with (2, e v1): coarse sampling, then a bounded minimiser."""
    v1 = math.sqrt(2 * G * H0)
    up, d = e * v1, 0.5
    t_end = (up + math.sqrt(up * up + 2 * G * 0.75)) / G

    def dist(t):
        return math.hypot(2.0 * t - d, r + up * t - 0.5 * G * t * t)

    ts = np.linspace(0.0, t_end, 2001)
    i = int(np.argmin([dist(t) for t in ts]))
    lo, hi = ts[max(i - 1, 0)], ts[min(i + 1, len(ts) - 1)]
    best = optimize.minimize_scalar(dist, bounds=(lo, hi), method="bounded",
                                    options={"xatol": 1e-13})
    return min(best.fun, dist(lo), dist(hi)) - r


def ball_interval(r):
    """Passing builds of the same flight with a ball of radius r: it must clear the nose
    corner (a root of the gap in e, above the double landing's e_lo) and land on tread 2 (its
    lowest point lands where the point ball's does: e_hi as before)."""
    e_lo, e_hi = point_ball_interval()
    return optimize.brentq(lambda e: _nose_gap(e, r), e_lo + 1e-9, e_hi, xtol=1e-14), e_hi


DISTRIBUTIONS = {
    "normal": (lambda rng, t, n: rng.normal(0.0, t / 3, n),
               lambda x, t: stats.norm.cdf(x, 0, t / 3)),
    "uniform": (lambda rng, t, n: rng.uniform(-t, t, n),
                lambda x, t: stats.uniform.cdf(x, -t, 2 * t)),
}


@pytest.mark.parametrize("radius", [0.0, 0.05])
@pytest.mark.parametrize("distribution, tolerance", [("normal", 0.3), ("uniform", 0.25)])
def test_yield_is_the_exact_probability_of_the_passing_interval(radius, distribution,
                                                                 tolerance):
    e_lo, e_hi = point_ball_interval() if radius == 0.0 else ball_interval(radius)
    assert 0.45 - tolerance < e_lo < 0.45 < e_hi < min(0.45 + tolerance, 1.0)  # both ends count
    draw, cdf = DISTRIBUTIONS[distribution]
    n = 200_000
    d = draw(np.random.default_rng(11), tolerance, n)
    out = run_builds(scene_of(radius=radius), INTERVAL, {"restitution": d}, 2)
    e = 0.45 + d
    inside = (e > e_lo) & (e <= e_hi)
    sure = np.minimum(np.abs(e - e_lo), np.abs(e - e_hi)) > 1e-9
    assert np.array_equal(out.passed[sure], inside[sure])       # build by build
    assert set(out.failure[(e > 0.0) & (e <= e_lo)]) <= {"double_landing", "nose_hit"}
    assert set(out.failure[e <= 0.0]) <= {"no_rebound"}   # taken at 0: it cannot bounce
    assert set(out.failure[e > e_hi]) <= {"skipped_step", "nose_hit"}
    exact = cdf(e_hi - 0.45, tolerance) - cdf(e_lo - 0.45, tolerance)
    half_width = 1.96 * math.sqrt(exact * (1 - exact) / n)
    assert abs(out.passed.mean() - exact) < 2 * half_width


# --- extremes -------------------------------------------------------------------------------------

@pytest.mark.parametrize("design, stages", [
    (ROBUST, 50),                                                         # passes
    (StairsDesign(restitution=0.8, launch_speed=3.0, landing_offset=2.2), 30),  # fails
])
def test_zero_tolerance_gives_the_nominal_yield_exactly(design, stages):
    scene = scene_of()
    zeros = {"rise": np.zeros((5, stages)), "restitution": np.zeros(5),
             "launch_speed": np.zeros(5)}
    out = run_builds(scene, design, zeros, stages)
    nominal = simulate_stairs(scene, design, stages=stages)
    kind = nominal.outcome.failure.kind if nominal.outcome.failure else ""
    assert list(out.failure) == [kind] * 5
    assert list(out.stages_passed) == [nominal.outcome.stages_passed] * 5
    assert out.passed.mean() == (1.0 if nominal.outcome.completed else 0.0)


def test_huge_tolerances_give_named_failures_not_nan():
    scene, stages, n = scene_of(), 40, 4000
    rng = np.random.default_rng(5)
    dev = {"rise": rng.normal(0, 0.5, (n, stages)), "tread": rng.normal(0, 2.0, (n, stages)),
           "restitution": rng.normal(0, 1.0, n), "launch_speed": rng.normal(0, 5.0, n),
           "launch_x": rng.normal(0, 3.0, n)}
    out = run_builds(scene, ROBUST, dev, stages)
    assert set(out.failure) <= set(FAILURES) and out.passed.sum() == 0
    assert np.all(np.isfinite(out.min_margin)) and np.all(out.min_margin < 0)
    counts = {k: int((out.failure == k).sum()) for k in FAILURES}
    assert counts["unbuildable_step"] > 0 and sum(counts.values()) == n
    assert np.all((out.stages_passed >= 0) & (out.stages_passed < stages))
    for i in np.flatnonzero(out.closed_form)[:40]:      # still the simulator's verdicts
        result, kind = simulated(scene, ROBUST, dev, i, stages)
        assert (kind, result.outcome.stages_passed) == (out.failure[i], out.stages_passed[i])
    outside = np.flatnonzero(~out.closed_form)
    assert outside.size > 0
    for i in outside[:20]:                              # the simulator takes them all, in words
        result, kind = simulated(scene, ROBUST, dev, i, stages)
        assert kind in (*FAILURE_KINDS, "unbuildable_step")


def test_a_simulated_build_takes_the_simulator_options():
    dev = {"tread": np.full(5, 0.01), "restitution": np.full(5, -0.001)}
    result = simulate_build(scene_of(), ROBUST, dev, 5, "fast", record_trajectory=True)
    assert result.outcome.completed and len(result.trajectory["time"]) > 5 * 48
    assert result.accuracy.name == "fast"
    assert result.stages[0]["vy_after"] == pytest.approx(0.799 * math.sqrt(2 * G * H0), rel=1e-12)


def test_no_builds_and_no_stages():
    empty = run_builds(scene_of(), ROBUST, {"tread": np.zeros((0, 3))}, 3)
    assert isinstance(empty, BuildOutcome) and empty.builds == 0
    none = run_builds(scene_of(), ROBUST, {"launch_speed": np.ones(4)}, 0)
    assert list(none.failure) == [""] * 4 and list(none.stages_passed) == [0] * 4


@pytest.mark.parametrize("deviations, words", [
    ({}, "number of builds is unknown"),
    ({"pivot_x": np.zeros(3)}, "unknown quantity 'pivot_x'"),
    ({"rise": np.zeros((3, 4))}, r"shape \(3, 4\), expected \(N,\) or \(N, 5\)"),
    ({"launch_x": np.zeros((3, 5))}, r"expected \(N,\)"),
    ({"rise": np.zeros(3), "tread": np.zeros(4)}, "4 builds, the others 3"),
    ({"tread": np.array([0.0, np.nan])}, "not every value is a finite number"),
])
def test_bad_deviations_are_refused_in_words(deviations, words):
    with pytest.raises(ValueError, match=words):
        run_builds(scene_of(), ROBUST, deviations, 5)


def test_friction_on_a_point_ball_is_refused():
    with pytest.raises(ValueError, match="point ball cannot roll"):
        run_builds(scene_of(radius=0.0), ROBUST, {"friction": np.zeros(2)}, 3)


# --- the yield command on a staircase, end to end -------------------------------------------------

def test_stairs_yield_end_to_end_and_a_failing_build_reproduced(tmp_path):
    # problems/stairs_yield.toml with 400 builds of 60 bounces and its tolerances doubled:
    # nose hits late in the flight, each one rerun by `simulate --build` to the same verdict
    import json
    from pathlib import Path

    from click.testing import CliRunner

    from pdm_design.cli import main

    text = (Path(__file__).resolve().parents[1] / "problems" / "stairs_yield.toml").read_text()
    text = text.replace("stages = 100", "stages = 60").replace("min_yield = 0.95", "")
    for old, new in (("0.005,", "0.01,"), ("0.0015,", "0.003,"), ("0.015,", "0.03,")):
        text = text.replace(f"value = {old}", f"value = {new}")
    text = text.replace('distribution = "normal"', 'distribution = "normal"\nbuilds = 400\n'
                        'confirm = 10')
    spec = tmp_path / "stairs.toml"
    spec.write_text(text)
    result = CliRunner().invoke(main, ["yield", str(spec), "--format", "json", "--out",
                                       str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert (doc["yield"]["builds"], doc["yield"]["stages"]) == (400, 60)
    assert doc["survival"][-1] == doc["yield"]["estimate"] < 1.0
    assert doc["confirmed"]["random"] == 10 == doc["confirmed"]["agreed"]
    assert {s["quantity"] for s in doc["sensitivity"]} == {"rise", "tread", "restitution",
                                                           "launch_speed"}
    assert set(doc["failures"]) <= set(FAILURES)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "sensitivity.png", "survival.png", "yield.json", "yield_scale.png"]
    for build in doc["failing_builds"][:2]:
        run = CliRunner().invoke(main, ["simulate", *build["command"].split()[2:],
                                        "--format", "json"])
        assert run.exit_code == 1, run.output
        outcome = json.loads(run.stdout)["outcome"]
        assert (outcome["stages_passed"], outcome["failure"]["event"]) == (
            build["stages_passed"], build["failure"])


def test_a_friction_tolerance_on_a_point_ball_is_refused_at_its_key(tmp_path):
    from pathlib import Path

    from click.testing import CliRunner

    from pdm_design.cli import main

    text = (Path(__file__).resolve().parents[1] / "problems" / "stairs_yield.toml").read_text()
    text = text.replace("radius = 0.05 ", "radius = 0.0 ").replace(
        "[tolerances]\n", "[tolerances]\nfriction = { value = 0.01, applies_to = \"lot\" }\n")
    spec = tmp_path / "point.toml"
    spec.write_text(text)
    result = CliRunner().invoke(main, ["yield", str(spec)])
    assert result.exit_code == 2
    assert f"{spec}: tolerances.friction: expected no friction tolerance" in result.stderr


def test_too_many_parts_for_the_sobol_sample_say_so_in_words():
    # 2 quantities of each of 6000 steps: 12 000 variables, beyond the Sobol' sequence's
    # 21 201 dimensions of Saltelli's two matrices
    from pdm_design.tolerances import Tolerance, Tolerances
    from pdm_design.tolerances.yield_ import yield_of

    tols = Tolerances((Tolerance("rise", "each", 1e-6), Tolerance("tread", "each", 1e-6)))
    r = yield_of(scene_of(), ROBUST, tols, builds=4, stages=6000, confirm=0, scales=())
    assert r.sensitivity == () and "12000 varying parts" in r.sensitivity_note
