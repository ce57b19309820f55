"""The elastic diagnosis in words: a row violated at many flights or palms is one line."""

from __future__ import annotations

from pdm_design.solve.result import Violation
from pdm_design.solve.words import describe, summarise


def violation(name, where, required, achieved):
    return Violation(name=name, where=where, required=required, achieved=achieved,
                     text=describe(name, where, required, achieved))


def test_a_row_at_many_flights_is_one_line_with_its_worst_margin():
    found = [violation("nose_clearance", f"flight {n}, exact comes down: gap while falling",
                       0.5, 0.2 - 0.01 * n) for n in (1, 2, 3, 5, 7, 8)]
    found.append(violation("riser_clearance", "landing 4", 0.7, 0.6))
    lines = summarise(found)
    assert len(lines) == 2
    assert lines[0].startswith("the ball clears the nose of the step it leaves (flights 1-3, 5, "
                               "7-8, exact comes down: gap while falling): needs margin 0.5, "
                               "reaches 0.12 at the least-violation design")
    assert lines[1] == found[-1].text  # alone in its group: as the diagnosis wrote it


def test_other_phases_and_conditions_stay_apart():
    found = [violation("nose_clearance", f"flight {n}, exact {phase}", 0.5, 0.1)
             for phase in ("takes off: gap at take-off", "comes down: gap while falling")
             for n in (1, 2)]
    found += [violation("palm_clearance", f"palm {n}", 0.0, -0.2) for n in (2, 3)]
    lines = summarise(found)
    assert [line.split(":")[0] for line in lines] == [
        "the ball clears the nose of the step it leaves (flights 1-2, exact takes off",
        "the ball clears the nose of the step it leaves (flights 1-2, exact comes down",
        "the next palm stays below the object until the handover (palms 2-3)"]


def test_a_shortfall_too_small_for_three_digits_is_still_shown():
    text = describe("nose_clearance", "flight 1", 0.5, 0.5 - 1.8e-5)
    assert "needs margin 0.5, reaches 0.5 less 1.8e-05 at the least-violation design" in text


def test_the_report_says_which_bounds_the_least_violation_design_sits_on():
    # problems/infeasible_manipulators.toml: friction holds a palm tilted by at most atan(0.3),
    # below the least handover angle beta >= 0.5 allows, so beta sits on that bound.
    from pathlib import Path

    from pdm_design.api import design
    from pdm_design.spec import load_spec

    spec = load_spec(Path(__file__).resolve().parents[1] / "problems/infeasible_manipulators.toml")
    outcome = design(spec, verify=False)
    assert ("at the least-violation design beta at its lower bound 0.5: widening that bound may "
            "help") in outcome.violations
