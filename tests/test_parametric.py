"""A table's one NLP: swept scene numbers as NLP parameters (formulation/parametric.py), a
chain's points continued from the local optima of the point before (solve.optimize's
`continued`), and the tie-break skipped where it cannot move the design (solve/tiebreak.py
`pinned`). Each is checked against the way it replaces: the spec's own NLP, the cold
multistart, the tie-break's own solve."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_scale import flat_data

from pdm_design.formulation import formulate
from pdm_design.formulation.common import spec_key
from pdm_design.solve import optimize
from pdm_design.spec import parse_spec, read_spec_data

ROBUST = Path(__file__).resolve().parents[1] / "problems" / "manipulators_robust.toml"
SWEPT = ("design.mass_ratio", "scene.palm.friction")
tiebreak = sys.modules["pdm_design.solve.tiebreak"]


def point(q: float, mu: float, parametric: bool = True, data=None):
    data = read_spec_data(ROBUST) if data is None else data
    data["design"]["mass_ratio"] = q
    data["scene"]["palm"]["friction"] = mu
    spec = parse_spec(data, "point")
    return replace(spec, nlp_parameters=SWEPT) if parametric else spec


POINTS = [(8.0, 0.7), (9.3, 0.86), (12.0, 0.9), (10.0, 0.8)]


def test_every_point_shares_one_nlp_and_solvers():
    forms = [formulate(point(q, mu)) for q, mu in POINTS]
    assert len({f.key for f in forms}) == 1  # one generic NLP, one set of IPOPT solvers
    assert len({spec_key(point(q, mu)) for q, mu in POINTS}) == len(POINTS)  # own NLPs differ
    # bound to each point's numbers: its parameter vector ends with them
    for form, (q, mu) in zip(forms, POINTS):
        assert form.parameters()[-2:].tolist() == [q, mu]


@pytest.mark.parametrize("q, mu", POINTS)
def test_the_generic_nlp_is_the_points_own(q, mu):
    """At the same x, the rows, objective terms and row normalisers of the bound generic NLP
    equal those of the NLP built with the point's numbers as constants (to rounding)."""
    own, generic = formulate(point(q, mu, parametric=False)), formulate(point(q, mu))
    assert own.conditions == generic.conditions and own.x_names == generic.x_names
    np.testing.assert_allclose(generic.norms, own.norms, rtol=1e-14)
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = own.lbx + rng.uniform(0.2, 0.8, own.lbx.size) * np.minimum(own.ubx - own.lbx, 1.0)
        x = own.start_vector(dict(zip(own.design_names, x)))
        for a, b in zip(own.evaluate(x, own.parameters()),
                        generic.evaluate(x, generic.parameters())):
            np.testing.assert_allclose(np.asarray(b), np.asarray(a), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("q, mu", POINTS)
def test_a_point_solved_on_the_generic_nlp_is_its_own_optimum(q, mu):
    own = optimize(point(q, mu, parametric=False), check_samples=64)
    generic = optimize(point(q, mu), check_samples=64)
    assert own.status is generic.status is own.status.OPTIMAL
    assert generic.tolerance["dx"] == pytest.approx(own.tolerance["dx"], rel=1e-6)
    for name in ("alpha", "beta"):
        assert generic.design[name] == pytest.approx(own.design[name], abs=1e-5)
    assert generic.checks["sampled_offsets"]["passed"]


def test_a_chain_continued_from_its_optima_reaches_the_cold_multistarts_designs():
    continued = ()
    for mu in np.linspace(0.7, 0.9, 6):
        warm = optimize(point(10.5, float(mu)), check_samples=0, continued=continued)
        cold = optimize(point(10.5, float(mu)), check_samples=0)
        if continued:
            assert warm.stats.starts == len(continued)  # no cold start was needed
        assert warm.tolerance["dx"] == pytest.approx(cold.tolerance["dx"], rel=1e-6)
        for name in ("alpha", "beta"):
            assert warm.design[name] == pytest.approx(cold.design[name], abs=1e-5)
        continued = warm.optima
        assert continued and continued[0].key == formulate(point(10.5, float(mu))).key


def test_a_failed_continuation_falls_back_to_the_starts():
    first = optimize(point(9.0, 0.8), check_samples=0)
    broken = tuple(replace(s, x=np.full_like(s.x, np.nan)) for s in first.optima)
    again = optimize(point(9.1, 0.8), check_samples=0, continued=broken)
    cold = optimize(point(9.1, 0.8), check_samples=0)
    assert again.stats.starts == len(broken) + cold.stats.starts
    assert again.design == pytest.approx(cold.design, abs=1e-9)
    # optima of another NLP are not continued from
    other = optimize(point(9.1, 0.8, parametric=False), check_samples=0,
                     continued=first.optima)
    assert other.stats.starts == cold.stats.starts


@pytest.mark.parametrize("q, mu", POINTS)
def test_a_pinned_optimum_is_one_the_tie_break_would_not_move(q, mu, monkeypatch):
    skipped = optimize(point(q, mu), check_samples=0)
    assert skipped.stats.tie_break_iterations == -1 and not skipped.stats.tie_break_kept
    # the tie-break's own solve, run anyway: it moves the design by less than FLAT
    monkeypatch.setattr(tiebreak, "pinned", lambda *args: False)
    solved = optimize(point(q, mu), check_samples=0)
    assert solved.stats.tie_break_iterations > 0 and not solved.stats.tie_break_kept
    assert solved.design == pytest.approx(skipped.design, abs=1e-9)


def test_a_flat_optimum_is_not_pinned():
    spec = parse_spec(flat_data())
    result = optimize(spec, check_samples=0)
    assert result.stats.tie_break_iterations > 0 and result.stats.tie_break_kept


def test_a_table_of_the_generic_nlp_rows_equals_points_solved_alone(tmp_path):
    from pdm_design.api import design
    from pdm_design.sweep.run import run_sweep

    rows = run_sweep(ROBUST, ["mass_ratio=8:12:3", "friction=0.7:0.9:4"], tmp_path,
                     workers=1, plots=False).rows
    assert len(rows) == 12
    for row in rows[::3]:
        alone = design(point(float(row["design.mass_ratio"]),
                             float(row["scene.palm.friction"]), parametric=False))
        assert float(row["tolerance"]) == pytest.approx(alone.tolerance["dx"], rel=1e-6)
        for name in ("alpha", "beta"):
            assert float(row[name]) == pytest.approx(alone.analysis.design[name], abs=1e-5)
        assert row["verified"] == "true"
