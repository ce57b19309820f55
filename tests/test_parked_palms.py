"""Palms parked at their front stops behind the carrying one: the closed-form clearance
(physics.manipulators.parked_palm_clearance) against a dense scan of the contact box, the
simulator's palms that come to rest during a carry, and the NLP's deferred rows."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from pdm_design.analysis import analyse
from pdm_design.api import design
from pdm_design.formulation import formulate
from pdm_design.scenes.manipulators.physics import parked_palm_clearance, pitch
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.solve import optimize
from pdm_design.spec import load_spec, parse_spec
from pdm_design.status import Status

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def _touches(n, *, alpha, theta_end, l, f, px, py, o, reach, depth, dx=0.0, dy=0.0,
             samples=20001):
    """Whether the object's base centre, carried from -alpha to theta_end at offset o, is ever
    inside the contact box of the palm n places back parked at f (its pivot moved by dx, dy
    relative to the carrying one): a scan of the arc, no interval algebra."""
    th = np.linspace(-alpha, theta_end, samples)
    gap_x = l * np.sin(th) + o - (l * math.sin(f) - n * px + dx)
    gap_y = l * np.cos(th) - (l * math.cos(f) + n * py + dy)
    return bool(np.any((np.abs(gap_x) < reach) & (gap_y > -depth) & (gap_y < 0.0)))


def _random_geometry(rng):
    l = rng.uniform(0.5, 3.0)
    alpha = rng.uniform(0.0, 0.5)
    beta = rng.uniform(alpha + 0.02, 1.0)
    px, py = pitch(alpha, beta, l)
    return dict(alpha=alpha, theta_end=beta, l=l, f=rng.uniform(beta, math.pi / 2), px=px,
                py=py, o=rng.uniform(-0.5, 0.5) * l, reach=rng.uniform(0.05, 2.0) * l,
                depth=rng.uniform(0.01, 0.5) * l)


def _clearance(n, g, *, o_lo=None, o_hi=None, shift=0.0):
    return parked_palm_clearance(
        n, alpha=g["alpha"], theta_end=g["theta_end"], link_length=g["l"], front_stop=g["f"],
        pitch_x=g["px"], pitch_y=g["py"], offset_lo=g["o"] if o_lo is None else o_lo,
        offset_hi=g["o"] if o_hi is None else o_hi, reach=g["reach"], depth=g["depth"],
        shift=shift)


def test_the_clearance_is_exact_against_a_scan_of_the_arc():
    rng = np.random.default_rng(11)
    signs = {True: 0, False: 0}
    for _ in range(1500):
        g = _random_geometry(rng)
        n = int(rng.integers(1, 5))
        c = _clearance(n, g) / g["l"]
        if abs(c) < 1e-3:  # a tangency: the scan's spacing decides it
            continue
        touches = _touches(n, **g)
        assert touches == (c < 0), (g, n, c)
        signs[touches] += 1
    assert min(signs.values()) > 150  # both outcomes are well represented


def test_the_robust_clearance_holds_for_every_offset_in_its_ranges():
    """Sound: with the offset's range, the pivots' relative move (shift) and a carry that may
    end earlier, a positive clearance means no realisation touches."""
    rng = np.random.default_rng(12)
    checked = 0
    for _ in range(1500):
        g = _random_geometry(rng)
        n = int(rng.integers(1, 5))
        spread, shift = rng.uniform(0, 0.2) * g["l"], rng.uniform(0, 0.05) * g["l"]
        o_lo, o_hi = g["o"] - spread, g["o"] + spread
        if _clearance(n, g, o_lo=o_lo, o_hi=o_hi, shift=shift) <= 0.0:
            continue
        checked += 1
        for _ in range(5):
            real = dict(g, o=rng.uniform(o_lo, o_hi),
                        theta_end=rng.uniform(-g["alpha"], g["theta_end"]))
            d = rng.uniform(-shift, shift, size=2)
            assert not _touches(n, **real, dx=d[0], dy=d[1], samples=4001)
    assert checked > 300


# Palms 0.79 m wide on a 0.33 m pitch, front stop 0.0143 rad past beta: palm 1 reaches its stop
# 5.5 ms after handing over, and the object on palm 2 then comes down onto its top.
PARKED_SOON = """
[scene]
kind = "manipulators"
[scene.body]
mass = 0.0968
width = 0.1126
height = 0.0211
[scene.palm]
width = 0.7888
thickness = 0.0039
friction = 0.926
front_stop = 0.41358
[initial]
position = [-0.41613, 0.57923]
velocity = [1.49547, 0.0]
[design]
alpha = 0.1819
beta = 0.3993
link_length = 0.586666
mass_ratio = 6.377
[verification]
stages = 6
"""


def test_a_palm_coming_to_rest_during_a_carry_is_met_where_its_top_is():
    """Palm 1 is released at the handover and parks while palm 2 carries the object: the
    object lands on its top where l cos th = pitch_y + l cos f (the arc descends through the
    parked top), not on palm 3. Before palms arriving mid-carry were obstacles, the simulator
    let it pass through palm 1."""
    spec = parse_spec(tomllib.loads(PARKED_SOON))
    d = spec.design_at()
    l, f = d.link_length, spec.scene.palm.front_stop
    result = simulate_manipulators(spec.scene, d, stages=6)
    handovers = [e for e in result.events if e.kind == "handover"]
    assert handovers[1].detail == "palm 2 -> palm 1"
    assert result.events.index(handovers[1]) > next(
        i for i, e in enumerate(result.events) if e.kind == "front_stop" and e.stage == 1)
    _, pitch_y = pitch(d.alpha, d.beta, l)
    expected = math.acos((pitch_y + l * math.cos(f)) / l)
    assert result.stages[1]["handover_angle"] == pytest.approx(expected, abs=1e-9)
    assert not result.outcome.completed
    # the closed forms see it too: the design is refused, with the simulator's verdict beside
    analysis = analyse(spec.scene, d, 6)
    assert analysis.margins["parked_palms"] < 0
    outcome = design(spec)
    assert outcome.status is Status.INFEASIBLE
    assert not outcome.verification["passed"]


def _meets_a_parked_palm(result):
    """The object handed over to a palm behind its carrier (stage k carries on palm k), or
    blocked."""
    return any(e.kind == "handover" and int(e.detail.split()[-1]) <= e.stage
               or e.kind == "blocked" for e in result.events)


def test_the_analysis_margin_agrees_with_the_simulator_on_parked_palms():
    """Fixed designs around PARKED_SOON, front stop swept: where the palm parks long before the
    object passes, the margin's sign says whether the simulated run meets a parked palm."""
    base = tomllib.loads(PARKED_SOON)
    agree = {True: 0, False: 0}
    for stop in np.linspace(0.45, 1.5, 22):
        base["scene"]["palm"]["front_stop"] = float(stop)
        spec = parse_spec(base)
        d = spec.design_at()
        margin = analyse(spec.scene, d, 6).margins["parked_palms"]
        if abs(margin) < 1e-3:
            continue
        met = _meets_a_parked_palm(simulate_manipulators(spec.scene, d, stages=6))
        assert met == (margin < 0), (stop, margin)
        agree[met] += 1
    assert min(agree.values()) >= 3


