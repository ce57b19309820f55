"""Benchmark of the designer (not a test): time per IPOPT solve and per optimize run on a spec,
against the same NLP solved with scipy's SLSQP (finite differences) and against the independent
grid search of tests/test_optimize.py. Writes results/bench_optimize.md.

    python results/bench_optimize.py            # about 20 s
    python results/bench_optimize.py --quick    # fewer repeats
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.optimize import minimize

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pdm_design.formulation import formulate  # noqa: E402
from pdm_design.solve import optimize, stacked  # noqa: E402
from pdm_design.solve.ipopt import SolverOptions, solve_once, solver_for, start_designs  # noqa: E402
from pdm_design.spec import load_spec  # noqa: E402


def _grid_module():
    spec = importlib.util.spec_from_file_location("test_optimize", ROOT / "tests/test_optimize.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def timed(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        tic = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - tic)
    return statistics.median(times), out


def bench_ipopt(spec, form, repeats):
    p = form.parameters(spec.requirements)
    solver = solver_for(form.key, form.nlp, SolverOptions())
    names = form.design_names
    guess = {n: spec.design[n].guess for n in names}
    designs = start_designs(names, [spec.design[n].min for n in names],
                            [spec.design[n].max for n in names], guess, 8)
    starts = [form.defined_start(d, guess, p) for d in designs]
    solves = []
    for _ in range(repeats):
        for i, x0 in enumerate(starts):
            solves.append(solve_once(solver, x0, p, form.lbx, form.ubx, form.lbg, form.ubg,
                                     start=i))
    ok = [s for s in solves if s.return_status == "Solve_Succeeded"]
    return {
        "median_solve": statistics.median(s.seconds for s in solves),
        "p90_solve": float(np.percentile([s.seconds for s in solves], 90)),
        "median_iterations": statistics.median(s.iterations for s in solves),
        "succeeded": f"{len(ok)}/{len(solves)}",
        # the tolerance itself: the NLP's f is the objective divided by its size (stairs)
        "best_objective": max(s.x[form.tolerance_index] for s in ok),
        "starts": starts,
    }


def bench_slsqp(spec, form, starts, repeats, *, fg=None, solver=None, optimize_run=None):
    """The same NLP (objective f, rows g, bounds) by SLSQP, gradients by finite differences.
    fg (objective and rows) and the IPOPT solver of the paired timing default to the shipped,
    uncompiled ones. optimize_run (a callable): one `optimize` of the same starts, timed
    alternately with SLSQP's whole run for the paired per-run ratio."""
    p = form.parameters(spec.requirements)
    if fg is None:
        fg = ca.Function("fg", [form.nlp["x"], form.nlp["p"]], [form.nlp["f"], form.nlp["g"]])
    eq = np.flatnonzero(form.ubg == form.lbg)
    ineq = np.flatnonzero(form.ubg != form.lbg)
    bounds = list(zip(form.lbx, np.where(np.isfinite(form.ubx), form.ubx, None)))
    # Every point of a solve is kept: scipy differences the objective and each constraint group
    # separately at the same points, and a one-point cache evaluated each point three times
    # (SLSQP 1.9x slower than it needs to be).
    cache = {}

    def evaluate(x):
        key = x.tobytes()
        if key not in cache:
            f, g = fg(x, p)
            cache[key] = (float(f), np.asarray(g).ravel())
        return cache[key]

    constraints = [{"type": "ineq", "fun": lambda x: evaluate(x)[1][ineq] - form.lbg[ineq]},
                   {"type": "eq", "fun": lambda x: evaluate(x)[1][eq] - form.lbg[eq]}]

    def one(x0):
        cache.clear()
        tic = time.perf_counter()
        res = minimize(lambda x: evaluate(x)[0], x0, method="SLSQP", bounds=bounds,
                       constraints=constraints, options={"maxiter": 500, "ftol": 1e-10})
        g = evaluate(res.x)[1]
        viol = max(np.max(np.maximum(form.lbg[ineq] - g[ineq], 0), initial=0.0),
                   np.max(np.abs(g[eq] - form.lbg[eq]), initial=0.0))
        return time.perf_counter() - tic, res, viol

    def run_all():
        return [one(x0) for x0 in starts]

    per_run, run_ratios, runs = [], [], None
    for _ in range(repeats):
        ipopt_seconds = timed(optimize_run, 1)[0] if optimize_run else None
        tic = time.perf_counter()
        runs = run_all()
        per_run.append(time.perf_counter() - tic)
        if ipopt_seconds:
            run_ratios.append(per_run[-1] / ipopt_seconds)
    feasible = [(-r.x[form.tolerance_index], r) for _, r, v in runs if r.success and v <= 1e-6]
    # Paired timing: the same start by IPOPT then by SLSQP, alternately, so that both see the
    # same machine load.
    solver = solver or solver_for(form.key, form.nlp, SolverOptions())
    ratios = []
    for _ in range(repeats):
        for x0 in starts:
            a = solve_once(solver, x0, p, form.lbx, form.ubx, form.lbg, form.ubg).seconds
            ratios.append(one(x0)[0] / a)
    return {
        "paired_ratio": statistics.median(ratios),
        "paired_run_ratio": statistics.median(run_ratios) if run_ratios else float("nan"),
        "median_solve": statistics.median(t for t, _, _ in runs),
        "median_run": statistics.median(per_run),
        "succeeded": f"{len(feasible)}/{len(runs)}",
        "median_iterations": statistics.median(r.nit for _, r, _ in runs),
        "median_evaluations": statistics.median(r.nfev for _, r, _ in runs),
        "best_objective": -min(f for f, _ in feasible) if feasible else float("nan"),
    }


