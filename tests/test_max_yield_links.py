"""The linearised yield on the device as built (formulation/manipulators/statistical.py: every
stage map with the real-link carry's closed forms, q_e at the landings, g_e and the pivot
friction in the carry, the palm's force with its tangential part, the carry's rows inside it
too) against the Monte Carlo of `pdm-design yield` (the yield map and the event simulator):
tolerances sized for a yield target at a fixed design pass the target at the interval's lower
end, and the linearised yield lies about the Monte Carlo interval; max_yield's answer likewise.
What the linearisation does not model is refused in words."""

import tomllib
from pathlib import Path

import pytest

from pdm_design.errors import SpecError
from pdm_design.scenes.manipulators.formulation import statistical
from pdm_design.scenes.manipulators.model import ManipulatorsDesign
from pdm_design.solve.yield_allocation import allocate_for_yield
from pdm_design.spec.loader import parse_spec
from pdm_design.tolerances.yield_ import yield_of

ROOT = Path(__file__).resolve().parents[1]
# a benchmark spec, not a shipped problem: its check simulates every one of its 5000 builds
SPEC = (ROOT / "results" / "specs" / "manipulators_real_links_yield_target.toml").read_text()


def _spec(text):
    return parse_spec(tomllib.loads(text))


def _fixed(alpha, beta):
    text = SPEC.replace("alpha = { min = 0.0, max = 0.6, initial = 0.1252 }", f"alpha = {alpha}")
    return text.replace("beta = { min = 0.2, max = 1.2, initial = 0.4516 }", f"beta = {beta}")


def test_plain_rows_where_the_device_is_plain_and_the_carry_inside_on_real_links():
    plain = _spec(SPEC.replace("[scene.links]\nmass = 0.5", "[scene.links]\nmass = 0.0")
                  .replace("friction_torque = 0.2", "friction_torque = 0.0"))
    built = _spec(SPEC)
    n_plain = len(statistical.Chain(plain.scene).middle[1])
    n_built = len(statistical.Chain(built.scene).middle[1])
    # the carry's lift-off, 4 tips and 2 slips at INSIDE angles between its ends
    assert n_built == n_plain + 7 * statistical.INSIDE


def test_link_mass_and_pivot_friction_tolerances_and_damping_are_refused_in_words():
    from pdm_design.scenes.manipulators.formulation import yield_target

    spec = _spec(SPEC.replace("friction = { value = 0.1, applies_to = \"lot\" }",
                              "link_mass = { value = 0.01, applies_to = \"each\" }"))
    with pytest.raises(SpecError, match="tolerances.link_mass.value"):
        yield_target.check(spec)
    damped = _spec(SPEC.replace("friction_torque = 0.2", "friction_torque = 0.2\ndamping = 0.1"))
    with pytest.raises(SpecError, match="undamped pivots"):
        yield_target.check(damped)


@pytest.mark.slow
def test_a_yield_target_sized_on_real_links_passes_the_monte_carlo():
    # the design `optimize` chooses for this spec (alpha 0.0766, beta 0.5155): its pivots
    # sized alone for 99.73 %, then 5 000 builds of the map and the simulator
    spec = _spec(_fixed(0.0766, 0.5155))
    design = ManipulatorsDesign(**spec.design)
    stages = spec.verification.stages
    found = allocate_for_yield(spec.scene, design, spec.tolerances, stages=stages)
    assert found.linearised["yield"] == pytest.approx(0.9973, abs=1e-6)
    assert 0.10 < found.scale < 0.20  # m: the pivots' half-width
    run = yield_of(spec.scene, design, found.tolerances, builds=5000, stages=stages, seed=0,
                   scales=(), sensitivity_samples=0)
    assert run.ci_low >= 0.9973
    # the union bound counts rows that fail together apiece: at or a little below the truth
    assert run.ci_low - 0.002 <= found.linearised["yield"] <= run.ci_high
