"""Where one IPOPT solve of problems/manipulators_robust.toml spends its time, and what each lever
that could shorten it buys, measured against the SLSQP baseline of bench_optimize.py in the same
run (not a test). Writes results/bench_ipopt_cost.md.

    python results/bench_ipopt_cost.py            # about 15 s
    python results/bench_ipopt_cost.py --quick

The question it answers: why IPOPT is not 5x faster per solve than SLSQP with finite
differences on this 6-variable problem, and what would change that.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import random
import shutil
import statistics
import sys
import time
from collections import Counter
from pathlib import Path
from unittest import mock

import casadi as ca

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pdm_design.formulation import common, formulate  # noqa: E402
from pdm_design.solve import stacked  # noqa: E402
from pdm_design.solve.ipopt import SolverOptions, solve_once, start_designs  # noqa: E402
from pdm_design.spec import load_spec  # noqa: E402

JIT = {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O1"], "verbose": False}}


def _bench_optimize():
    """results/bench_optimize.py as a module (its SLSQP baseline is reused, not rewritten)."""
    spec = importlib.util.spec_from_file_location("bench_optimize",
                                                  ROOT / "results/bench_optimize.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Problem:
    """The built NLP, its parameters and the 8 multistart points optimize uses."""

    def __init__(self, path, *, merge=True):
        """merge=False: the NLP as built before casadi.cse merges repeated subexpressions."""
        self.spec = load_spec(path)
        if merge:
            self.form = formulate(self.spec)
        else:
            with mock.patch.object(common.ca, "cse", lambda expression: expression):
                self.form = formulate(self.spec, cache=False)
        self.p = self.form.parameters(self.spec.requirements)
        names = self.form.design_names
        guess = {n: self.spec.design[n].guess for n in names}
        designs = start_designs(names, [self.spec.design[n].min for n in names],
                                [self.spec.design[n].max for n in names], guess, 8)
        self.starts = [self.form.defined_start(d, guess, self.p) for d in designs]

    def solver(self, extra=None, rows=None):
        """An IPOPT solver on the NLP (optionally only its first `rows` rows)."""
        nlp = dict(self.form.nlp)
        if rows is not None:
            nlp["g"] = nlp["g"][:rows]
        options = SolverOptions().casadi()
        options.update(extra or {})
        return ca.nlpsol("cost", "ipopt", nlp, options)

    def solves(self, solver, repeats, rows=None):
        """`repeats` solves from each start, after one unrecorded pass (first calls are slow)."""
        form = self.form
        lbg, ubg = form.lbg[:rows], form.ubg[:rows]
        runs = [solve_once(solver, x0, self.p, form.lbx, form.ubx, lbg, ubg)
                for _ in range(repeats + 1) for x0 in self.starts]
        return runs[len(self.starts):]


def interleaved(variants, repeats, seed=0):
    """label -> solves, the variants taking turns in a new random order each repeat, so that
    a few percent between them is not the machine's load drifting."""
    rng = random.Random(seed)
    runs = {label: [] for label in variants}
    for _ in range(repeats + 1):  # the first round warms up, unrecorded
        for label in rng.sample(list(variants), len(variants)):
            problem, solver = variants[label]
            runs[label].append(problem.solves(solver, 1))
    return {label: [s for batch in batches[1:] for s in batch]
            for label, batches in runs.items()}


def median_ms(solves):
    return statistics.median(s.seconds for s in solves) * 1e3


def fixed_and_per_iteration(problem, repeats, rows=None):
    """Solve time with IPOPT stopped after 0, 1 and 3 iterations: intercept and slope."""
    times = {k: median_ms(problem.solves(problem.solver({"ipopt.max_iter": k}, rows), repeats,
                                         rows))
             for k in (0, 1, 3)}
    return times[0], (times[3] - times[1]) / 2


