"""The convex sub-problem (cvxpy): tolerance regions inside the linearised safe set of offsets.

At a design x*, the scenario conditions G_i(d) = slack_i(x*, d) - r_i scale_i(x*, d) (explicit in
every manipulator's offset or every step's errors d, formulation/*_offsets.py) are linearised at
d = 0 with CasADi's Jacobian and normalised by scale_i(x*, 0):  b + A d >= 0.  Then

* square box   max tau         s.t.  b_i - tau ||A_i||_1 >= 0              (an LP)
* axis box     max sum log h_g s.t.  b_i - sum_g h_g sum_{j in g} |A_ij| >= 0
* ellipsoid    max log det E   s.t.  ||E A_i||_2 <= b_i,  E symmetric PSD  (centred at 0),
               solved in its polar form (see `_ellipsoid`)

A box {|d_j| <= h_j} lies in {b + A d >= 0} iff b_i - sum_j h_j |A_ij| >= 0 for every row (the
worst corner of each row); an ellipsoid {E u : ||u|| <= 1} iff b_i - ||E A_i|| >= 0. These are the
first-order answers: not sound for the nonlinear conditions, reported next to the NLP's robust box
(which is sound) to show how much the worst-case bounds cost.
"""

from __future__ import annotations

import threading
import warnings

import casadi as ca
import cvxpy as cp
import numpy as np

from .result import LinearisedTolerance

FULL_ELLIPSOID_MAX_DIM = 24
_JAC: dict[str, object] = {}
_LOCK = threading.Lock()


def _jacobian_function(form):
    with _LOCK:
        fn = _JAC.get(form.key)
    if fn is None:
        sc = form.scenario
        x = ca.SX.sym("x", len(form.lbx))
        d = ca.SX.sym("d", len(sc.offset_names))
        slack, scale = sc.function(x, d)
        fn = ca.Function("lin", [x, d], [slack, scale, ca.jacobian(slack, d),
                                         ca.jacobian(scale, d)])
        with _LOCK:
            _JAC[form.key] = fn
    return fn


def linear_safe_set(form, x, p):
    """(A, b, kept rows) of the linearised, normalised safe set b + A d >= 0 at design x."""
    sc = form.scenario
    n = len(sc.offset_names)
    slack, scale, js, jsc = (np.asarray(v, dtype=float) for v in _jacobian_function(form)(
        x, np.zeros(n)))
    slack, scale = slack.ravel(), scale.ravel()
    required = dict(zip(form.p_names, np.asarray(p, dtype=float).ravel()))
    r = np.array([max((required.get(k, 0.0) for k in info.keys), default=0.0)
                  if info.kind == "margin" else 0.0 for info in sc.conditions])
    G0 = slack - r * scale
    J = js - r[:, None] * jsc
    norm = np.where(np.abs(scale) > 1e-12, np.abs(scale), 1.0)
    b, A = G0 / norm, J / norm[:, None]
    keep = np.flatnonzero(np.abs(A).sum(axis=1) > 1e-12)
    return A, b, keep


def linearised_tolerance(form, x, p, *, cap: float) -> LinearisedTolerance:
    """Largest square box, axis box and ellipsoid inside the linearised safe set at x."""
    sc = form.scenario
    names = sc.offset_names
    A_all, b_all, keep = linear_safe_set(form, x, p)
    if np.any(b_all < -1e-9):
        return LinearisedTolerance(0.0, {g: 0.0 for g in sc.groups}, {}, names,
                                   status="the nominal design already violates a condition")
    A, b = A_all[keep], np.maximum(b_all[keep], 0.0)
    absA = np.abs(A)

    tau = cp.Variable(nonneg=True)
    cp.Problem(cp.Maximize(tau), [b - tau * absA.sum(axis=1) >= 0, tau <= cap]).solve(
        solver=cp.CLARABEL)
    square = float(tau.value)

    groups = list(sc.groups)
    G = np.stack([absA[:, list(sc.groups[g])].sum(axis=1) for g in groups], axis=1)
    h = cp.Variable(len(groups), nonneg=True)
    cp.Problem(cp.Maximize(cp.sum(cp.log(h))), [b - G @ h >= 0, h <= cap]).solve(
        solver=cp.CLARABEL)
    box = {g: float(v) for g, v in zip(groups, np.atleast_1d(h.value))}

    ellipsoid, status = _ellipsoid(A, b, names, cap)
    return LinearisedTolerance(square, box, ellipsoid, names, status=status)


def _ellipsoid(A, b, names, cap):
    """Largest-volume ellipsoid {E u : ||u|| <= 1} centred at 0 inside {b + A d >= 0}.

    Full shape up to FULL_ELLIPSOID_MAX_DIM coordinates, in the polar form (linear constraints):
    max log det P s.t. c_i' P c_i <= 1 with c_i = A_i / b_i, P = E^2; beyond that an axis-aligned
    ellipsoid (an SOCP: max sum log e_j s.t. ||diag(e) A_i|| <= b_i), since cvxpy's log-det cone
    grows too slow for interactive use (about 10 s at 40 coordinates).
    """
    n = len(names)
    if np.any(b <= 0):
        return {"shape": "none", "min_semi_axis": 0.0, "max_semi_axis": 0.0,
                "volume_radius": 0.0, "extent": {nm: 0.0 for nm in names}}, "degenerate"
    C = A / b[:, None]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if n <= FULL_ELLIPSOID_MAX_DIM:
            P = cp.Variable((n, n), PSD=True)
            prob = cp.Problem(cp.Maximize(cp.log_det(P)),
                              [cp.sum(cp.multiply(C @ P, C), axis=1) <= 1, cp.diag(P) <= cap**2])
            prob.solve(solver=cp.CLARABEL)
            if P.value is None:
                return {}, prob.status
            w, V = np.linalg.eigh(0.5 * (P.value + P.value.T))
            E = V @ np.diag(np.sqrt(np.clip(w, 0.0, None))) @ V.T
            shape = "full"
        else:
            e = cp.Variable(n, nonneg=True)
            prob = cp.Problem(cp.Maximize(cp.sum(cp.log(e))),
                              [cp.norm(C @ cp.diag(e), 2, axis=1) <= 1, e <= cap])
            prob.solve(solver=cp.CLARABEL)
            if e.value is None:
                return {}, prob.status
            E = np.diag(e.value)
            shape = "axis-aligned"
    axes = np.clip(np.linalg.eigvalsh(E), 0.0, None)
    return {
        "shape": shape,
        "min_semi_axis": float(axes.min()),
        "max_semi_axis": float(axes.max()),
        "volume_radius": float(np.exp(np.mean(np.log(np.maximum(axes, 1e-300))))),
        "extent": {nm: float(np.linalg.norm(E[:, j])) for j, nm in enumerate(names)},
        "matrix": E.tolist(),
    }, prob.status
