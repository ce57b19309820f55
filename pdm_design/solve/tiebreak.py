"""One spec, one design: on a flat optimum, the design nearest the spec's initial guess.

An optimum need not be a point. On `problems/manipulators_robust.toml` with the mass ratio free,
no row that limits the tolerance depends on it: every mass ratio in an interval gives the same
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
f <= cap holds to IPOPT's tolerance (10 tol is accepted). An answer that moves no variable by more than FLAT of its
bounds is a curved optimum's slide along the slack, not a flat set: the multistart's answer
stands then, as it does when the second solve fails (`stats.tie_break_kept`).
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
# lets a curved one slide ~ sqrt(tol) toward the guess (2e-5 rad of alpha on
# problems/manipulators_robust.toml), noise that would differ between scales; it is not kept.
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
    if form.n_design == 0:
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
    run = solve_once(solver, chosen.x, np.concatenate([np.asarray(p, float), [cap, size], g0, span]),
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


_OBJECTIVES: Bounded = Bounded()


def form_objective(form):
    """The NLP's objective as a Function (x, p) (cached per formulation)."""
    fn = _OBJECTIVES.get(form.key)
    if fn is None:
        fn = ca.Function("f", [form.nlp["x"], form.nlp["p"]], [form.nlp["f"]])
        _OBJECTIVES[form.key] = fn
    return fn