def evaluation_share(problem):
    """CasADi's own timers: wall time in the NLP's functions during one solve from each start."""
    solver = problem.solver()
    spent, total = 0.0, 0.0
    for x0 in problem.starts:
        s = solve_once(solver, x0, problem.p, problem.form.lbx, problem.form.ubx,
                       problem.form.lbg, problem.form.ubg)
        stats = solver.stats()
        spent += sum(v for k, v in stats.items() if k.startswith("t_wall_nlp"))
        total += s.seconds
    return spent / len(problem.starts) * 1e3, total / len(problem.starts) * 1e3


def stacked_starts(problem, repeats):
    """The 8 starts as `optimize` solves them, stacked into one NLP (solve/stacked.py), against
    one NLP per start in turn, alternating. Returns the stacked solver's build seconds, then per
    8 starts: stacked and sequential medians (ms), the stacked iterations and status, and the
    worst objective among the copies."""
    form = problem.form
    options = SolverOptions(max_iter=stacked.MAX_ITER)
    tic = time.perf_counter()
    solver = stacked.build_stacked(form.nlp, options, len(problem.starts))
    build = time.perf_counter() - tic
    single = problem.solver()
    together, apart = [], []
    for _ in range(repeats + 1):  # the first round warms up
        copies = stacked.solve_stacked(solver, problem.starts, problem.p, form.lbx, form.ubx,
                                       form.lbg, form.ubg)
        together.append(copies[0].seconds)
        apart.append(sum(solve_once(single, x0, problem.p, form.lbx, form.ubx, form.lbg,
                                    form.ubg).seconds for x0 in problem.starts))
    return (build, statistics.median(together[1:]) * 1e3, statistics.median(apart[1:]) * 1e3,
            copies[0].iterations, copies[0].return_status,
            min(c.x[form.tolerance_index] for c in copies))


