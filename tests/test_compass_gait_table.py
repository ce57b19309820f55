"""`pdm-design table` of a fixed compass gait over its slope: the gait continued point to point,
and where a multiplier leaves the unit circle, in bifurcations.json."""

import json
from pathlib import Path

import pytest

from pdm_design.cli import main
from pdm_design.scenes.compass_gait.gait import fixed_point
from pdm_design.spec import load_spec

SPEC = Path(__file__).resolve().parents[1] / "problems" / "compass_gait_ramp.toml"


def _multipliers(spec, slope, guess):
    gait = fixed_point(spec.scene, spec.design_at({}).__class__(slope=slope), guess)
    return [complex(re, im) for re, im in gait["multipliers"]], gait["fixed_point"]


def test_a_slope_table_reports_the_period_doubling_where_a_multiplier_passes_minus_1(tmp_path):
    from click.testing import CliRunner

    out = CliRunner().invoke(main, ["table", str(SPEC), "--sweep", "slope=0.06:0.09:31",
                                    "--out", str(tmp_path / "t"), "--no-plots"])
    assert out.exit_code == 0, out.output
    found = json.loads((tmp_path / "t" / "bifurcations.json").read_text())
    doubling = [b for b in found["bifurcations"] if b["kind"] == "period_doubling"]
    assert len(doubling) == 1 and doubling[0]["parameter"] == "slope"
    value = doubling[0]["value"]
    spec = load_spec(SPEC)
    # the exact multipliers on either side, 2e-5 rad away (the refinement is to 1e-5)
    before, start = _multipliers(spec, value - 2e-5, None)
    after, _ = _multipliers(spec, value + 2e-5, start)
    assert max(abs(m) for m in before) < 1.0
    assert any(abs(m.imag) < 1e-9 and m.real < -1.0 for m in after)
    assert value == pytest.approx(0.07664, abs=5e-4)  # 4.39 degrees


def test_another_sweep_adds_no_bifurcations(tmp_path):
    from click.testing import CliRunner

    out = CliRunner().invoke(main, ["table", str(SPEC), "--sweep", "friction=0.8:1.0:3",
                                    "--out", str(tmp_path / "t"), "--no-plots"])
    assert out.exit_code == 0, out.output
    assert (tmp_path / "t" / "table.csv").exists()
    assert not (tmp_path / "t" / "bifurcations.json").exists()


def test_a_fixed_walker_above_its_max_spectral_radius_is_infeasible_in_words(tmp_path):
    """The classic walker's gait at 3 degrees has spectral radius 0.58 (its AD multipliers, held
    against the simulator's finite differences in test_compass_gait_multipliers.py)."""
    from pdm_design.api import evaluate
    from pdm_design.spec.loader import parse_spec, read_spec_data

    radius = fixed_point(load_spec(SPEC).scene, load_spec(SPEC).design_at(), None)[
        "spectral_radius"]
    for bound, feasible in ((radius + 0.01, True), (radius - 0.01, False)):
        data = read_spec_data(SPEC)
        data["requirements"] = {"max_spectral_radius": bound}
        outcome = evaluate(parse_spec(data, str(SPEC)), verify=False)
        assert outcome.status.is_success is feasible
        assert any("spectral radius" in v for v in outcome.violations) is not feasible
