"""One spec, one design: on a flat optimum, the design nearest the spec's initial guess.

An optimum need not be a point. On a 6-stage robust problem with the mass ratio free, no row
that limits the tolerance depends on it: every mass ratio in an interval gives the same
box, and IPOPT stopped wherever its start led it (`optimize` 11.0057, a `table` row warm-started
from its neighbour 10.896, both with a box of 10.3184 mm). So, after the multistart, a second
NLP picks one design of the optimal set, by a rule of the spec alone:

    minimise   sum_i ((x_i - guess_i) / span_i)^2      over the free design variables
    subject to every row of the NLP, and  f(x) <= f* + RELATIVE tol max(|f*|, ABSOLUTE)

(guess: the spec's `initial`, or the middle of the bounds; span: the bounds' width; f* the best
start's objective). The distance is strictly convex, so on a convex optimal set the answer is one
point whichever start found f*, and `optimize`, `table` (whose warm starts are extra starts,
never the guess) and `sheet` give the same design. It costs the optimum at most IPOPT's
tolerance `tol` of its value (1e-8 by default: 1e-9 mm of an 83 mm box; a larger slack, 100 tol,
moved a unique optimum, beta on its slip limit, by 1e-6 rad toward the guess), and the row
f <= cap holds to IPOPT's tolerance (10 tol is accepted). An answer that moves no variable by
more than FLAT of its bounds is a curved optimum's slide along the slack, not a flat set: the
multistart's answer stands then, as it does when the second solve fails (`stats.tie_break_kept`).

The second solve is not run where its answer is known to be the multistart's (`pinned`): where
no design within the tie-break's slack s (the cap's RELATIVE tol max(|f*|, ABSOLUTE) and the
10 tol IPOPT may overstep it by) is FLAT away. With A the gradients of the active rows and
bounds (equality rows, and those with a multiplier), a move d splits into a part off them,
pinv(A) (A d), and one along them, N z (N: A's null space). Off them: each active row i with
multiplier lam_i raises the objective by |lam_i| |A_i d| at first order, so |A_i d| <=
s / |lam_i| (0 for an equality). Along them the objective rises at second order, z' H z / 2
with H the Lagrangian's Hessian on N, so a design variable k moves by at most
sqrt(2 s c' H^+ c), c = N' e_k, if every flat direction of H leaves the design alone (the
landing-speed interval's ends are free on a robust optimum: they move no design variable); a
flat direction that moves the design is a flat optimum, and the tie-break runs. When the sum
of both parts is below a third of FLAT for every free design variable, the tie-break could not
move the design by FLAT: it is skipped (`stats.tie_break_iterations` -1).
"""

from __future__ import annotations

import threading
from dataclasses import replace

import casadi as ca
import numpy as np

from ..lru import Bounded
from ..status import Status
from .ipopt import solve_once, solver_for

RELATIVE = 1.0  # times IPOPT's tol
# A move smaller than this (of any variable's bounds) is no flat optimum: the objective's slack
# lets a curved one slide ~ sqrt(tol) toward the guess (2e-5 rad of an angle on that 6-stage
# robust problem), noise that would differ between scales; it is not kept.
FLAT = 1e-3
ABSOLUTE = 1e-12  # the objective's size when the optimum is 0 (no objective: any design)
_NLPS: Bounded = Bounded()
_LOCK = threading.Lock()


def tie_break_nlp(form) -> dict:
    """The second NLP of a formulation: parameters (p, f cap, guess, span), built once."""
    with _LOCK:
        nlp = _NLPS.get(form.key)
    if nlp is None:
        x, p, f, g = (form.nlp[k] for k in ("x", "p", "f", "g"))
        n = form.n_design
        cap, size = ca.SX.sym("cap"), ca.SX.sym("size")
        guess, span = ca.SX.sym("guess", n), ca.SX.sym("span", n)
        distance = ca.sumsqr((x[:n] - guess) / span)
        # the objective's row relative to its size: IPOPT relaxes a row's bound by 1e-8 of
        # its units (bound_relax_factor), which on an objective of 0.01 was 1e-6 of it
        nlp = {"x": x, "p": ca.vertcat(p, cap, size, guess, span), "f": distance,
               "g": ca.vertcat(g, (cap - f) / size)}
        with _LOCK:
            _NLPS[form.key] = nlp
    return nlp


def nearest_optimum(form, options, chosen, p, guess: dict[str, float], lows, highs):
    """(the run, kept): the design nearest `guess` among those within RELATIVE tol of the best
    objective, solved from the multistart's best run `chosen`; kept unless that solve does not
    succeed or moves no variable by more than FLAT of its bounds (a curved optimum: `chosen` is
    the one). (None, False) without free variables."""
    if form.n_design == 0 or pinned(form, chosen, p, options.tol, lows, highs):
        return None, False
    names = form.design_names
    lo, hi = np.asarray(lows, float), np.asarray(highs, float)
    span = np.where(hi > lo, hi - lo, 1.0)
    g0 = np.array([guess.get(n, 0.5 * (a + b)) for n, a, b in zip(names, lo, hi)])
    size = max(abs(chosen.f), ABSOLUTE)
    cap = chosen.f + RELATIVE * options.tol * size
    # from the optimum, with IPOPT's warm-start options (a small barrier parameter): 4-6
    # iterations where a cold start from it took 11-14
    warm = replace(options, warm=True)
    solver = solver_for(form.key + " nearest optimum", tie_break_nlp(form), warm)
    run = solve_once(solver, chosen.x,
                     np.concatenate([np.asarray(p, float), [cap, size], g0, span]),
                     form.lbx, form.ubx, np.append(form.lbg, 0.0), np.append(form.ubg, np.inf),
                     lam_x0=chosen.lam_x, lam_g0=np.append(chosen.lam_g, 0.0),
                     start=chosen.start)
    if run.status is not Status.OPTIMAL:
        return run, False
    f = float(form_objective(form)(run.x, p))
    if not f <= cap + 10.0 * options.tol * size:  # the row holds to IPOPT's tolerance
        return run, False
    moved = np.max(np.abs(run.x[:form.n_design] - chosen.x[:form.n_design]) / span)
    return run, bool(moved > FLAT)