def bench_grid(spec, repeats):
    mod = _grid_module()
    alpha = np.linspace(spec.design["alpha"].min, spec.design["alpha"].max, 121)
    beta = np.linspace(spec.design["beta"].min, spec.design["beta"].max, 201)

    def run():
        return mod.robust_tolerance_grid(spec.scene, alpha, beta, link_length=2.0,
                                         mass_ratio=10.0, stages=spec.verification.stages)

    seconds, grid = timed(run, repeats)
    i, j = np.unravel_index(np.argmax(grid), grid.shape)
    return {"seconds": seconds, "best_objective": float(grid.max()), "alpha": alpha[i],
            "beta": beta[j], "points": grid.size}


def _deferred(spec, form):
    """The rows the NLP leaves out and `optimize` checks at its answer (docs/optimizer.md)."""
    n = len(form.deferred_conditions)
    if not n:
        return ""
    held = optimize(spec, linearise=False, check_samples=0).solution.key == form.key
    outcome = ("they hold there, so neither method is given them" if held
               else "its answer broke them, and it solved with them")
    return (f", and {n} deferred rows (palms parked at their front stops) that `optimize` checks "
            f"at its answer: {outcome}")


def _slsqp_rows(slsqp):
    """The two SLSQP rows of a comparison table (one solve, the 8-start run)."""
    return [
        f"| SLSQP + finite differences, one solve | {slsqp['median_solve'] * 1e3:.2f} ms | – | "
        f"median {slsqp['median_iterations']:.0f} iterations, "
        f"{slsqp['median_evaluations']:.0f} function evaluations |",
        f"| SLSQP + finite differences, 8 starts | {slsqp['median_run'] * 1e3:.1f} ms | "
        f"{slsqp['best_objective']:.6f} | {slsqp['succeeded']} converged feasible |",
    ]


