"""IPOPT through CasADi: one solver per formulation and options (cached), multistart, warm start,
and the map from IPOPT's return status to our Status vocabulary."""

from __future__ import annotations

import functools
import threading
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..lru import Bounded
from ..status import Status

_STATUS = {
    "Solve_Succeeded": Status.OPTIMAL,
    "Solved_To_Acceptable_Level": Status.ACCEPTABLE,
    "Maximum_Iterations_Exceeded": Status.ITERATION_LIMIT,
    "Infeasible_Problem_Detected": Status.INFEASIBLE,
}
_RANK = {Status.OPTIMAL: 0, Status.ACCEPTABLE: 1, Status.ITERATION_LIMIT: 2,
         Status.INFEASIBLE: 3, Status.SOLVER_ERROR: 4}


def map_status(return_status: str) -> Status:
    """IPOPT's return_status -> Status. Only Solve_Succeeded is OPTIMAL."""
    return _STATUS.get(return_status, Status.SOLVER_ERROR)


@dataclass(frozen=True)
class SolverOptions:
    max_iter: int = 500
    tol: float = 1e-8
    acceptable_tol: float = 1e-6
    warm: bool = False
    # IPOPT relaxes every bound by this much; at its default 1e-8 the optimum sits ~1e-8 off
    # whatever tol is (results/accuracy.md), so the precise preset sets it to 0.
    bound_relax_factor: float = 1e-8

    def casadi(self) -> dict:
        opts = {
            "print_time": False,
            "show_eval_warnings": False,
            "calc_lam_p": False,
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "ipopt.max_iter": self.max_iter,
            "ipopt.tol": self.tol,
            "ipopt.acceptable_tol": self.acceptable_tol,
            "ipopt.mu_strategy": "adaptive",
            "ipopt.bound_relax_factor": self.bound_relax_factor,
            # MUMPS' own scaling costs ~20 % of a solve on these small, well-scaled KKT systems;
            # so do the residual checks and iterative refinement of each step: 14 % less time,
            # the same iterations, statuses and optima on every shipped problem from 64 starts
            # (results/bench_ipopt_cost.md).
            "ipopt.mumps_scaling": 0,
            "ipopt.mumps_permuting_scaling": 0,
            "ipopt.fast_step_computation": "yes",
            "ipopt.min_refinement_steps": 0,
        }
        if self.warm:
            opts.update({"ipopt.warm_start_init_point": "yes",
                         "ipopt.warm_start_bound_push": 1e-9,
                         "ipopt.warm_start_mult_bound_push": 1e-9,
                         "ipopt.mu_init": 1e-6})
        return opts


@dataclass(frozen=True)
class Solve:
    """One IPOPT run."""

    status: Status
    return_status: str
    x: np.ndarray
    f: float
    lam_x: np.ndarray
    lam_g: np.ndarray
    iterations: int
    seconds: float
    start: int

    @classmethod
    def evaluation_error(cls, x0, rows: int, seconds: float, start: int) -> Solve:
        """A run CasADi refused at its start point (an evaluation error raised, not returned)."""
        x0 = np.asarray(x0, float)
        return cls(Status.SOLVER_ERROR, "Evaluation_Error", x0, np.inf, np.zeros(len(x0)),
                   np.zeros(rows), 0, seconds, start)


_SOLVERS: Bounded = Bounded()
_LOCK = threading.Lock()


def solver_for(nlp_key: str, nlp: dict, options: SolverOptions):
    """casadi nlpsol for one NLP and options, built once and cached."""
    key = (nlp_key, options)
    with _LOCK:
        solver = _SOLVERS.get(key)
        if solver is None:
            solver = ca.nlpsol("pdm", "ipopt", nlp, options.casadi())
            _SOLVERS[key] = solver
    return solver


def solve_once(solver, x0, p, lbx, ubx, lbg, ubg, *, lam_x0=None, lam_g0=None, start=0) -> Solve:
    args = dict(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    if lam_x0 is not None:
        args.update(lam_x0=lam_x0, lam_g0=lam_g0)
    tic = time.perf_counter()
    try:
        sol = solver(**args)
    except RuntimeError:  # evaluation errors at the start point
        return Solve.evaluation_error(x0, len(lbg), time.perf_counter() - tic, start)
    seconds = time.perf_counter() - tic
    stats = solver.stats()
    ret = stats.get("return_status", "Unknown")
    return Solve(
        status=map_status(ret), return_status=ret,
        x=np.asarray(sol["x"]).ravel(), f=float(sol["f"]),
        lam_x=np.asarray(sol["lam_x"]).ravel(), lam_g=np.asarray(sol["lam_g"]).ravel(),
        iterations=int(stats.get("iter_count", 0)), seconds=seconds, start=start,
    )


# Bounds spanning more than this ratio (both ends positive) are sampled evenly in their logarithm:
# evenly in [1e-6, 1e6] m, 7 of 8 link lengths fell above 1e5 m and every start failed.
LOG_SPAN = 100.0


def start_designs(names, lows, highs, guess, count: int, seed: int = 0) -> list[dict]:
    """The spec's guess, then scrambled-Sobol points in the bounds box (count in all)."""
    starts = [dict(guess)]
    n = len(names)
    if count <= 1 or n == 0:
        return starts[: max(count, 1)]
    for row in _sobol(n, count - 1, seed):
        starts.append({nm: _within(lo, hi, r) for nm, lo, hi, r in zip(names, lows, highs, row)})
    return starts


def _within(lo: float, hi: float, r: float) -> float:
    """The point a fraction r of the way from lo to hi (of the way in log scale for wide bounds)."""
    if lo > 0.0 and hi > LOG_SPAN * lo:
        return float(min(max(lo * (hi / lo) ** r, lo), hi))
    return float(lo + r * (hi - lo))


@functools.lru_cache(maxsize=64)
def _sobol(dimension: int, count: int, seed: int) -> np.ndarray:
    """count scrambled-Sobol points in the unit cube (cached: drawing them took 0.4 ms, 4 % of
    an 8-start optimize of a 6-stage robust problem). solve/sobol.py draws scipy's
    points without importing scipy.stats (0.4 s)."""
    from .sobol import sobol

    points = sobol(dimension, _pow2(count), seed)[:count]
    points.flags.writeable = False
    return points


def _pow2(n: int) -> int:
    k = 1
    while k < n:
        k *= 2
    return k


TIE = 1e-9  # objectives this close (relative) are one optimum


def best(solves: list[Solve]) -> Solve:
    """The best run: best status first (optimal < acceptable < ...), then least objective; of
    runs that reach the least objective to TIE, the first (a warm start's, else the spec's
    guess'): which one IPOPT's last digits favour is noise (solve/tiebreak.py then settles a
    flat optimum)."""
    def f(s):
        return s.f if np.isfinite(s.f) else np.inf

    top = min(solves, key=lambda s: (_RANK[s.status], f(s)))
    near = TIE * max(1.0, abs(f(top))) if np.isfinite(f(top)) else 0.0
    return next(s for s in solves if s.status is top.status and f(s) <= f(top) + near)
