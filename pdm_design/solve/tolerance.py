"""The convex sub-problem (cvxpy): tolerance regions inside the linearised safe set of offsets.

At a design x*, the scenario conditions G_i(d) = slack_i(x*, d) - r_i scale_i(x*, d) (explicit in
every stage's build errors d: the scene's scenario, Scene.formulate) are linearised at d = 0
with CasADi's Jacobian and normalised by scale_i(x*, 0):  b + A d >= 0.  Then

* square box   max tau         s.t.  b_i - tau ||A_i||_1 >= 0              (an LP)
* axis box     max prod h_g    s.t.  b_i - sum_g h_g sum_{j in g} |A_ij| >= 0
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
import numpy as np

from ..lru import Bounded
from .result import LinearisedTolerance

FULL_ELLIPSOID_MAX_DIM = 24
# Beyond this many offsets the linearised sets cost more than the whole optimisation: the
# axis-aligned ellipsoid took cvxpy 30 s at 400 coordinates, the dense Jacobian 4 GB at 2001.
MAX_COORDINATES = 256
_JAC: Bounded = Bounded()
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


def linearised_tolerance(form, x, p, *, cap: float, length: float) -> LinearisedTolerance:
    """Largest square box, axis box and ellipsoid inside the linearised safe set at x.

    The offsets are solved for in units of `length` (the device's size), so that cvxpy sees the
    same numbers at any scale of the scene (in metres, its exponential cones failed on a device
    ten times the shipped ones); `cap` (m) bounds every half-width. A part
    that cannot be solved is left out, and `status` says which and why.
    """
    sc = form.scenario
    names = sc.offset_names
    if len(names) > MAX_COORDINATES:
        return LinearisedTolerance(0.0, {}, {}, names, status=(
            f"not computed: {len(names)} offset coordinates (more than {MAX_COORDINATES}); the "
            "robust box is the answer"))
    A_all, b_all, keep = linear_safe_set(form, x, p)
    if np.any(b_all < -1e-9):
        return LinearisedTolerance(0.0, {g: 0.0 for g in sc.groups}, {}, names,
                                   status="the nominal design already violates a condition")
    A, b = A_all[keep] * length, np.maximum(b_all[keep], 0.0)
    absA, top = np.abs(A), cap / length
    problems = []
    import cvxpy as cp  # here, not at the top: optimize runs that never get here skip its 0.14 s

    tau, square = cp.Variable(nonneg=True), 0.0
    if _solved(cp.Problem(cp.Maximize(tau), [b - tau * absA.sum(axis=1) >= 0, tau <= top]),
               "square box", problems):
        square = float(tau.value) * length

    groups = list(sc.groups)
    G = np.stack([absA[:, list(sc.groups[g])].sum(axis=1) for g in groups], axis=1)
    h = cp.Variable(len(groups), nonneg=True)
    box = {}
    # the largest area as a geometric mean (second-order cones): its logarithm (exponential
    # cones) failed in Clarabel on a row of 100 stages. The optimum is flat along the
    # binding row, so the box is found to tight tolerances (defaults moved it by 1e-5).
    if _solved(cp.Problem(cp.Maximize(cp.geo_mean(h)), [b - G @ h >= 0, h <= top]),
               "axis box", problems, tight=True):
        box = {g: float(v) * length for g, v in zip(groups, np.atleast_1d(h.value))}

    ellipsoid = _ellipsoid(A, b, names, top, problems)
    if "matrix" in ellipsoid:
        ellipsoid = _scaled(ellipsoid, length)
    return LinearisedTolerance(square, box, ellipsoid, names,
                               status="; ".join(problems) or "optimal")


def _solved(problem, what: str, problems: list[str], tight: bool = False,
            inaccurate: bool = False) -> bool:
    """Solve with Clarabel; False (and a line in `problems`) unless it is optimal (or, with
    `inaccurate`, optimal_inaccurate: the caller makes the point feasible)."""
    import cvxpy as cp

    options = {"tol_gap_abs": 1e-12, "tol_gap_rel": 1e-12, "tol_feas": 1e-12} if tight else {}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            problem.solve(solver=cp.CLARABEL, **options)
    except cp.error.SolverError as exc:
        problems.append(f"{what} not computed: {exc}")
        return False
    if problem.status == cp.OPTIMAL_INACCURATE and inaccurate:
        return True
    if problem.status != cp.OPTIMAL:
        problems.append(f"{what} not computed: cvxpy status {problem.status}")
        return False
    return True


def _scaled(ellipsoid: dict, length: float) -> dict:
    """An ellipsoid found in units of `length`, in metres."""
    out = dict(ellipsoid)
    for key in ("min_semi_axis", "max_semi_axis", "volume_radius"):
        out[key] = ellipsoid[key] * length
    out["extent"] = {k: v * length for k, v in ellipsoid["extent"].items()}
    out["matrix"] = (np.asarray(ellipsoid["matrix"]) * length).tolist()
    return out


def _ellipsoid(A, b, names, cap, problems):
    """Largest-volume ellipsoid {E u : ||u|| <= 1} centred at 0 inside {b + A d >= 0} ({} and a
    line in `problems` when it cannot be found).

    Full shape up to FULL_ELLIPSOID_MAX_DIM coordinates, in the polar form (linear constraints):
    max log det P s.t. c_i' P c_i <= 1 with c_i = A_i / b_i, P = E^2; beyond that an axis-aligned
    ellipsoid (an SOCP: max sum log e_j s.t. ||c_i * e|| <= 1), since cvxpy's log-det cone
    grows too slow for interactive use (about 10 s at 40 coordinates).
    """
    import cvxpy as cp

    n = len(names)
    if np.any(b <= 0):
        problems.append("ellipsoid degenerate: a condition is at its limit at the design itself")
        return {"shape": "none", "min_semi_axis": 0.0, "max_semi_axis": 0.0,
                "volume_radius": 0.0, "extent": {nm: 0.0 for nm in names}, "matrix": []}
    C = A / b[:, None]
    if n <= FULL_ELLIPSOID_MAX_DIM:
        P = cp.Variable((n, n), PSD=True)
        if not _solved(cp.Problem(cp.Maximize(cp.log_det(P)),
                                  [cp.sum(cp.multiply(C @ P, C), axis=1) <= 1,
                                   cp.diag(P) <= cap**2]), "ellipsoid", problems,
                       inaccurate=True):
            return {}
        # Clarabel stops "inaccurate" on some rows of near-parallel constraints (at the same
        # log det to 8 digits as without them): shrunk onto the constraints, any P is inside.
        P_value = 0.5 * (P.value + P.value.T)
        P_value /= max(1.0, float(np.max(np.sum((C @ P_value) * C, axis=1))),
                       float(np.max(np.diag(P_value))) / cap**2)
        w, V = np.linalg.eigh(P_value)
        E = V @ np.diag(np.sqrt(np.clip(w, 0.0, None))) @ V.T
        shape = "full"
    else:
        e = cp.Variable(n, nonneg=True)
        # row i of C diag(e) is C_i * e: broadcast, not an n x n product (memory m n^2)
        rows = cp.multiply(C, cp.reshape(e, (1, n), order="C"))
        if not _solved(cp.Problem(cp.Maximize(cp.sum(cp.log(e))),
                                  [cp.norm(rows, 2, axis=1) <= 1, e <= cap]),
                       "ellipsoid", problems, inaccurate=True):
            return {}
        e_value = np.clip(e.value, 0.0, None)
        e_value /= max(1.0, float(np.max(np.linalg.norm(C * e_value, axis=1))),
                       float(np.max(e_value)) / cap)
        E = np.diag(e_value)
        shape = "axis-aligned"
    axes = np.clip(np.linalg.eigvalsh(E), 0.0, None)
    return {
        "shape": shape,
        "min_semi_axis": float(axes.min()),
        "max_semi_axis": float(axes.max()),
        "volume_radius": float(np.exp(np.mean(np.log(np.maximum(axes, 1e-300))))),
        "extent": {nm: float(np.linalg.norm(E[:, j])) for j, nm in enumerate(names)},
        "matrix": E.tolist(),
    }
