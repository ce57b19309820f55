"""objective.max_yield and tolerances.yield_target in the rimless wheel's NLP on stairs
(nlp_yield.py: the footholds' drift chained through the step map): the chained spreads against
central differences (statistical.py's, and a step map written out here), a lot of treads
against its exact thresholds, the NLP's nines against Monte Carlo of the step map, the
max_yield answer against its neighbours and the `yield` command, and a yield target judged by
Monte Carlo."""

import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.special import ndtr

from pdm_design import api
from pdm_design.commands.yield_ import run_yield
from pdm_design.errors import SpecError
from pdm_design.scenes.rimless_wheel import RimlessWheelDesign
from pdm_design.scenes.rimless_wheel import physics as phys
from pdm_design.scenes.rimless_wheel.builds import build_outcome
from pdm_design.scenes.rimless_wheel.formulation import build
from pdm_design.scenes.rimless_wheel.nlp_yield import Spread, row_moments
from pdm_design.scenes.rimless_wheel.statistical import linearised_yield, row_reliability
from pdm_design.spec.loader import load_spec
from pdm_design.tolerance_model import Tolerance

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"
SPEC = """
[scene]
kind = "rimless_wheel"
ground = "{ground}"
friction = 1.0
[scene.wheel]
mass = 1.0
[initial]
speed = 1.3
[design]
spokes = 8
{design}
{objective}
[tolerances]
{tolerances}
[verification]
stages = 20
"""
FREE = """leg_length = { min = 0.5, max = 1.5 }
rise = { min = 0.01, max = 0.3 }
tread = { min = 0.3, max = 1.0 }
landing_offset = { min = 0.0, max = 0.7 }"""
# a drifting design: the tread 0.68 m against the chord's span 0.6843 m
DRIFTING = dict(leg_length=0.9, rise=0.08, tread=0.68, landing_offset=0.35)


def spec_of(tmp_path, name, design=FREE, objective="",
            tolerances="start_speed = { value = 0.1 }", ground="stairs"):
    path = tmp_path / f"{name}.toml"
    path.write_text(SPEC.format(ground=ground, design=design, objective=objective,
                                tolerances=tolerances))
    return load_spec(path), str(path)


def tolerances_of(rise, tread, modes=("each", "each"), start=0.1):
    return [Tolerance("rise", value=rise, applies_to=modes[0]),
            Tolerance("tread", value=tread, applies_to=modes[1]),
            Tolerance("start_speed", value=start)]


def spread_of(tolerances):
    each, lot = [0.0, 0.0], [0.0, 0.0]
    start = 0.0
    for t in tolerances:
        if t.quantity == "start_speed":
            start = t.value / 3
        else:
            (lot if t.applies_to == "lot" else each)[("rise", "tread").index(t.quantity)] = \
                t.value / 3
    return Spread(each, lot, start)


def chained(tmp_path, tolerances, stages, design=DRIFTING):
    """(g, sd) of nlp_yield.row_moments on the NLP's free symbols set to `design`."""
    spec, _ = spec_of(tmp_path, "free")
    _, _, m = build(spec)
    g, sd = row_moments(m, stages, spread_of(tolerances))
    names = ("leg_length", "rise", "tread", "landing_offset")
    f = ca.Function("f", [m.values[n] for n in names], [g, sd])
    return tuple(x.full().ravel() for x in f(*[design[n] for n in names]))


@pytest.mark.parametrize("modes", [("each", "each"), ("each", "lot"), ("lot", "lot"),
                                   ("lot", "each")])
def test_the_chained_spreads_equal_statistical_central_differences(tmp_path, modes):
    """row_moments (one stance differentiated, the state (E, s) chained) against
    statistical.row_reliability (every build perturbed, central differences) over 40 steps of a
    drifting design, each step's own errors and lots."""
    tolerances = tolerances_of(0.02, 0.01, modes)
    g, sd = chained(tmp_path, tolerances, 40)
    design = RimlessWheelDesign(spokes=8, **DRIFTING)
    g_ref, sd_ref, _, _ = row_reliability(spec_of(tmp_path, "s")[0].scene, design, tolerances, 40)
    assert np.allclose(g, g_ref, rtol=0, atol=1e-12)
    assert np.allclose(sd, sd_ref, rtol=1e-6, atol=1e-9)


