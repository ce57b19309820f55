"""A slip before the handover followed by the builds' map (scenes/manipulators/tolerances.py,
slide_to_handover): on the paper's device a carry whose angle passes atan(mu) before the
handover slides there to the handover. The map integrates that slide in the angle (fourth-order
Runge-Kutta, physics.slide_accelerations) where the event simulator integrates it in time
(DOP853 with event location): two methods, whose handover states and verdicts must agree."""

from pathlib import Path

import numpy as np
import pytest

from pdm_design.accuracy import accuracy as resolve
from pdm_design.commands.yield_ import spec_tolerances
from pdm_design.scenes.manipulators import physics as phys
from pdm_design.scenes.manipulators import tolerances as builds_map
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.spec.loader import load_spec
from pdm_design.tolerances.draw import draw
from pdm_design.tolerances.yield_ import simulated

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
STAGES = 12


def _spec(tmp_path, friction, tolerances):
    """The yield target problem's row at a fixed design whose handover angle (beta 0.664,
    tan 0.783) lies past atan(mu) for a friction below 0.78: the object slides before each
    handover."""
    text = (PROBLEMS / "manipulators_yield_target.toml").read_text()
    text = text.replace("alpha = { min = 0.0, max = 0.6, initial = 0.0613 }", "alpha = 0.2173")
    text = text.replace("beta = { min = 0.2, max = 1.2, initial = 0.4928 }", "beta = 0.6639")
    text = text.replace("friction = 0.8 ", f"friction = {friction} ").replace(
        "stages = 20", f"stages = {STAGES}")
    head, _, _ = text.partition("[tolerances]")
    path = tmp_path / "slide.toml"
    path.write_text(head + ("[tolerances]\nbuilds = 200\nseed = 0\n" + tolerances
                            if tolerances else ""))
    return load_spec(path)


def _mapped_handovers(spec, deviations):
    """The map's outcome and, stage by stage, the slipping builds' (vx, vy, offset) at the
    handover as slide_to_handover returns them."""
    seen = []
    original = builds_map._Builds.slide_to_handover

    def spy(self, k, slips, *args):
        out = original(self, k, slips, *args)
        seen.append((k, slips.copy(), *(np.array(o, float) for o in out)))
        return out

    builds_map._Builds.slide_to_handover = spy
    try:
        outcome = builds_map.run_builds(spec.scene, spec.design_at(), deviations, STAGES)
    finally:
        builds_map._Builds.slide_to_handover = original
    return outcome, seen


def test_the_slide_to_each_handover_is_the_simulators(tmp_path):
    # friction 0.6: atan = 0.540 < the handover angle, every carry slides (about 4 mm back
    # along its palm), and the nominal row completes; the map follows each slide
    spec = _spec(tmp_path, 0.6, "")
    outcome, seen = _mapped_handovers(spec, {"pivot_x": np.zeros((1, STAGES))})
    assert outcome.closed_form[0] and outcome.failure[0] == ""
    assert [k for k, slips, *_ in seen if slips[0]] == list(range(STAGES))  # the last to beta
    design = spec.design_at()
    run = simulate_manipulators(spec.scene, design, stages=STAGES, accuracy=resolve("precise"))
    assert run.outcome.completed
    # the next landing offset = the offset slid to + l sin(beta) - (pitch_x - l sin(alpha))
    # (the nominal row's handover geometry, the same at every stage)
    pitch_x = float(phys.pitch(design.alpha, design.beta, design.link_length)[0])
    ahead = design.link_length * (np.sin(design.beta) + np.sin(design.alpha)) - pitch_x
    for k, _, vx, vy, offset in seen[:-1]:
        rec = run.stages[k]
        assert rec["slipped"]
        # the handover velocity (the palm's swing plus the slide) to 1e-7 m/s
        assert vx[0] == pytest.approx(rec["handover_vx"], abs=1e-7)
        assert vy[0] == pytest.approx(rec["handover_vy"], abs=1e-7)
        # the slide took the object back along the palm, and it lands where the simulator's does
        assert offset[0] < rec["landing_offset"] - 3e-3
        assert offset[0] + ahead == pytest.approx(run.stages[k + 1]["landing_offset"], abs=1e-7)


def test_slipping_builds_stay_in_the_map_with_the_simulators_verdict(tmp_path):
    # pivots +-60 mm each, friction 0.8 +-0.01 (one lot): most builds slide somewhere
    spec = _spec(tmp_path, 0.8, 'pivot_x = { value = 0.06, applies_to = "each" }\n'
                 'pivot_y = { value = 0.06, applies_to = "each" }\n'
                 'friction = { value = 0.01, applies_to = "lot" }\n')
    tolerances = spec_tolerances(spec, "slide.toml")
    deviations = draw(tolerances, 200, STAGES, 0, scene=spec.scene)
    outcome, seen = _mapped_handovers(spec, deviations)
    slid = np.zeros(200, bool)
    for _, slips, *_ in seen:
        slid |= slips
    assert slid.sum() >= 60, slid.sum()
    kept = np.flatnonzero(slid & outcome.closed_form)
    assert len(kept) >= 0.9 * slid.sum()
    accuracy = resolve("default")
    for i in kept[:25]:
        verdict = simulated(spec.scene, spec.design_at(), tolerances, 0, int(i), STAGES, accuracy)
        assert verdict == (int(outcome.stages_passed[i]), outcome.failure[i]), i