def bench_problem(name, title, what, reps):
    """IPOPT against SLSQP only, on problems/<name>.toml ({stages} in `what`: its stages)."""
    spec = load_spec(ROOT / f"problems/{name}.toml")
    form = formulate(spec)
    ipopt = bench_ipopt(spec, form, reps)
    optimize(spec)
    run, res = timed(lambda: optimize(spec, linearise=False, check_samples=0), reps)
    slsqp = bench_slsqp(spec, form, ipopt["starts"], max(2, reps // 2),
                        optimize_run=lambda: optimize(spec, linearise=False, check_samples=0))
    lines = [
        f"## {title}: `problems/{name}.toml`",
        "",
        f"{len(form.x_names)} variables ({', '.join(form.x_names)}), {len(form.lbg)} rows "
        f"({what.format(stages=spec.verification.stages)}){_deferred(spec, form)}.",
        "",
        "| method | time | objective (tolerance, m) | notes |",
        "|---|---|---|---|",
        f"| IPOPT, one solve | {ipopt['median_solve'] * 1e3:.2f} ms | "
        f"{ipopt['best_objective']:.6f} | median {ipopt['median_iterations']:.0f} iterations, "
        f"{ipopt['succeeded']} Solve_Succeeded |",
        f"| IPOPT, `optimize` ({_how(res)}) | {run * 1e3:.1f} ms | "
        f"{res.objective:.6f} | status {res.status.value}, {_iterations(res)} |",
        *_slsqp_rows(slsqp),
        "",
        f"Ratio SLSQP / IPOPT: per solve **{slsqp['median_solve'] / ipopt['median_solve']:.1f}x** "
        f"(paired: **{slsqp['paired_ratio']:.1f}x**),"
        f" per 8-start run **{slsqp['median_run'] / run:.1f}x** "
        f"(paired: **{slsqp['paired_run_ratio']:.1f}x**).",
        "",
    ]
    if not form.stack_starts:
        lines += _unstacked(spec, reps)
    return lines


def _how(result):
    """How `optimize` solved its starts, in a table cell."""
    if result.stats.stacked_starts:
        return f"{result.stats.starts} starts stacked into one NLP"
    return f"{result.stats.starts} starts, one IPOPT run each"


def _iterations(result):
    stats = result.stats
    if stats.stacked_starts:
        return f"{stats.iterations} iterations"
    return f"{stats.total_iterations} iterations in all"


def _unstacked(spec, reps):
    """Why `optimize` solves this scene's starts one at a time (Formulation.stack_starts): its
    run against the same starts stacked into one NLP, on the spec and on the spec with a
    required nose clearance (exact nose rows)."""
    nose = replace(spec, requirements={**spec.requirements, "nose_clearance": 0.05})
    return [
        "Why `optimize` solves the stairs' starts one at a time (`Formulation.stack_starts`): "
        "the same 8 starts stacked into one NLP (the stacked solver created beforehand, as a "
        "re-solve would find it) against `optimize` as shipped, no post-processing:",
        "",
        "| spec | `optimize`, one run per start | stacked into one NLP |",
        "|---|---|---|",
        _stacked_against_alone("as shipped", spec, reps),
        _stacked_against_alone("`nose_clearance = 0.05`", nose, reps),
        "",
    ]


def _stacked_against_alone(label, spec, reps):
    """A table row: `optimize` (one run per start) against its starts stacked into one NLP."""
    form = formulate(spec)
    p = form.parameters(spec.requirements)
    starts = bench_ipopt(spec, form, 1)["starts"]
    optimize(spec)
    alone, res = timed(lambda: optimize(spec, linearise=False, check_samples=0), reps)
    solver = stacked.stacked_solver_for(form.key, form.nlp, SolverOptions(), len(starts))
    together, copies = timed(lambda: stacked.solve_stacked(
        solver, starts, p, form.lbx, form.ubx, form.lbg, form.ubg), reps)
    return (f"| {label} | {alone * 1e3:.1f} ms, {res.stats.total_iterations} iterations in all | "
            f"{together * 1e3:.1f} ms, {copies[0].iterations} iterations, "
            f"{copies[0].return_status} |")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(ROOT / "results/bench_optimize.md"))
    args = parser.parse_args()
    reps = 3 if args.quick else 20
    load_before = os.getloadavg()[0]
    path = ROOT / "problems/manipulators_robust.toml"
    spec = load_spec(path)

    build, form = timed(lambda: formulate(spec, cache=False), reps)
    nlpsol, _ = timed(lambda: ca.nlpsol("b", "ipopt", form.nlp, SolverOptions().casadi()), reps)
    stacked_build, _ = timed(lambda: stacked.build_stacked(form.nlp, SolverOptions(), 8),
                             max(2, reps // 5))
    form = formulate(spec)
    ipopt = bench_ipopt(spec, form, reps)
    optimize(spec)  # warm the caches: the build is once per spec
    run_bare, res = timed(lambda: optimize(spec, linearise=False, check_samples=0), reps)
    run_full, full = timed(lambda: optimize(spec), max(3, reps // 4))
    warm, wres = timed(lambda: optimize(spec, starts=1, warm_start=res, linearise=False,
                                        check_samples=0), reps)
    slsqp = bench_slsqp(spec, form, ipopt["starts"], max(2, reps // 2),
                        optimize_run=lambda: optimize(spec, linearise=False, check_samples=0))
    grid = bench_grid(spec, max(2, reps // 10))

    nlp_obj = res.objective
    lines = [
        "# Optimizer benchmark",
        "",
        "Command (from the repository root; regenerates this file):",
        "",
        "    python results/bench_optimize.py",
        "",
        f"Machine: {platform.processor() or platform.machine()}, Python "
        f"{platform.python_version()}, CasADi {ca.__version__} (IPOPT, MUMPS), "
        f"{reps} repeats, load average {load_before:.2f} before / {os.getloadavg()[0]:.2f} after "
        f"on {os.cpu_count()} CPUs. Problem: `problems/manipulators_robust.toml` "
        f"(alpha, beta free; "
        f"maximise the pivot offset tolerance over {spec.verification.stages} manipulators): "
        f"{len(form.x_names)} variables ({', '.join(form.x_names)}), {len(form.lbg)} constraint "
        f"rows{_deferred(spec, form)}. Times are medians, wall clock.",
        "",
        "## Build once, solve many",
        "",
        "| step | time |",
        "|---|---|",
        f"| build the NLP from the spec (SX expressions, rows, scenario function) | "
        f"{build * 1e3:.1f} ms |",
        f"| create the IPOPT solver (`nlpsol`: derivatives, sparsity) | {nlpsol * 1e3:.1f} ms |",
        f"| create the stacked solver `optimize` uses for 8 starts | "
        f"{stacked_build * 1e3:.1f} ms |",
        f"| one IPOPT solve of the built NLP (median over {8 * reps} solves from 8 starts) | "
        f"**{ipopt['median_solve'] * 1e3:.2f} ms** (90th percentile "
        f"{ipopt['p90_solve'] * 1e3:.2f} ms; median {ipopt['median_iterations']:.0f} "
        f"iterations; {ipopt['succeeded']} Solve_Succeeded) |",
        f"| one `optimize` run, 8 starts (stacked into one NLP), no post-processing | "
        f"{run_bare * 1e3:.1f} ms |",
        f"| one `optimize` run, 8 starts, with cvxpy box/ellipsoid and checks | "
        f"{run_full * 1e3:.1f} ms |",
        f"| one warm-started `optimize` run (1 start + the previous solution) | "
        f"{warm * 1e3:.1f} ms ({wres.stats.iterations} iterations) |",
        "",
        "## Against other methods (same problem, same run)",
        "",
        "| method | time | objective (tolerance, m) | notes |",
        "|---|---|---|---|",
        f"| IPOPT, one solve | {ipopt['median_solve'] * 1e3:.2f} ms | "
        f"{ipopt['best_objective']:.6f} | exact Hessian (CasADi AD) |",
        f"| IPOPT, `optimize` (8 starts stacked into one NLP) | {run_bare * 1e3:.1f} ms | "
        f"{nlp_obj:.6f} | status {res.status.value}, {res.stats.iterations} iterations |",
        *_slsqp_rows(slsqp),
        f"| grid search, {grid['points']} points x bisection (numpy, vectorised) | "
        f"{grid['seconds'] * 1e3:.0f} ms | {grid['best_objective']:.6f} | best at "
        f"alpha {grid['alpha']:.3f}, beta {grid['beta']:.3f} |",
        "",
        "Ratios (the machine is shared, 2 cores: unpaired medians of two methods are taken at "
        "different moments and swing with the load; the paired ratio, IPOPT and SLSQP "
        "alternating on the same start, is the fair one):",
        "",
        f"- SLSQP / IPOPT per solve: **{slsqp['median_solve'] / ipopt['median_solve']:.1f}x** "
        f"(median of paired, interleaved solves from the same start: "
        f"**{slsqp['paired_ratio']:.1f}x**); "
        f"per 8-start run (`optimize` solves its starts stacked into one NLP): "
        f"**{slsqp['median_run'] / run_bare:.1f}x** (paired, alternating: "
        f"**{slsqp['paired_run_ratio']:.1f}x**; objective IPOPT {nlp_obj:.6f} vs SLSQP "
        f"{slsqp['best_objective']:.6f}).",
        f"- grid / IPOPT optimize run: **{grid['seconds'] / run_bare:.0f}x** "
        f"(objective grid {grid['best_objective']:.6f}, "
        f"{(nlp_obj / grid['best_objective'] - 1) * 100:+.2f} % for IPOPT).",
        "",
        "The SLSQP baseline evaluates the very same CasADi functions (objective and rows, no "
        "derivatives), each point once (scipy differences the objective and the two constraint "
        "groups separately at the same points; the baseline remembers every point of a solve), "
        "so the difference is the method: finite-difference gradients and a "
        "quasi-Newton Hessian versus IPOPT with exact first and second derivatives. The grid is "
        "the independent numpy implementation of the robust tolerance used in "
        "`tests/test_optimize.py` (bisection on the box half-width at each grid point).",
        "",
        f"Design found: alpha = {res.design['alpha']:.6f} rad, beta = {res.design['beta']:.6f} "
        f"rad, tolerance {nlp_obj * 1e3:.2f} mm; cvxpy box in the linearised safe set: "
        f"square {full.linearised.square * 1e3:.2f} mm, per axis dx "
        f"{full.linearised.box['dx'] * 1e3:.2f} mm / dy {full.linearised.box['dy'] * 1e3:.2f} mm;"
        f" largest centred ellipsoid: smallest semi-axis "
        f"{full.linearised.ellipsoid['min_semi_axis'] * 1e3:.2f} mm. Sampled-offset check: "
        f"{full.checks['sampled_offsets']['samples']} offset vectors inside the robust box, worst "
        f"excess margin {full.checks['sampled_offsets']['worst_excess_margin']:.4f} "
        f"({full.checks['sampled_offsets']['worst_condition']}).",
        "",
    ]
    lines += bench_problem("manipulators_robust_all_free", "Larger problem",
                           "alpha, beta, link length and mass ratio free", reps)
    lines += bench_problem("stairs_design", "Stairs problem",
                           "{stages} bounces, two worst-case error scenarios", reps)
    Path(args.out).write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