def hand_rows(design, rises, treads, speed):
    """over_the_top, nose and landing of every step (steps, 3), a loop over the steps: the
    stance map E' = eta^2 (E + rate (1 - cos(beta + alpha))) - rate (1 - cos(beta - alpha))
    and the foothold s_k = s_{k-1} + c cos beta_k - tread_{k-1}, the nose of tread k - 1 lying
    tread_{k-1} - s_{k-1} ahead of foothold k - 1 (docs/rimless_wheel.md, sections 4, 6, 7)."""
    leg, alpha = design["leg_length"], math.pi / 8
    c, rate, eta = 2 * leg * math.sin(alpha), 2 * 9.81 / leg, math.cos(2 * alpha)
    beta_0 = math.asin(design["rise"] / c)
    energy = speed**2 - rate * (1 - math.cos(beta_0 - alpha))
    s, out = design["landing_offset"], []
    tread_before = design["tread"]
    for rise, tread in zip(rises, treads):
        beta = math.asin(rise / c)
        reach = leg * math.sin(2 * alpha) / math.cos(alpha - beta)
        nose = tread_before - s
        s = s + c * math.cos(beta) - tread_before
        out.append((energy / rate, (reach - nose) / design["tread"],
                    (tread - s) / design["tread"]))
        energy = (eta**2 * (energy + rate * (1 - math.cos(beta + alpha)))
                  - rate * (1 - math.cos(beta - alpha)))
        tread_before = tread
    return np.array(out)


def test_the_chained_spreads_equal_central_differences_of_a_step_map_written_out(tmp_path):
    """The over_the_top, nose and landing rows' spreads from the chain against central
    differences of hand_rows (a point mass: k^2 = 0) in every step's rise and tread and the
    start speed, 15 steps of a drifting design."""
    steps, sigma_r, sigma_t, sigma_w, h = 15, 0.02 / 3, 0.01 / 3, 0.1 / 3, 1e-6
    g, sd = chained(tmp_path, tolerances_of(0.02, 0.01), steps)
    width = len(g) // steps
    rises, treads = np.full(steps, DRIFTING["rise"]), np.full(steps, DRIFTING["tread"])
    base = hand_rows(DRIFTING, rises, treads, 1.3)
    variance = np.zeros_like(base)
    for what, sigma in (("rise", sigma_r), ("tread", sigma_t)):
        for k in range(steps):
            moved = []
            for sign in (1, -1):
                r, t = rises.copy(), treads.copy()
                (r if what == "rise" else t)[k] += sign * h
                moved.append(hand_rows(DRIFTING, r, t, 1.3))
            variance += ((moved[0] - moved[1]) / (2 * h) * sigma) ** 2
    moved = [hand_rows(DRIFTING, rises, treads, 1.3 + sign * h) for sign in (1, -1)]
    variance += ((moved[0] - moved[1]) / (2 * h) * sigma_w) ** 2
    for column, index in ((0, 0), (1, width - 2), (2, width - 1)):  # statistical.py's order
        assert np.allclose(g[index::width], base[:, column], rtol=0, atol=1e-9)
        assert np.allclose(sd[index::width], np.sqrt(variance[:, column]), rtol=1e-5)


