"""Multistart points solved together as one stacked NLP (solve/stacked.py): every copy must
reach what its start reaches when solved alone, and a stacked run that fails must leave the
answer to the one-start-at-a-time runs, with its cost still counted."""

from __future__ import annotations

import importlib
import tomllib
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from pdm_design.formulation import formulate
from pdm_design.solve import optimize, stacked
from pdm_design.solve.ipopt import SolverOptions, solve_once, solver_for, start_designs
from pdm_design.spec import load_spec, parse_spec
from pdm_design.status import Status

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def _starts(spec, form, p, count=8):
    names = form.design_names
    guess = {n: spec.design[n].guess for n in names}
    designs = start_designs(names, [spec.design[n].min for n in names],
                            [spec.design[n].max for n in names], guess, count)
    return [form.defined_start(d, guess, p) for d in designs]


@pytest.mark.parametrize("name", ["manipulators_robust", "stairs_design"])
def test_each_stacked_copy_reaches_what_its_start_reaches_alone(name):
    spec = load_spec(PROBLEMS / f"{name}.toml")
    form = formulate(spec)
    p = form.parameters(spec.requirements)
    starts = _starts(spec, form, p)
    together = stacked.solve_stacked(
        stacked.stacked_solver_for(form.key, form.nlp, SolverOptions(), len(starts)),
        starts, p, form.lbx, form.ubx, form.lbg, form.ubg)
    rows = ca.Function("g", [form.nlp["x"], form.nlp["p"]], [form.nlp["g"]])
    for copy, alone in zip(together, _alone(form, p, starts)):
        assert alone.return_status == copy.return_status == "Solve_Succeeded"
        assert copy.f == pytest.approx(alone.f, rel=1e-7)
        # the copy's own rows and bounds hold, to IPOPT's bound relaxation
        g = np.asarray(rows(copy.x, p)).ravel()
        assert np.all(copy.x >= form.lbx - 1e-7) and np.all(copy.x <= form.ubx + 1e-7)
        assert np.all(g >= form.lbg - 1e-7) and np.all(g <= form.ubg + 1e-7)


def _alone(form, p, starts):
    single = solver_for(form.key, form.nlp, SolverOptions())
    return [solve_once(single, x0, p, form.lbx, form.ubx, form.lbg, form.ubg) for x0 in starts]


def test_a_first_solve_runs_its_starts_one_at_a_time():
    # creating the stacked solver costs more than it saves in one solve (docs/optimizer.md)
    text = (PROBLEMS / "manipulators_robust.toml").read_text()
    spec = parse_spec(tomllib.loads(text.replace("initial = 0.2 }", "initial = 0.21 }")))
    assert spec.design["alpha"].initial == 0.21  # a spec no other test has formulated
    first = optimize(spec, linearise=False, check_samples=0)
    again = optimize(spec, linearise=False, check_samples=0)
    assert first.stats.stacked_starts == 0 and again.stats.stacked_starts == 8
    assert first.stats.build_time > 0.0 and again.stats.build_time == 0.0
    assert again.design == pytest.approx(first.design, rel=1e-6, abs=1e-9)


def test_optimize_solves_its_starts_together_and_counts_one_run():
    formulate(load_spec(PROBLEMS / "manipulators_robust.toml"))  # solved before: stacked
    result = optimize(load_spec(PROBLEMS / "manipulators_robust.toml"), linearise=False,
                      check_samples=0)
    stats = result.stats
    assert result.status is Status.OPTIMAL
    assert stats.stacked_starts == stats.starts == 8
    assert stats.return_statuses == ("Solve_Succeeded",) * 8
    # one stacked run; its optimum is pinned (solve/tiebreak.py): no tie-break run
    assert stats.tie_break_iterations == -1 and not stats.tie_break_kept
    assert stats.total_iterations == stats.iterations
    assert stats.total_solve_time == stats.solve_time  # the one run


def test_a_stacked_run_that_fails_leaves_the_answer_to_one_run_per_start(monkeypatch):
    spec = load_spec(PROBLEMS / "manipulators_robust.toml")
    reference = optimize(spec, linearise=False, check_samples=0)
    monkeypatch.setattr(stacked, "MAX_ITER", 3)  # the stacked run needs about 16
    result = optimize(spec, linearise=False, check_samples=0)
    stats = result.stats
    assert result.status is Status.OPTIMAL
    assert stats.stacked_starts == 0
    assert stats.starts == len(stats.return_statuses) == 8
    # the failed stacked run's 3 iterations are counted, besides every start's own
    form = formulate(spec)
    p = form.parameters(spec.requirements)
    alone = _alone(form, p, _starts(spec, form, p))
    assert stats.total_iterations == (3 + sum(run.iterations for run in alone)
                                      + max(stats.tie_break_iterations, 0))
    assert result.objective == pytest.approx(reference.objective, rel=1e-7)


