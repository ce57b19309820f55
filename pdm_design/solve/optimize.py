"""`optimize(spec)`: build (or reuse) the NLP, multistart IPOPT, diagnose, re-check, report."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from ..formulation import build, formulate
from ..formulation.allocation import allocating, pivot_box, values_at
from ..formulation.build import FULL
from ..formulation.common import BACKOFF_FACTOR, MODEL, OBJECTIVE_SENSE
from ..formulation.yield_target import AUX as TARGET_SCALE
from ..formulation.yield_target import scale_of
from ..status import Status
from . import check, elastic
from .ipopt import SolverOptions, best, solve_once, solver_for, start_designs
from .result import LinearisedTolerance, OptimizeResult, Solution, SolverStats
from .screen import SAMPLE, at_target_scales, screened
from .stacked import groups, solve_stacked, stacked_solver_for
from .tiebreak import nearest_optimum
from .words import bounds_hint, normalised_margin, summarise

FEASIBILITY_TOL = 1e-7
NOT_ASKED = ("not computed: not asked for (`optimize --linearised`, linearise=True in the API); "
             "the robust box is the answer")


@dataclass
class _Search:
    """Where the solve stands: the formulation solved (the full one after a retry), one Solve
    per start, every IPOPT run made, the starts that shared a stacked run, the chosen run, and
    what it cost beyond the IPOPT runs (build seconds; the tie-break's or the diagnosis'
    iterations and seconds)."""

    form: object
    runs: list
    calls: list
    stacked_starts: int
    chosen: object
    build_time: float
    extra_iters: int = 0
    extra_time: float = 0.0
    tie_iters: int = -1
    kept: bool = False


DISTINCT = 1e-4  # two optima whose designs differ by less (of the bounds) are one


def optimize(
    spec,
    *,
    starts: int = 8,
    seed: int = 0,
    max_iter: int = 500,
    tol: float = 1e-8,
    bound_relax_factor: float = 1e-8,
    requirements: dict[str, float] | None = None,
    warm_start: OptimizeResult | None = None,
    diagnose: bool = True,
    linearise: bool = False,
    check_samples: int = 256,
    start_from: dict[str, float] | None = None,
    tie_break: bool = True,
    continued: tuple[Solution, ...] = (),
) -> OptimizeResult:
    """Best design of `spec` (see docs/optimizer.md).

    starts: IPOPT runs from the spec's initial guess and scrambled-Sobol points in the bounds.
    requirements: required margins (default: the spec's); they are NLP parameters, so changing
        them re-solves the same built NLP.
    warm_start: a previous result of the same spec: one extra run from its solution and
        multipliers (IPOPT warm start), tried first.
    diagnose: when no start succeeds, solve the elastic problem and report what cannot be met.
    linearise: compute the cvxpy box / ellipsoid in the linearised safe set (an informative
        extra that costs more than the answer: off unless asked; a robust answer then carries
        a `linearised` whose status says it was not computed).
    check_samples: offsets sampled inside the robust box for the independent check (0: skip).
    bound_relax_factor: IPOPT's bound relaxation; 0 puts the optimum on its bounds exactly.
    start_from: a design (free variables by name) to start from first, besides the others (a
        table's neighbouring point): it may speed the solve, never move the spec's guess.
    tie_break: of an optimal set, the design nearest the spec's guess (solve/tiebreak.py: the
        same spec gives the same design whatever the starts found first).
    continued: the local optima of a neighbouring spec with the same NLP (`result.optima`: a
        table's point before this one, formulation/parametric.py): each is solved again from
        its solution and multipliers instead of the starts; the starts run only if one of
        those runs does not succeed (docs/tables.md, "Warm starts").
    """
    tic = time.perf_counter()
    form, was_cached, build_time, ws = _formulation(spec, warm_start)
    _check_options(spec, requirements, starts, max_iter, tol)
    reqs = dict(spec.requirements if requirements is None else requirements)
    p = form.parameters(reqs, backoff=BACKOFF_FACTOR * max(tol, bound_relax_factor))
    options = SolverOptions(max_iter=max_iter, tol=tol, bound_relax_factor=bound_relax_factor)
    guess, lows, highs, x_starts = _start_points(spec, form, p, starts, seed, start_from)

    search = _continue(form, options, continued, p, build_time)
    if not search.runs or search.chosen is None:  # none to continue from, or one failed
        tried = search.runs
        search = _search(spec, form, options, x_starts, p, ws, was_cached, build_time)
        search.runs, search.calls = tried + search.runs, tried + search.calls
    if search.chosen.status is Status.OPTIMAL and tie_break:
        _tie_break(search, options, p, guess, lows, highs)
    status, x = search.chosen.status, search.chosen.x
    violations, at_bounds = (), ()
    if status in (Status.INFEASIBLE, Status.SOLVER_ERROR) and diagnose:
        (search.chosen, status, x, violations, at_bounds, search.extra_iters,
         search.extra_time) = _diagnose(search.form, options, x_starts, p, search.chosen,
                                        search.runs, search.calls)
    return _assemble(spec, search, status, x, p, reqs, violations, at_bounds, tic,
                     linearise=linearise, check_samples=check_samples, seed=seed)


def _formulation(spec, warm_start):
    """(the formulation, whether it was built before, its build seconds, the warm start's
    solution or None): the full NLP when the warm start solved that one."""
    was_cached = build.is_cached(spec)
    form = formulate(spec)
    build_time = 0.0 if was_cached else form.build_time
    ws = warm_start.solution if warm_start is not None else None
    if ws is not None and ws.key == form.key + FULL:
        form = formulate(spec, full=True)  # the warm start solved the NLP with every row
    return form, was_cached, build_time, ws


def _check_options(spec, requirements, starts, max_iter, tol) -> None:
    """The options' own checks, before any solve (ValueError naming the option)."""
    if requirements is not None:
        _check_requirements(spec, requirements)
    if isinstance(starts, bool) or not isinstance(starts, int) or starts < 1:
        raise ValueError(f"starts = {starts!r}, expected an integer >= 1")
    if not (tol > 0.0 and max_iter >= 1):  # IPOPT refuses them with its whole option text
        raise ValueError(f"tol = {tol!r}, max_iter = {max_iter!r}: expected tol > 0 and "
                         "max_iter >= 1")


# designs drawn to find a start where the closed forms are defined when the guess is not one
ANCHOR_CANDIDATES = 64


def _start_points(spec, form, p, starts, seed, start_from):
    """(the spec's guess by name, the lower and upper bounds, the NLP's start points): the
    `start_from` design first, then the guess and scrambled-Sobol points."""
    names = form.design_names
    guess = {n: spec.design[n].guess for n in names}
    lows = [spec.design[n].min for n in names]
    highs = [spec.design[n].max for n in names]
    screen = form.screened_starts and starts > 1 and names
    designs = start_designs(names, lows, highs, guess, SAMPLE if screen else max(starts, 1),
                            seed)
    always = 1  # the guess
    if start_from:  # first, so that it is tried even with one start
        designs = [{n: float(start_from.get(n, guess[n])) for n in names}] + designs
        always = 2
    anchor = form.defined_anchor(guess, lambda: designs + start_designs(
        names, lows, highs, guess, ANCHOR_CANDIDATES, seed + 1), p)
    x_starts = form.defined_starts(designs, anchor, p)
    if screen:  # the starts worth a run of the sample (solve/screen.py)
        x_starts = screened(form, p, x_starts, always, starts)
    else:  # a yield target's scale: each start's own largest meeting it
        x_starts = at_target_scales(form, p, x_starts)
    return guess, lows, highs, x_starts


def _stacks(form, was_cached: bool) -> bool:
    """Whether the starts are solved stacked: only for an NLP solved before in this process
    (creating the stacked solver costs more than it saves in one solve, docs/optimizer.md
    section 5), and always for a table's generic NLP (formulation/parametric.py), whose solver
    serves every point, so that a row does not depend on which worker solved it first."""
    return (was_cached or bool(form.parameter_names)) and form.stack_starts


def _continue(form, options, continued, p, build_time) -> _Search:
    """The search continued from a neighbour's local optima: each solved from its solution and
    multipliers (IPOPT's warm start). No runs when there are none of this NLP; no chosen run
    (search from the starts, these runs counted too) unless every run succeeds without
    breaking a deferred row."""
    if not continued or any(s.key != form.key for s in continued):
        return _Search(form, [], [], 0, None, build_time)
    solver = solver_for(form.key, form.nlp, replace(options, warm=True))
    runs = [solve_once(solver, s.x, p, form.lbx, form.ubx, form.lbg, form.ubg, lam_x0=s.lam_x,
                       lam_g0=s.lam_g, start=-1 - i) for i, s in enumerate(continued)]
    chosen = best(runs)
    if any(r.status is not Status.OPTIMAL for r in runs) or form.deferred_broken(chosen.x, p):
        chosen = None
    return _Search(form, runs, list(runs), 0, chosen, build_time)


def optima(form, runs) -> tuple[Solution, ...]:
    """The distinct local optima among the runs that succeeded, best first: a design apart
    from every better one by more than DISTINCT of its bounds (the auxiliaries aside)."""
    n = form.n_design
    span = form.ubx[:n] - form.lbx[:n]
    span = np.where(np.isfinite(span) & (span > 0.0), span, 1.0)
    kept = []
    for run in sorted((r for r in runs if r.status is Status.OPTIMAL), key=lambda r: r.f):
        if all(np.max(np.abs(run.x[:n] - k.x[:n]) / span, initial=0.0) > DISTINCT
               for k in kept):
            kept.append(run)
    return tuple(Solution(form.key, r.x, r.lam_x, r.lam_g) for r in kept)


def _search(spec, form, options, x_starts, p, ws, was_cached, build_time) -> _Search:
    """The multistart, and its retry with every row when the answer breaks a deferred one."""
    runs, calls, stacked_starts = _multistart(form, options, x_starts, p, ws,
                                              _stacks(form, was_cached))
    chosen = best(runs)
    if chosen.status in (Status.OPTIMAL, Status.ACCEPTABLE) and form.deferred_broken(chosen.x, p):
        # The answer breaks a row left out of the NLP: solve every start again with every row
        # (and diagnose with them if that fails). A spec that fails without them is diagnosed
        # without them: the analysis' margins at the diagnosed point include theirs.
        was_cached = build.is_cached(spec, full=True)
        form = formulate(spec, full=True)
        build_time += 0.0 if was_cached else form.build_time
        runs, more_calls, stacked_starts = _multistart(form, options, x_starts, p, None,
                                                       _stacks(form, was_cached))
        calls += more_calls
        chosen = best(runs)
    return _Search(form, runs, calls, stacked_starts, chosen, build_time)


def _tie_break(search: _Search, options, p, guess, lows, highs) -> None:
    """One design for one spec: the optimal design nearest the spec's guess (tiebreak.py);
    its run's cost is counted, its design kept only when it is optimal too."""
    nearest, search.kept = nearest_optimum(search.form, options, search.chosen, p, guess, lows,
                                           highs)
    if nearest is not None:
        search.tie_iters = search.extra_iters = nearest.iterations
        search.extra_time = nearest.seconds
    if search.kept:
        search.chosen = replace(search.chosen, x=nearest.x)


def _assemble(spec, search: _Search, status, x, p, reqs, violations, at_bounds, tic, *,
              linearise, check_samples, seed) -> OptimizeResult:
    """The result at x: the design, objectives, box, margins, checks, status and statistics."""
    form = search.form
    # IPOPT relaxes bounds by bound_relax_factor: restitution 1 came back as 1 + 7e-9, a rise
    # of -1e-8 followed, and the re-check refused it. The design is what lies within them.
    x = np.clip(x, form.lbx, form.ubx)
    design = form.design_values(x)
    slack, scale, terms, _ = (np.asarray(v, dtype=float).ravel() for v in form.evaluate(x, p))
    objectives = dict(zip(form.objective_names, terms.tolist()))
    # Only an answer IPOPT converged to claims a box, a score or a linearised set; a stopped or
    # failed run's last point claims nothing (a solver error reported a box of 0 mm).
    answered = status in (Status.OPTIMAL, Status.ACCEPTABLE)
    tolerance, allocated = _tolerance(spec, form, x) if answered else (None, None)
    robust_margins = _robust_margins(form, x, p, slack, scale)
    score = None
    if answered:
        score = float(sum(w * OBJECTIVE_SENSE[n] * objectives[n] for n, w in form.weights.items()))
    analysis, checks = _checks(spec, form, x, p, design, reqs, tolerance, allocated,
                               check_samples, seed)
    linearised = _linearised(spec, form, x, p, design, linearise) if answered else None
    status = _checked_status(status, checks, form)
    return OptimizeResult(
        status=status, design=design, objective=score, objectives=objectives,
        tolerance=tolerance, linearised=linearised,
        margins=dict(analysis.margins) if analysis is not None else {},
        robust_margins=robust_margins,
        periodic=dict(analysis.periodic) if analysis is not None else {},
        violations=tuple(violations), checks=checks, stats=_stats(search, tic),
        message=_message(status, violations, at_bounds, spec.kind),
        at_bounds=tuple(at_bounds) if violations else (),
        solution=Solution(form.key, x, search.chosen.lam_x, search.chosen.lam_g),
        tolerances=allocated, optima=optima(form, search.runs),
    )


def _tolerance(spec, form, x):
    """(the robust box by axis, the allocated half-widths or None) of a converged answer;
    (None, None) for a spec without a tolerance."""
    if form.tolerance_index is None:
        if TARGET_SCALE in form.x_names:  # sized for a yield target (formulation/yield_target)
            z = float(x[form.x_names.index(TARGET_SCALE)])
            return None, tuple(values_at(spec, scale_of(z)))
        return None, None
    tol_value = float(x[form.tolerance_index])
    tolerance = {axis: tol_value for axis in form.tolerance_axes}
    allocated = None
    if allocating(spec):  # one half-width per quantity (formulation/allocation.py)
        allocated = tuple(values_at(spec, tol_value))
        tolerance = pivot_box(spec, allocated)
    return tolerance, allocated


def _checks(spec, form, x, p, design, reqs, tolerance, allocated, check_samples, seed):
    """(the closed-form analysis or None, the independent checks by name): the closed-form
    re-check, and offsets sampled inside the robust box."""
    closed = check.closed_form_check(spec, design, reqs)
    checks: dict[str, object] = {"closed_form": {"passed": closed["passed"],
                                                 "failures": closed["failures"]}}
    # (a scene without explicit-error scenarios: its simulator checks the box, verify/)
    if (form.tolerance_index is not None and tolerance and check_samples > 0
            and form.scenario_source is not None):
        checks["sampled_offsets"] = check.sampled_offsets_check(
            form, x, p, tuple(tolerance.values()) if allocated else
            float(x[form.tolerance_index]), samples=check_samples, seed=seed)
    return closed["analysis"], checks


def _linearised(spec, form, x, p, design, linearise):
    """A converged answer's linearised tolerance set: computed when asked, else marked so;
    None for a spec without a tolerance."""
    if form.tolerance_index is None:
        return None
    if not linearise:
        return LinearisedTolerance(0.0, {}, {}, (), status=NOT_ASKED)
    from .tolerance import linearised_tolerance  # cvxpy: only when asked

    size = _length_scale(spec, design)  # offsets in units of the device's size: the same
    return linearised_tolerance(form, x, p, cap=10.0 * size, length=size)  # at any scale


def _checked_status(status, checks, form):
    """A converged answer that fails a check is UNVERIFIED; with nothing free, EVALUATED."""
    if status in (Status.OPTIMAL, Status.ACCEPTABLE):
        failed = [k for k, v in checks.items() if isinstance(v, dict) and not v["passed"]]
        if failed:
            status = Status.UNVERIFIED
        elif status is Status.OPTIMAL and not form.design_names:
            status = Status.EVALUATED
    return status


def _stats(search: _Search, tic) -> SolverStats:
    """The solve's iterations, seconds and starts, every run's and the extra runs' counted."""
    chosen, runs, calls = search.chosen, search.runs, search.calls
    return SolverStats(
        iterations=chosen.iterations,
        total_iterations=sum(r.iterations for r in calls) + search.extra_iters,
        solve_time=chosen.seconds,
        total_solve_time=sum(r.seconds for r in calls) + search.extra_time,
        starts=len(runs),
        stacked_starts=search.stacked_starts,
        build_time=search.build_time,
        wall_time=time.perf_counter() - tic,
        return_statuses=tuple(r.return_status for r in runs),
        tie_break_iterations=search.tie_iters,
        tie_break_kept=search.kept,
    )


def _diagnose(form, options, x_starts, p, chosen, runs, calls):
    """No start succeeded: solve the elastic problem (solve/elastic.py). If it finds the spec
    feasible after all, IPOPT restarts from its point (appended to runs and calls); if it finds
    it infeasible, its least-violation design and violations are the answer; if it fails too,
    IPOPT's own status stands and nothing more is claimed.
    Returns (chosen, status, x, violations, at_bounds, its iterations, its seconds)."""
    diag = elastic.diagnose(form, p, x_starts[: min(len(x_starts), 4)],
                            max_iter=options.max_iter)
    status, x, violations, at_bounds = chosen.status, chosen.x, (), ()
    if diag.status in (Status.OPTIMAL, Status.ACCEPTABLE):
        if diag.total <= FEASIBILITY_TOL:
            solver = solver_for(form.key, form.nlp, options)
            retry = solve_once(solver, diag.x, p, form.lbx, form.ubx, form.lbg, form.ubg,
                               start=len(runs))
            runs.append(retry)
            calls.append(retry)
            if retry.status in (Status.OPTIMAL, Status.ACCEPTABLE):
                chosen, status, x = retry, retry.status, retry.x
        else:
            status, x, violations = Status.INFEASIBLE, diag.x, diag.violations
            at_bounds = diag.at_bounds
    return chosen, status, x, violations, at_bounds, diag.iterations, diag.seconds


def _robust_margins(form, x, p, slack, scale) -> dict[str, float]:
    """Each row's normalised margin at x, the deferred rows' included (checked, not solved)."""
    out = {info.label: normalised_margin(slack[info.index], scale[info.index])
           for info in form.conditions if info.kind != MODEL}
    if form.deferred is not None:
        d_slack, d_scale, _ = (np.asarray(v, dtype=float).ravel() for v in form.deferred(x, p))
        out.update({info.label: normalised_margin(d_slack[info.index], d_scale[info.index])
                    for info in form.deferred_conditions})
    return out


def _message(status, violations, at_bounds, kind=None) -> str:
    message = status.message
    if violations:
        message += " Cannot be met: " + "; ".join(summarise(violations, kind)[:5]) + "."
        if at_bounds:
            hint = bounds_hint(at_bounds)
            message += f" {hint[0].upper()}{hint[1:]}."
    return message


def _multistart(form, options, x_starts, p, warm_solution, stack):
    """(one Solve per start, the IPOPT runs made, how many starts shared a stacked run), the
    warm start's run first when it solved this NLP."""
    runs, calls = [], []  # one Solve per start; one per IPOPT run (stacked starts share one)
    if warm_solution is not None and warm_solution.key == form.key:
        warm = solver_for(form.key, form.nlp, replace(options, warm=True))
        ws = warm_solution
        runs.append(solve_once(warm, ws.x, p, form.lbx, form.ubx, form.lbg, form.ubg,
                               lam_x0=ws.lam_x, lam_g0=ws.lam_g, start=-1))
        calls.append(runs[-1])
    solver = solver_for(form.key, form.nlp, options)
    from_starts, start_calls, stacked_starts = _solve_starts(form, options, solver, x_starts, p,
                                                             stack)
    return runs + from_starts, calls + start_calls, stacked_starts


def _solve_starts(form, options, solver, x_starts, p, stack):
    """(one Solve per start, the IPOPT runs made, how many starts shared a stacked run). The
    starts are solved together in groups (solve/stacked.py) when `stack` (the NLP gains by it,
    Formulation.stack_starts, and was solved before); a group whose stacked run does not succeed
    is solved one by one, and its failed run still counts in the totals."""
    runs, calls, shared = [], [], 0
    for group in groups(len(x_starts)):
        starts = x_starts[group.start:group.stop]
        if len(starts) > 1 and stack:
            stacked = stacked_solver_for(form.key, form.nlp, options, len(starts))
            together = solve_stacked(stacked, starts, p, form.lbx, form.ubx, form.lbg, form.ubg,
                                     first=group.start)
            calls.append(together[0])
            if together[0].status is Status.OPTIMAL:
                runs += together
                shared += len(together)
                continue
        alone = [solve_once(solver, x0, p, form.lbx, form.ubx, form.lbg, form.ubg, start=i)
                 for i, x0 in zip(group, starts)]
        runs += alone
        calls += alone
    return runs, calls, shared


def _check_requirements(spec, requirements: dict) -> None:
    """The checks a spec's [requirements] table gets (docs/spec.md, section 7): a misspelt name
    would otherwise hold nothing, silently."""
    from ..plugin import of

    known = of(spec).margins
    for name, value in requirements.items():
        if name not in known:
            raise ValueError(f"requirements: {name!r} is not a margin of a {spec.kind} spec "
                             f"(one of {', '.join(known)})")
        if isinstance(value, bool) or not -1.0 <= float(value) <= 1.0:  # NaN fails too
            raise ValueError(f"requirements: {name} = {value!r}, expected a number in [-1, 1]")


def _length_scale(spec, design) -> float:
    """The device's size (m): Scene.length_scale."""
    from ..plugin import of

    return of(spec).length_scale(spec, design)