ACTIVE = 1e-6  # a multiplier above this of the largest marks an active row or bound
FLAT_CURVATURE = 1e-8  # a curvature below this of the Hessian's largest entry is none
_JACOBIANS: Bounded = Bounded()


def pinned(form, run, p, tol: float, lows, highs) -> bool:
    """Whether the tie-break could not move `run`'s design by FLAT of its bounds: the module
    docstring's bound, each free design variable's move under the tie-break's whole slack
    (the cap and IPOPT's tolerance on it) below a third of FLAT."""
    x, lam_g, lam_x = (np.asarray(v, float).ravel() for v in (run.x, run.lam_g, run.lam_x))
    largest = max(np.max(np.abs(lam_g), initial=0.0), np.max(np.abs(lam_x), initial=0.0))
    if not largest > 0.0:
        return False
    jac, hess = _derivatives(form)
    equality = form.lbg == form.ubg
    # active: a multiplier above ACTIVE of the largest, and of the objective (at an interior
    # optimum every multiplier is IPOPT's barrier residue, 1e-11, none of them a row's)
    floor = ACTIVE * max(largest, abs(run.f))
    rows = equality | (np.abs(lam_g) > floor)
    bounds = np.abs(lam_x) > floor
    A = np.vstack([np.asarray(jac(x, p), float)[rows], np.eye(x.size)[bounds],
                   np.zeros((0, x.size))])
    slack = (RELATIVE + 10.0) * tol * max(abs(run.f), ABSOLUTE)
    lam = np.concatenate([np.abs(lam_g[rows]), np.abs(lam_x[bounds])])
    reach = np.where(np.concatenate([equality[rows], np.zeros(bounds.sum(), bool)]), 0.0,
                     slack / np.where(lam > 0.0, lam, np.inf))
    n = form.n_design
    # first order: off the active rows, d = pinv(A) (A d), each |A_i d| <= slack / |lam_i|
    first = np.abs(np.linalg.pinv(A)[:n]) @ reach if A.shape[0] else np.zeros(n)
    # second order: along them, d = N z with z' H z / 2 <= slack (H: the Lagrangian's Hessian
    # on the null space N of A), so |d_k| <= sqrt(2 slack c' H^+ c), c = N' e_k
    if A.shape[0]:
        u, sv, vt = np.linalg.svd(A)
        null = vt[int(np.sum(sv > 1e-9 * sv[0])):].T
    else:  # an interior optimum: every direction is along the (no) active rows
        null = np.eye(x.size)
    second = np.zeros(n)
    if null.shape[1]:
        full = np.asarray(hess(x, p, lam_g), float)
        w, v = np.linalg.eigh(0.5 * (null.T @ (full + full.T) @ null))
        zero = FLAT_CURVATURE * max(np.max(np.abs(full)), 1.0)  # rounding, in H's units
        flat = np.abs(w) <= zero
        if np.any(w < -zero):
            return False  # not a minimum along the rows: no bound
        along = null[:n] @ v  # each design variable's share of each curvature direction
        if np.any(np.abs(along[:, flat]) > 1e-9):
            return False  # a flat direction moves the design
        second = np.sqrt(2.0 * slack * np.sum(along[:, ~flat] ** 2 / w[~flat], axis=1))
    span = np.asarray(highs, float) - np.asarray(lows, float)
    span = np.where(span > 0.0, span, 1.0)
    move = (first + second) / span
    return bool(np.all(np.isfinite(move)) and np.all(move < FLAT / 3.0))


def _derivatives(form):
    """(Jacobian of the rows (x, p), Hessian of the Lagrangian (x, p, lam_g)), cached."""
    with _LOCK:
        found = _JACOBIANS.get(form.key)
    if found is None:
        x, p, f, g = (form.nlp[k] for k in ("x", "p", "f", "g"))
        lam = ca.SX.sym("lam_g", g.numel())
        found = (ca.Function("jac_g", [x, p], [ca.jacobian(g, x)]),
                 ca.Function("hess_l", [x, p, lam], [ca.hessian(f + ca.dot(lam, g), x)[0]]))
        with _LOCK:
            _JACOBIANS[form.key] = found
    return found


_OBJECTIVES: Bounded = Bounded()


def form_objective(form):
    """The NLP's objective as a Function (x, p) (cached per formulation)."""
    fn = _OBJECTIVES.get(form.key)
    if fn is None:
        fn = ca.Function("f", [form.nlp["x"], form.nlp["p"]], [form.nlp["f"]])
        _OBJECTIVES[form.key] = fn
    return fn