def test_a_lot_of_treads_against_its_exact_thresholds(tmp_path):
    """A tread lot t alone (every tread but tread 0 off by t, no other error): on matched
    stairs the footholds are s_k = s_0 - (k - 1) t exactly, so step k's landing holds iff
    t > (s_0 - T) / k and its nose iff t < (reach - T + s_0) / (k - 1): each row's reliability
    index (g / sd) is that threshold over sigma, exactly, and the chain's must be it."""
    design = dict(leg_length=1.0, rise=0.1, landing_offset=0.4)
    alpha = math.pi / 8
    c = 2 * math.sin(alpha)
    design["tread"] = math.sqrt(c**2 - 0.1**2)
    reach = math.sin(2 * alpha) / math.cos(alpha - math.asin(0.1 / c))
    sigma = 0.01 / 3
    tolerances = [Tolerance("tread", value=0.01, applies_to="lot")]
    g, sd = chained(tmp_path, tolerances, 20, design)
    width = len(g) // 20
    index = g / np.maximum(sd, 1e-300)
    for k in range(1, 21):
        landing = index[(k - 1) * width + width - 1]
        assert landing == pytest.approx((design["tread"] - 0.4) / k / sigma, rel=1e-9)
        if k > 1:
            nose = index[(k - 1) * width + width - 2]
            assert nose == pytest.approx((reach - design["tread"] + 0.4) / (k - 1) / sigma,
                                         rel=1e-9)


def toml_of(tolerances) -> str:
    """[tolerances] lines of Tolerance objects (the start speed a lot, its only kind)."""
    return "\n".join(f"{t.quantity} = {{ value = {t.value!r}"
                     + ("" if t.quantity == "start_speed" else f", applies_to = \"{t.applies_to}\"")
                     + " }" for t in tolerances)


def nlp_nines(tmp_path, design: dict, tolerances, name="fixed"):
    """The NLP's max_yield term of a fixed design (formulation.build's objective term)."""
    fixed = "\n".join(f"{k} = {v!r}" for k, v in design.items())
    text = toml_of(tolerances)
    spec, _ = spec_of(tmp_path, name, design=fixed, objective="[objective]\nmax_yield = 1.0",
                      tolerances=text)
    model, _, _ = build(spec)
    return float(ca.evalf(model.objective_terms["max_yield"]))


def monte_carlo(tolerances, design, builds=100_000, seed=5):
    """(yield, standard error) of `builds` builds on the step map (builds.build_outcome), each
    tolerance drawn normal (sigma = t / 3), a lot once a build."""
    spec_scene = load_spec(PROBLEMS / "rimless_wheel_stairs_max_yield.toml").scene
    rng = np.random.default_rng(seed)
    passed, batch = 0, 25_000
    for _ in range(builds // batch):
        dev = {t.quantity: rng.normal(0, t.value / 3, batch if t.applies_to == "lot"
                                      or t.quantity == "start_speed" else (batch, 20))
               for t in tolerances}
        passed += int(np.sum(build_outcome(spec_scene, design, dev, 20).stages_passed >= 20))
    mc = passed / builds
    return mc, math.sqrt(mc * (1 - mc) / builds)


def test_the_nlp_yield_against_monte_carlo_every_step_its_own(tmp_path):
    """1 - 10^-nines of the NLP at rise 70 mm (rise and tread +-30 mm a step, start +-0.1
    rad/s: stalls on the low rises) against 100 000 builds on the step map: within 4 standard
    errors and the linearisation's 1e-3 (0.9857 against 0.9847)."""
    design = dict(leg_length=1.0, rise=0.07, landing_offset=0.4)
    tolerances = tolerances_of(0.03, 0.03)
    lin = 1 - 10 ** -nlp_nines(tmp_path, design, tolerances)
    mc, se = monte_carlo(tolerances, RimlessWheelDesign(spokes=8, **design))
    assert 0.95 < mc < 0.995
    assert abs(lin - mc) < 4 * se + 1e-3


def test_the_nlp_yield_against_monte_carlo_with_a_lot_of_treads(tmp_path):
    """A tread lot fails the landing (short treads) or the nose (long ones) on many steps of one
    build at once: the union bound counts that build once a step. The Monte Carlo's failure
    (6.1 %) lies between the largest row's probability (the NLP's rows, 3.6 %) and the union
    bound (22 %)."""
    design = dict(leg_length=1.0, rise=0.1, landing_offset=0.4)
    tolerances = tolerances_of(0.03, 0.03, ("each", "lot"))
    g, sd = chained(tmp_path, tolerances, 20, {**design, "tread": float(
        phys.stairs_advance(0.1, 1.0, math.pi / 8))})
    bound = 10 ** -nlp_nines(tmp_path, design, tolerances)
    assert bound == pytest.approx(float(np.sum(ndtr(-g / sd))), rel=1e-6)
    mc, se = monte_carlo(tolerances, RimlessWheelDesign(spokes=8, **design))
    assert float(np.max(ndtr(-g / sd))) < 1 - mc - 4 * se
    assert 1 - mc + 4 * se < bound


@pytest.fixture(scope="module")
def answer():
    spec = load_spec(PROBLEMS / "rimless_wheel_stairs_max_yield.toml")
    return spec, api.optimize(spec, verify=False)


def numpy_nines(spec, rise, landing_offset):
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=rise,
                                landing_offset=landing_offset)
    found = linearised_yield(spec.scene, design, list(spec.tolerances), 20)
    return -math.log10(found["failure_bound"])


