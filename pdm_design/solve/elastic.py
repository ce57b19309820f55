"""Elastic mode: when no design meets every condition, say which cannot be met and by how much.

The elastic NLP keeps the model rows (definitions of auxiliary variables) hard and gives every
physical row i an elastic variable s_i >= 0 (two for an equality), in the row's normalised units:

    g_i(x) + s_i >= 0,        minimise  sum_i s_i      (L1: few rows take the violation)

with the tolerance box and the margin epigraph held at 0 (the nominal design). The rows whose
s_i stay positive are the conditions that cannot be met together; each is reported with the margin
it needs and the margin it reaches at the elastic optimum (the least total violation found from
several starts), in the words of `describe`.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..formulation.common import MODEL
from ..status import Status
from .ipopt import SolverOptions, best, solve_once, solver_for
from .result import Violation
from .words import describe, normalised_margin

VIOLATION_TOL = 1e-6

_ELASTIC: dict[str, tuple] = {}
_LOCK = threading.Lock()


@dataclass(frozen=True)
class Diagnosis:
    total: float  # sum of elastic variables (normalised units); ~0: feasible after all
    x: np.ndarray  # the original decision vector at the elastic optimum
    violations: tuple[Violation, ...]
    at_bounds: tuple[str, ...]  # design variables at a bound in the least-violation design
    status: Status
    iterations: int
    seconds: float


def _elastic_nlp(form):
    """(nlp, lbg, ubg, index of each elastic row) for a formulation, built once."""
    with _LOCK:
        if form.key in _ELASTIC:
            return _ELASTIC[form.key]
    x, p, g = form.nlp["x"], form.nlp["p"], form.nlp["g"]
    rows, lbg, ubg, owners, slacks = [], [], [], [], []
    for info in form.conditions:
        gi = g[info.index]
        if info.kind == MODEL:
            rows.append(gi)
        elif info.equality:
            sp, sm = ca.SX.sym(f"s{info.index}p"), ca.SX.sym(f"s{info.index}m")
            slacks += [sp, sm]
            owners += [info.index, info.index]
            rows.append(gi + sp - sm)
        else:
            s = ca.SX.sym(f"s{info.index}")
            slacks.append(s)
            owners.append(info.index)
            rows.append(gi + s)
        lbg.append(form.lbg[info.index])
        ubg.append(form.ubg[info.index])
    s_vec = ca.vertcat(*slacks)
    nlp = {"x": ca.vertcat(x, s_vec), "p": p, "f": ca.sum1(s_vec), "g": ca.vertcat(*rows)}
    g_of = ca.Function("g", [x, p], [g])
    built = (nlp, np.array(lbg), np.array(ubg), tuple(owners), g_of)
    with _LOCK:
        _ELASTIC[form.key] = built
    return built


def diagnose(form, p, starts: list[np.ndarray], *, max_iter: int = 500) -> Diagnosis:
    """Solve the elastic NLP from each start vector; report the violated conditions."""
    nlp, lbg, ubg, owners, g_of = _elastic_nlp(form)
    solver = solver_for("elastic:" + form.key, nlp, SolverOptions(max_iter=max_iter))
    n_x, n_s = len(form.lbx), len(owners)
    lbx = np.concatenate([form.lbx, np.zeros(n_s)])
    ubx = np.concatenate([form.ubx, np.full(n_s, math.inf)])
    for idx in (form.tolerance_index, form.margin_index):
        if idx is not None:
            lbx[idx] = ubx[idx] = 0.0
    runs = []
    for i, x0 in enumerate(starts):
        x0 = np.array(x0, dtype=float)
        for idx in (form.tolerance_index, form.margin_index):
            if idx is not None:
                x0[idx] = 0.0
        g0 = np.nan_to_num(np.asarray(g_of(x0, p)).ravel(), nan=1.0)
        s0 = np.array([max(0.0, -g0[j]) + 1e-3 for j in owners])
        runs.append(solve_once(solver, np.concatenate([x0, s0]), p, lbx, ubx, lbg, ubg, start=i))
    run = best(runs)
    x = run.x[:n_x]
    slack_values = run.x[n_x:]
    per_row: dict[int, float] = {}
    for owner, value in zip(owners, slack_values):
        per_row[owner] = per_row.get(owner, 0.0) + float(value)
    sl, sc, _, _ = form.evaluate(x, p)
    sl, sc = np.asarray(sl).ravel(), np.asarray(sc).ravel()
    violations = []
    for info in form.conditions:
        if per_row.get(info.index, 0.0) <= VIOLATION_TOL:
            continue
        required = form.requirement(info, p)
        achieved = normalised_margin(sl[info.index], sc[info.index])
        violations.append(Violation(
            name=info.name, where=info.where, required=float(required),
            achieved=float(achieved), equality=info.equality,
            text=describe(info.name, info.where, float(required), float(achieved),
                          equality=info.equality, value=float(sl[info.index]),
                          kind=form.kind),
        ))
    violations.sort(key=lambda v: v.achieved - v.required)
    at_bounds = []
    for i, name in enumerate(form.design_names):
        lo, hi = form.lbx[i], form.ubx[i]
        span = max(hi - lo, 1e-12)
        if x[i] - lo <= 1e-6 * span:
            at_bounds.append(f"{name} at its lower bound {lo:g}")
        elif hi - x[i] <= 1e-6 * span:
            at_bounds.append(f"{name} at its upper bound {hi:g}")
    total = float(sum(per_row.values()))
    return Diagnosis(total, x, tuple(violations), tuple(at_bounds), run.status,
                     sum(r.iterations for r in runs), sum(r.seconds for r in runs))