def test_starts_are_split_into_near_equal_groups_of_at_most_max_copies():
    for count in range(1, 70):
        parts = stacked.groups(count)
        sizes = [len(g) for g in parts]
        assert [i for g in parts for i in g] == list(range(count))
        assert max(sizes) <= stacked.MAX_COPIES and max(sizes) - min(sizes) <= 1
        assert len(parts) == -(-count // stacked.MAX_COPIES)


def test_more_starts_than_a_group_holds_take_one_stacked_run_per_group():
    spec = load_spec(PROBLEMS / "manipulators_robust.toml")
    formulate(spec)  # solved before: stacked
    result = optimize(spec, starts=20, linearise=False, check_samples=0)
    stats = result.stats
    assert result.status is Status.OPTIMAL
    assert stats.starts == stats.stacked_starts == 20
    # two groups of 10, each its own run: their iterations add up
    form = formulate(spec)
    p = form.parameters(spec.requirements)
    starts = _starts(spec, form, p, count=20)
    solver = stacked.stacked_solver_for(form.key, form.nlp, SolverOptions(), 10)
    runs = [stacked.solve_stacked(solver, starts[a:a + 10], p, form.lbx, form.ubx, form.lbg,
                                  form.ubg)[0] for a in (0, 10)]
    assert stats.total_iterations == (sum(run.iterations for run in runs)
                                      + max(stats.tie_break_iterations, 0))
    assert stats.iterations in {run.iterations for run in runs}


@pytest.mark.parametrize("name", ["manipulators_robust", "manipulators_robust_all_free"])
def test_optimize_finds_the_same_design_stacked_as_one_start_at_a_time(name, monkeypatch):
    spec = load_spec(PROBLEMS / f"{name}.toml")
    formulate(spec)  # solved before: stacked
    together = optimize(spec, linearise=False, check_samples=0)
    optimize_module = importlib.import_module("pdm_design.solve.optimize")
    monkeypatch.setattr(optimize_module, "groups", lambda n: [range(i, i + 1) for i in range(n)])
    alone = optimize(spec, linearise=False, check_samples=0)
    assert together.stats.stacked_starts == 8 and alone.stats.stacked_starts == 0
    assert together.status is alone.status is Status.OPTIMAL
    assert together.objective == pytest.approx(alone.objective, rel=1e-8)
    for key, value in alone.design.items():
        assert together.design[key] == pytest.approx(value, rel=1e-5, abs=1e-8)


def test_stairs_starts_are_solved_one_at_a_time_with_every_run_counted():
    # Stacking gains nothing on stairs (Formulation.stack_starts): no stacked run is made.
    spec = load_spec(PROBLEMS / "stairs_design.toml")  # without the tie-break's run
    result = optimize(spec, linearise=False, check_samples=0, tie_break=False)
    stats = result.stats
    assert result.status is Status.OPTIMAL and stats.stacked_starts == 0
    form = formulate(spec)
    p = form.parameters(spec.requirements)
    alone = _alone(form, p, _starts(spec, form, p))
    assert stats.total_iterations == (sum(run.iterations for run in alone)
                                      + max(stats.tie_break_iterations, 0))
    best = min(alone, key=lambda run: run.f)
    assert result.tolerance["rise"] == pytest.approx(best.x[form.tolerance_index], rel=1e-9)


def test_an_evaluation_error_at_the_start_is_a_solver_error_for_every_copy():
    def refuses(**_):
        raise RuntimeError("Error in Function::call for 'nlp_g'")

    solver = stacked.StackedSolver(refuses, None, count=2, n=3)
    runs = stacked.solve_stacked(solver, [np.ones(3), np.zeros(3)], np.zeros(1), np.zeros(3),
                                 np.ones(3), np.zeros(4), np.ones(4), first=5)
    assert [r.start for r in runs] == [5, 6]
    assert all(r.status is Status.SOLVER_ERROR and r.return_status == "Evaluation_Error"
               and r.f == np.inf and r.lam_g.shape == (4,) for r in runs)
    assert solve_once(refuses, np.ones(3), None, None, None, np.zeros(4), None).status \
        is Status.SOLVER_ERROR