def start_statuses(problem, seeds=8):
    """IPOPT's return statuses from seeds x 8 multistart points, each taken as drawn and as
    optimize takes it (moved toward the guess where the closed forms are undefined)."""
    spec, form = problem.spec, problem.form
    names = form.design_names
    guess = {n: spec.design[n].guess for n in names}
    solver = problem.solver()
    counts = {"as drawn": Counter(), "defined_start": Counter()}
    for seed in range(seeds):
        for d in start_designs(names, [spec.design[n].min for n in names],
                               [spec.design[n].max for n in names], guess, 8, seed=seed):
            for label, x0 in (("as drawn", form.start_vector(d)),
                              ("defined_start", form.defined_start(d, guess, problem.p))):
                run = solve_once(solver, x0, problem.p, form.lbx, form.ubx, form.lbg, form.ubg)
                counts[label][run.return_status] += 1
    return counts


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(ROOT / "results/bench_ipopt_cost.md"))
    args = parser.parse_args()
    reps = 3 if args.quick else 10
    load_before = os.getloadavg()[0]
    problem = Problem(ROOT / "problems/manipulators_robust.toml")
    form = problem.form
    bench = _bench_optimize()

    base = problem.solves(problem.solver(), reps)
    iterations = statistics.median(s.iterations for s in base)
    fixed, per_iter = fixed_and_per_iteration(problem, reps)
    fixed8, per_iter8 = fixed_and_per_iteration(problem, reps, rows=8)
    eval_ms, solve_ms = evaluation_share(problem)
    others = [Problem(ROOT / f"problems/{name}.toml")
              for name in ("manipulators_robust_all_free", "stairs_design")]
    statuses = {other.spec.name: start_statuses(other) for other in (problem, *others)}

    unmerged = Problem(ROOT / "problems/manipulators_robust.toml", merge=False)
    variants = {  # label: (problem, solver)
        "IPOPT as shipped (adaptive barrier, MUMPS, SX virtual machine)":
            (problem, problem.solver()),
        "repeated subexpressions not merged (no casadi.cse)": (unmerged, unmerged.solver()),
        "IPOPT's default step checks (residuals, at least one refinement step)":
            (problem, problem.solver({"ipopt.fast_step_computation": "no",
                                      "ipopt.min_refinement_steps": 1})),
        "monotone barrier update (fewer linear solves per iteration)":
            (problem, problem.solver({"ipopt.mu_strategy": "monotone"})),
        "SPRAL instead of MUMPS (the other linear solver in CasADi's IPOPT)":
            (problem, problem.solver({"ipopt.linear_solver": "spral"})),
    }
    jit_note = "no C compiler on this machine: not measured"
    paired = {"as shipped": bench.bench_slsqp(problem.spec, form, problem.starts, reps)}
    if shutil.which("gcc"):
        tic = time.perf_counter()
        jit_solver = problem.solver(JIT)
        compile_s = time.perf_counter() - tic
        variants["functions compiled to C by CasADi's JIT (gcc -O1)"] = (problem, jit_solver)
        jit_note = f"compiling the NLP's functions took {compile_s:.2f} s"
        paired["compiled"] = _paired_compiled(bench, problem, jit_solver, reps)
    rows = list(interleaved(variants, reps).items())
    tol = form.tolerance_index  # the objective in metres (the NLP's f may be scaled)
    stack_build, stacked_ms, apart_ms, stack_iters, stack_status, stack_worst = \
        stacked_starts(problem, reps)
    slsqp_run_ms = paired["as shipped"]["median_run"] * 1e3
    instructions = {label: _instructions(p.form) for label, p in
                    (("merged (as shipped)", problem), ("not merged", unmerged))}
    payback = "without a compiler there is nothing to weigh."
    if shutil.which("gcc"):
        saved = median_ms(rows[0][1]) - median_ms(rows[-1][1])
        payback = (f"the compiler's {compile_s:.2f} s pays back after about "
                   f"{compile_s * 1e3 / saved:.0f} solves of one NLP, and every spec change or "
                   "sweep point is a new NLP." if saved > 0 else "it saved nothing here.")

    lines = [
        "# Where an IPOPT solve's time goes",
        "",
        "Command (from the repository root; regenerates this file):",
        "",
        "    python results/bench_ipopt_cost.py",
        "",
        f"Machine: {platform.machine()}, Python {platform.python_version()}, CasADi "
        f"{ca.__version__}, {reps} repeats of the 8 starts `optimize` uses, load average "
        f"{load_before:.2f} before / {os.getloadavg()[0]:.2f} after on {os.cpu_count()} CPUs. "
        f"Problem: `problems/manipulators_robust.toml`, {len(form.x_names)} variables, "
        f"{len(form.lbg)} rows. Times are medians, wall clock.",
        "",
        "## The cost of one solve",
        "",
        "| quantity | value |",
        "|---|---|",
        f"| one solve as shipped | {median_ms(base):.2f} ms, median {iterations:.0f} iterations |",
        f"| fixed cost per solve (IPOPT stopped before its first iteration) | {fixed:.2f} ms |",
        f"| cost per iteration, all {len(form.lbg)} rows | {per_iter:.3f} ms |",
        f"| cost per iteration, first 8 rows only | {per_iter8:.3f} ms (fixed {fixed8:.2f} ms) |",
        f"| of a solve, time inside the NLP's functions (CasADi's timers) | {eval_ms:.2f} ms of "
        f"{solve_ms:.2f} ms |",
        "",
        "The cost per iteration hardly depends on the number of rows: an iteration costs "
        "IPOPT's and MUMPS' fixed overhead more than this problem's size. At the 8-row cost, "
        f"the median iteration count alone takes {iterations * per_iter8:.2f} ms.",
        "",
        "## Levers",
        "",
        "Each variant takes its turn in a new random order in every repeat (load drift would "
        "swamp differences of a few percent).",
        "",
        "| variant | one solve | iterations | best objective (tolerance, m) |",
        "|---|---|---|---|",
        *(f"| {label} | {median_ms(s):.2f} ms | {statistics.median(x.iterations for x in s):.0f} "
          f"| {max(x.x[tol] for x in s):.10f} |" for label, s in rows),
        "",
        f"JIT: {jit_note}.",
        "",
        "Instructions CasADi's virtual machine runs (f and g; the Hessian of the Lagrangian): "
        + "; ".join(f"{label} {a} and {b}" for label, (a, b) in instructions.items()) + ".",
        "",
        "## The 8 starts as one NLP (as `optimize` solves them)",
        "",
        "`optimize` stacks the starts' copies into one NLP (objectives summed, a block-diagonal "
        "KKT system: `pdm_design/solve/stacked.py`), so IPOPT's per-iteration overhead is paid "
        "once for all of them. Alternating, per 8 starts:",
        "",
        "| way | per 8 starts | IPOPT iterations |",
        "|---|---|---|",
        f"| one NLP per start, in turn | {apart_ms:.1f} ms | {iterations:.0f} (median) each |",
        f"| one stacked NLP, {len(problem.starts)} copies | {stacked_ms:.1f} ms | "
        f"{stack_iters}, {stack_status}; worst copy's tolerance {stack_worst:.10f} m |",
        f"| SLSQP + finite differences, 8 starts in turn | {slsqp_run_ms:.1f} ms | – |",
        "",
        f"Per 8 starts, SLSQP / stacked IPOPT: **{slsqp_run_ms / stacked_ms:.1f}x**. The "
        f"stacked solver takes {stack_build * 1e3:.0f} ms to create (the derivatives of every "
        f"copy), once per spec, against {apart_ms - stacked_ms:.1f} ms saved per solve of the "
        f"8 starts: a one-shot `pdm-design optimize` spends about "
        f"{stack_build * 1e3 - (apart_ms - stacked_ms):.0f} ms more (of about 1.2 s), every "
        "re-solve of the built NLP (new requirements through the API) gains. One copy that "
        "cannot converge holds the "
        "others to its iterations (IPOPT's step length and barrier parameter are shared): the "
        f"stacked run is capped at {stacked.MAX_ITER} iterations, and unless it succeeds "
        "`optimize` solves the starts one by one.",
        "",
        "## Multistart points where the closed forms are undefined",
        "",
        "IPOPT's return statuses from 8 seeds x the 8 points `optimize` draws (a point where "
        "beta < alpha, say, has no handover: IPOPT stops at once), as drawn and moved toward "
        "the guess (`Formulation.defined_start`):",
        "",
        "| problem | starts | statuses |",
        "|---|---|---|",
        *(f"| `{name}` | {label} | {', '.join(f'{k} {v}' for k, v in sorted(c.items()))} |"
          for name, counts in statuses.items() for label, c in counts.items()),
        "",
        "## Against SLSQP with finite differences (paired, same start, alternating)",
        "",
        "| functions both methods evaluate | SLSQP / IPOPT per solve |",
        "|---|---|",
        *(f"| {label} | **{r['paired_ratio']:.1f}x** |" for label, r in paired.items()),
        "",
        "Compiled functions speed IPOPT's derivatives and SLSQP's function calls alike. "
        f"`optimize` does not compile: {payback} HSL's MA27, IPOPT's usual linear solver for "
        "small problems, is "
        "licensed (neither on PyPI nor in Debian), so a tool installed with pip cannot rely on "
        "it.",
        "",
    ]
    Path(args.out).write_text("\n".join(lines))
    print("\n".join(lines))


def _instructions(form):
    """Virtual-machine instructions of f and g, and of the Hessian of the Lagrangian IPOPT uses."""
    x, p = form.nlp["x"], form.nlp["p"]
    fg = ca.Function("fg", [x, p], [form.nlp["f"], form.nlp["g"]])
    hessian = ca.nlpsol("count", "ipopt", form.nlp, SolverOptions().casadi())
    return fg.n_instructions(), hessian.get_function("nlp_hess_l").n_instructions()


def _paired_compiled(bench, problem, jit_solver, reps):
    """bench_slsqp's paired ratio with both methods on compiled functions."""
    form = problem.form
    fg = ca.Function("fg", [form.nlp["x"], form.nlp["p"]], [form.nlp["f"], form.nlp["g"]], JIT)
    return bench.bench_slsqp(problem.spec, form, problem.starts, reps, fg=fg, solver=jit_solver)


if __name__ == "__main__":
    main()