def _random_row(rng):
    """A fixed design with palms up to four pitches wide and a front stop anywhere from just
    past beta to pi/2, its first landing near palm 1's centre."""
    l, a = rng.uniform(0.5, 3.0), rng.uniform(0.0, 0.3)
    b = rng.uniform(a + 0.1, 0.9)
    W = l * (math.sin(a) + math.sin(b)) * rng.uniform(0.5, 4.0)
    stop = rng.uniform(b + 0.005, b + 0.3) if rng.random() < 0.5 else rng.uniform(b, math.pi / 2)
    return parse_spec({
        "scene": {"kind": "manipulators",
                  "body": {"mass": 1.0, "width": rng.uniform(0.05, 0.3) * W,
                           "height": rng.uniform(0.02, 0.3) * l},
                  "palm": {"width": W, "thickness": 0.02 * l, "friction": 1.5,
                           "front_stop": max(stop, b + 0.005)}},
        "initial": {"position": [-l * math.sin(a) + rng.uniform(-0.1, 0.1) * W - 0.3 * l,
                                 1.3 * l * math.cos(a)],
                    "velocity": [math.sqrt(9.81 * l) * rng.uniform(0.3, 0.8), 0.0]},
        "design": {"alpha": a, "beta": b, "link_length": l, "mass_ratio": rng.uniform(2, 20)},
        "verification": {"stages": 8}})


def test_the_analysis_margin_says_whether_a_random_row_meets_a_parked_palm():
    """Random fixed designs whose other margins all hold: the run completes iff parked_palms
    >= 0, and otherwise comes down on (or hits) a palm behind the carrying one. (The margin
    takes the palm just released as parked from the handover on; no case here needed the
    timing.)"""
    rng = np.random.default_rng(21)
    seen = {True: 0, False: 0}
    for _ in range(300):
        spec = _random_row(rng)
        d = spec.design_at()
        analysis = analyse(spec.scene, d, 8)
        margin = analysis.margins["parked_palms"]
        others = [v for k, v in analysis.margins.items() if k != "parked_palms"]
        if analysis.problems or min(others) < 0.02 or abs(margin) < 1e-3:
            continue
        result = simulate_manipulators(spec.scene, d, stages=8)
        met = _meets_a_parked_palm(result)
        assert met == (margin < 0) and result.outcome.completed == (margin >= 0), margin
        seen[met] += 1
    assert min(seen.values()) >= 30


def test_parked_rows_are_deferred_and_added_when_the_answer_breaks_them():
    spec = load_spec(PROBLEMS / "manipulators_robust.toml")
    core, full = formulate(spec), formulate(spec, full=True)
    assert core.deferred is not None and len(core.deferred_conditions) == 5  # 5 palms back
    assert full.nlp["g"].shape[0] == core.nlp["g"].shape[0] + 5
    assert {c.name for c in full.conditions} - {c.name for c in core.conditions} == {
        "parked_palms"}
    # the shipped problem: its answer keeps clear without them, and says so
    result = optimize(spec)
    assert result.solution.key == core.key
    parked = [v for k, v in result.robust_margins.items() if k.startswith("parked_palms")]
    assert len(parked) == 5 and min(parked) > 0.1
    # a row of wide palms with an early stop: the answer without them breaks them
    text = tomllib.loads((PROBLEMS / "manipulators_robust.toml").read_text())
    text["scene"]["palm"]["width"] = 3.2
    text["scene"]["palm"]["front_stop"] = 0.7
    wide = parse_spec(text)
    without = formulate(wide)
    result = optimize(wide)
    assert result.status is Status.OPTIMAL
    assert result.solution.key == formulate(wide, full=True).key != without.key
    assert min(v for k, v in result.robust_margins.items()
               if k.startswith("parked_palms")) >= 0
    # a warm start from that answer solves the NLP it came from, rows and all
    warm = optimize(wide, starts=1, warm_start=result, linearise=False)
    assert warm.solution.key == result.solution.key
    assert warm.stats.return_statuses[0] == "Solve_Succeeded"
    assert warm.objective == pytest.approx(result.objective, abs=1e-8)
