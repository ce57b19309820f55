"""Verification on real links compares the simulator with the closed forms over the analysis'
own stages: the paper's device's stage map does not extend them (it is another map)."""

from pathlib import Path

from pdm_design.api import evaluate
from pdm_design.spec import load_spec

SPEC = Path(__file__).resolve().parents[1] / "problems" / "manipulators_all_toleranced.toml"


def test_a_row_on_real_links_longer_than_its_approach_agrees_with_its_closed_forms():
    spec = load_spec(SPEC)
    outcome = evaluate(spec)
    approach = outcome.analysis.approach["handover_speeds"]
    assert len(approach) < spec.verification.stages  # the row outlasts the listed approach
    agreement = outcome.verification["agreement"]
    assert agreement["compared"] == len(approach)
    assert agreement["relative_error"] < 1e-7  # two methods: the simulator and the closed form
    assert outcome.verification["passed"]
