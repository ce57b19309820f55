"""All multistart points in one IPOPT run: the NLP copied once per start, objectives summed.

The copies share no variable and no row, so the stacked KKT system is block diagonal and each
copy's answer is a KKT point of the original NLP. What they share is IPOPT's per-iteration
overhead, which on these small NLPs grows far more slowly than their size: an iteration of
a 6-stage robust problem costs about 0.2 ms for one copy and 0.7 ms for eight, and its
8 starts take about 11 ms stacked against 23 ms one after another (results/bench_ipopt_cost.md).
They also share the step length and the barrier parameter, so one copy that cannot converge
holds the others back: the stacked run is capped (MAX_ITER) and, unless it succeeds,
the caller solves the starts one by one as before.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from ..lru import Bounded
from .ipopt import Solve, SolverOptions, map_status

# Stacked runs of 8 starts of the shipped problems take 16-28 iterations (one start alone: a
# median of 14-18; results/bench_optimize.md); a run needing many more has a copy in trouble.
MAX_ITER = 100
# Copies per stacked run. Per start, a run of a 6-stage robust problem cost about the same
# from 8 to 64 copies (1.4-1.8 ms), but one of a 20-stage problem cost 4x more at 64 than at
# 32; creating the solver grows with the copies (0.4-0.9 s for 64); and one failing copy sends
# its whole group back to one run per start.
MAX_COPIES = 16


def groups(count: int) -> list[range]:
    """The starts 0..count-1 in consecutive groups of near-equal size, none over MAX_COPIES."""
    parts = -(-count // MAX_COPIES)
    edges = [round(i * count / parts) for i in range(parts + 1)] if count else [0]
    return [range(a, b) for a, b in zip(edges, edges[1:])]


@dataclass(frozen=True)
class StackedSolver:
    solver: object  # nlpsol over the stacked NLP
    objectives: object  # (copies' x as columns, p) -> each copy's own objective
    count: int
    n: int  # variables per copy


_SOLVERS: Bounded = Bounded()
_LOCK = threading.Lock()


def stacked_solver_for(nlp_key: str, nlp: dict, options: SolverOptions,
                       count: int) -> StackedSolver:
    """The stacked solver of `count` copies of one NLP, built once per (NLP, options, count);
    at most MAX_ITER iterations."""
    options = replace(options, max_iter=min(options.max_iter, MAX_ITER))
    key = (nlp_key, options, count)
    with _LOCK:
        stacked = _SOLVERS.get(key)
        if stacked is None:
            stacked = build_stacked(nlp, options, count)
            _SOLVERS[key] = stacked
    return stacked


def build_stacked(nlp: dict, options: SolverOptions, count: int) -> StackedSolver:
    """The stacked solver, built anew (stacked_solver_for caches it)."""
    x, p = nlp["x"], nlp["p"]
    copy = ca.Function("copy", [x, p], [nlp["f"], nlp["g"]])
    xs = ca.SX.sym("x", x.numel(), count)  # column k: copy k's variables
    outs = [copy(xs[:, k], p) for k in range(count)]
    stacked = {"x": ca.vec(xs), "p": p, "f": ca.sum1(ca.vertcat(*(f for f, _ in outs))),
               "g": ca.vertcat(*(g for _, g in outs))}
    return StackedSolver(ca.nlpsol("pdm_stacked", "ipopt", stacked, options.casadi()),
                         ca.Function("f", [x, p], [nlp["f"]]).map(count), count, x.numel())


def solve_stacked(stacked: StackedSolver, x_starts, p, lbx, ubx, lbg, ubg,
                  first: int = 0) -> list[Solve]:
    """One Solve per start (numbered from `first`), all from the one stacked run: each carries
    that run's status, iterations and wall time (they are shared, not per copy)."""
    count, n, m = stacked.count, stacked.n, len(lbg)
    tic = time.perf_counter()
    try:
        sol = stacked.solver(x0=np.concatenate([np.asarray(x0, float) for x0 in x_starts]), p=p,
                             lbx=np.tile(lbx, count), ubx=np.tile(ubx, count),
                             lbg=np.tile(lbg, count), ubg=np.tile(ubg, count))
    except RuntimeError:  # evaluation errors at a start point
        seconds = time.perf_counter() - tic
        return [Solve.evaluation_error(x0, m, seconds, first + i) for i, x0 in enumerate(x_starts)]
    seconds = time.perf_counter() - tic
    stats = stacked.solver.stats()
    ret = stats.get("return_status", "Unknown")
    xs = np.asarray(sol["x"]).reshape(count, n)
    lam_x = np.asarray(sol["lam_x"]).reshape(count, n)
    lam_g = np.asarray(sol["lam_g"]).reshape(count, m)
    objectives = np.asarray(stacked.objectives(xs.T, p)).ravel()
    return [Solve(status=map_status(ret), return_status=ret, x=xs[k],
                  f=float(objectives[k]), lam_x=lam_x[k], lam_g=lam_g[k],
                  iterations=int(stats.get("iter_count", 0)), seconds=seconds, start=first + k)
            for k in range(count)]
