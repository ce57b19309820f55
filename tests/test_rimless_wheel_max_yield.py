"""objective.max_yield and tolerances.yield_target in the rimless wheel's NLP on a ramp
(nlp_yield.py): the NLP's nines at its answer against the numpy linearised yield
(statistical.py, central differences), the answer against its neighbours on that yield, and the
Monte Carlo of the `yield` command (the event builds) as the judge."""

import math

import numpy as np
import pytest

from pdm_design import api
from pdm_design.commands.yield_ import run_yield
from pdm_design.errors import SpecError
from pdm_design.scenes.rimless_wheel import RimlessWheelDesign
from pdm_design.scenes.rimless_wheel.statistical import linearised_yield
from pdm_design.spec.loader import load_spec
from pdm_design.tolerance_model import Tolerance

SPEC = """
[scene]
kind = "rimless_wheel"
ground = "{ground}"
[initial]
speed = 1.1
[design]
spokes = 8
leg_length = {leg}
{design}
{objective}
[tolerances]
{tolerances}
start_speed = {{ value = {start} }}
[verification]
stages = 20
"""
FREE = "slope = { min = 0.02, max = 0.3, initial = 0.08 }"
GIVEN = 'slope = { value = 0.03, applies_to = "each" }'
TOLERANCES = [Tolerance("slope", value=0.03, applies_to="each"),
              Tolerance("start_speed", value=0.1)]


def spec_of(tmp_path, name, design=FREE, objective="[objective]\nmax_yield = 1.0",
            tolerances=GIVEN, ground="ramp", start=0.1, leg="1.0"):
    path = tmp_path / f"{name}.toml"
    path.write_text(SPEC.format(ground=ground, design=design, objective=objective,
                                tolerances=tolerances, start=start, leg=leg))
    return load_spec(path), str(path)


def numpy_nines(spec, slope):
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=slope)
    return -math.log10(linearised_yield(spec.scene, design, TOLERANCES, 20)["failure_bound"])


@pytest.fixture(scope="module")
def answer(tmp_path_factory):
    spec, _ = spec_of(tmp_path_factory.mktemp("max_yield"), "max_yield")
    return spec, api.optimize(spec, verify=False)


def test_nines_at_the_answer_equal_the_numpy_linearised_yield(answer):
    """The NLP's term (exact CasADi derivatives) against statistical.py's central
    differences of the same rows at the answer's slope."""
    spec, out = answer
    assert out.status.is_success
    slope = out.analysis.design["slope"]
    assert out.objective["terms"]["max_yield"] == pytest.approx(numpy_nines(spec, slope),
                                                                rel=1e-6)


def test_the_answer_is_a_maximum_of_the_numpy_linearised_yield(answer):
    """Inside the slope's bounds, and the numpy yield is lower a little either side."""
    spec, out = answer
    slope = out.analysis.design["slope"]
    assert 0.03 < slope < 0.29
    best = numpy_nines(spec, slope)
    for step in (-0.01, 0.01):
        assert numpy_nines(spec, slope + step) < best


def test_the_monte_carlo_yield_of_the_answer_beats_the_starting_design(answer, tmp_path):
    """The `yield` command's builds (same seed) of the spec's start (slope 0.08) and of the
    answer: 72.6 % against 100 % at 20 000 builds; here 4 000."""
    _, out = answer
    yields = []
    for name, slope in (("start", 0.08), ("answer", out.analysis.design["slope"])):
        spec, path = spec_of(tmp_path, name, design=f"slope = {slope!r}", objective="")
        result = run_yield(spec, path, builds=4000, seed=3)
        yields.append(result)
    start, best = yields
    assert best.estimate >= start.estimate
    assert best.ci_low > start.ci_high  # clearly better, not by chance


def test_a_yield_target_is_met_by_monte_carlo(tmp_path):
    """The largest slope tolerance at which the NLP's linearised yield is 99 % (the numpy
    linearised yield agrees at the answer), judged by the Monte Carlo's 95 % lower end."""
    spec, _ = spec_of(tmp_path, "target", objective="",
                      tolerances='yield_target = 0.99\nslope = { allocate = true, '
                                 'applies_to = "each" }')
    out = api.optimize(spec, verify=False)
    assert out.status.is_success
    checked = out.tolerances_yield
    assert checked["met"] and checked["ci_low"] >= 0.99
    sized = next(t["value"] for t in out.tolerances if t["quantity"] == "slope")
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=out.analysis.design["slope"])
    tolerances = [Tolerance("slope", value=sized, applies_to="each"),
                  Tolerance("start_speed", value=0.1)]
    assert linearised_yield(spec.scene, design, tolerances, 20)["yield"] == pytest.approx(
        0.99, abs=1e-6)


def test_what_is_not_linearised_is_refused_naming_the_key(tmp_path):
    spec, _ = spec_of(tmp_path, "leg", tolerances='leg_length = { value = 0.01, '
                                                  'distribution = "uniform" }')
    with pytest.raises(SpecError, match="tolerances.*leg_length.*uniform"):
        api.optimize(spec, verify=False)


def test_an_unreachable_target_is_said_in_words(tmp_path):
    """A start speed of +-1 rad/s stalls or slips too many wheels for 99.99 % at any slope and
    any slope tolerance: the answer is infeasible and names the yield target's row."""
    spec, _ = spec_of(tmp_path, "hard", objective="", start=1.0,
                      tolerances='yield_target = 0.9999\nslope = { allocate = true, '
                                 'applies_to = "each" }')
    for slope in np.linspace(0.02, 0.3, 57):  # statistical.py: no slope reaches it at s -> 0
        design = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=float(slope))
        tolerances = [Tolerance("slope", value=1e-9, applies_to="each"),
                      Tolerance("start_speed", value=1.0)]
        assert linearised_yield(spec.scene, design, tolerances, 20)["yield"] < 0.9999
    out = api.optimize(spec, verify=False)
    assert not out.status.is_success
    assert any("yield target" in v for v in out.violations)


@pytest.mark.parametrize("applies_to", ["each", "lot"])
def test_the_chained_spreads_equal_central_differences_over_many_steps(tmp_path, applies_to):
    """nlp_yield.row_moments (one stance differentiated, chained through the step map) against
    statistical.row_reliability (every build perturbed, central differences) at 60 steps, the
    leg and slope symbols of the NLP set to 0.8 m and 0.12 rad; every step's own slope error,
    or one for every step of a build (a lot)."""
    import casadi as ca

    from pdm_design.scenes.rimless_wheel.formulation import build
    from pdm_design.scenes.rimless_wheel.nlp_yield import Spread, row_moments
    from pdm_design.scenes.rimless_wheel.statistical import row_reliability

    spec, _ = spec_of(tmp_path, "rows", leg="{ min = 0.5, max = 1.5 }")
    _, _, m = build(spec)
    lot = applies_to == "lot"
    g, sd = row_moments(m, 60, Spread([0.0 if lot else 0.01], [0.01 if lot else 0.0], 0.1 / 3))
    f = ca.Function("f", [m.values["leg_length"], m.values["slope"]], [g, sd])
    g, sd = (x.full().ravel() for x in f(0.8, 0.12))
    design = RimlessWheelDesign(spokes=8, leg_length=0.8, slope=0.12)
    tolerances = [Tolerance("slope", value=0.03, applies_to=applies_to),
                  Tolerance("start_speed", value=0.1)]
    g_ref, sd_ref, _, _ = row_reliability(spec.scene, design, tolerances, 60)
    assert np.allclose(g, g_ref, rtol=0, atol=1e-12)
    assert np.allclose(sd, sd_ref, rtol=1e-6, atol=1e-9)