def test_the_max_yield_answer_against_the_numpy_linearised_yield(answer):
    """The NLP's term at its answer equals statistical.py's (central differences) there, and
    statistical.py's nines are lower 5 mm either side in the rise and in the foothold."""
    spec, out = answer
    assert out.status.is_success
    rise, offset = out.analysis.design["rise"], out.analysis.design["landing_offset"]
    best = numpy_nines(spec, rise, offset)
    assert out.objective["terms"]["max_yield"] == pytest.approx(best, rel=1e-6)
    assert 0.02 < rise < 0.29 and 0.01 < offset < 0.69
    for d_rise, d_offset in ((-0.005, 0), (0.005, 0), (0, -0.005), (0, 0.005)):
        assert numpy_nines(spec, rise + d_rise, offset + d_offset) < best


def test_the_monte_carlo_yield_of_the_answer_beats_the_starting_design(answer, tmp_path):
    """The `yield` command's builds (same seed) of the spec's start (rise 65 mm: stalls) and of
    the answer."""
    spec, out = answer
    tolerances = toml_of(spec.tolerances)
    yields = []
    for name, rise, offset in (("start", 0.065, 0.4),
                               ("answer", out.analysis.design["rise"],
                                out.analysis.design["landing_offset"])):
        fixed, path = spec_of(tmp_path, name, tolerances=tolerances,
                              design=f"leg_length = 1.0\nrise = {rise!r}\n"
                                     f"landing_offset = {offset!r}")
        yields.append(run_yield(fixed, path, builds=4000, seed=3))
    start, best = yields
    assert best.ci_low > start.ci_high  # clearly better, not by chance
    assert best.ci_low > 0.99


def test_a_yield_target_is_met_by_monte_carlo():
    """problems/rimless_wheel_stairs_yield_target.toml (every step's rise, a lot of treads,
    allocated for 99 %): the Monte Carlo's 95 % lower end reaches the target, and
    statistical.py's linearised yield at the sized tolerances is the target."""
    spec = load_spec(PROBLEMS / "rimless_wheel_stairs_yield_target.toml")
    out = api.optimize(spec, verify=False)
    assert out.status.is_success
    checked = out.tolerances_yield
    assert checked["met"] and checked["ci_low"] >= 0.99
    sized = {t["quantity"]: t["value"] for t in out.tolerances}
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=out.analysis.design["rise"],
                                landing_offset=out.analysis.design["landing_offset"])
    tolerances = tolerances_of(sized["rise"], sized["tread"], ("each", "lot"))
    assert linearised_yield(spec.scene, design, tolerances, 20)["yield"] == pytest.approx(
        0.99, abs=1e-6)


@pytest.mark.parametrize("tolerances,match", [
    ('leg_length = { value = 0.01, distribution = "uniform" }', "tolerances.*leg_length"),
    ('rise = { value = 0.01, distribution = "uniform" }', "tolerances.*uniform"),
])
def test_what_is_not_linearised_is_refused_naming_the_key(tmp_path, tolerances, match):
    spec, _ = spec_of(tmp_path, "refused", objective="[objective]\nmax_yield = 1.0",
                      design="leg_length = 1.0\nrise = { min = 0.03, max = 0.2 }",
                      tolerances=tolerances)
    with pytest.raises(SpecError, match=match):
        api.optimize(spec, verify=False)
