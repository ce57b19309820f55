"""Moments of a chain of linearised stage maps and bounds on the probability that a row
fails: the statistical linearisation the scenes' `max_yield` share (each scene's
formulation/statistical.py; docs/optimizer.md section 10).

A row of stages: stage k reads the state s_k (ns numbers), part k's deviations e_k, part
k + 1's e_{k+1} (ne numbers each: every part's independent of every other's) and the lot's
e_lot (nl numbers, one for the whole build), and gives rows g(x, z) >= 0 and the next state,
z = (s, e_k, e_k1, e_lot). Linearised at zero deviation,
    ds_{k+1} = A ds_k + B_k e_k + B_{k+1} e_{k+1} + B_L e_lot,
and ds_k is carried as a rest independent of e_k, the later parts and the lot (covariance R),
a coefficient C on e_k and one L on the lot:
    R' = A R A^T + (A C + B_k) S_e (A C + B_k)^T + Q,   C' = B_{k+1},   L' = A L + B_L,
a row's variance Gs R Gs^T + |(Gs C + G_k) S_e^1/2|^2 + |G_{k+1} S_e^1/2|^2
+ |(Gs L + G_L) S_L^1/2|^2 + its quadratic term's own: exact first-order covariance in
O(stages). Means are second order, g + tr(H Sz) / 2, and Q (and each row's extra variance)
the quadratic terms' own covariance, tr(H_a Sz H_b Sz) / 2 (exact for a quadratic of normal z).

The failure probability: the union bound sum_i Phi(-beta_i) (failure_bound, nines), or
Hunter's bound over each row and its own one call before (tree_nines, log_new_failure), in
logarithms with a tail-accurate log Phi (log_tail).
"""

from __future__ import annotations

import math

import casadi as ca

FAILURE_FLOOR = 1e-300  # the union bound never below this: its logarithm stays finite
VARIANCE_FLOOR = 1e-24  # added to every row's variance: a row no deviation moves has sd 1e-12


def sigmas(tolerances, parts, lots, scale=1.0):
    """(sigma of each part quantity, sigma of each lot quantity) as lists of floats or SX
    (scale: a common factor, a number or a symbol), in the order of `parts` and `lots` (a part's
    quantity toleranced per lot is the lot's `NAME_lot`)."""
    each, lot = [0.0] * len(parts), [0.0] * len(lots)
    for tol in tolerances:
        s = tol.sigma * scale
        if tol.applies_to == "each":
            each[parts.index(tol.quantity)] = s
        elif tol.quantity in parts:
            lot[lots.index(f"{tol.quantity}_lot")] = s
        else:
            lot[lots.index(tol.quantity)] = s
    return each, lot

def linearise(rows, state, x, s, ek, ek1, el):
    """(Function (x, s, Sz) -> (g + tr(H Sz) / 2, dg/dz, tr((H Sz)^2) / 2 of each row[,
    s' + tr(H Sz) / 2, ds'/dz, tr(H_a Sz H_b Sz) / 2 of the state's]), row names) at zero
    deviation, z = (s, ek, ek1, el), Sz the covariance of z. rows: [(name, expression)];
    state: the next state (None for a last stage)."""
    z = ca.vertcat(s, ek, ek1, el)
    Sz = ca.SX.sym("Sz", z.numel(), z.numel())
    outs = []
    names = tuple(name for name, _ in rows)
    rows = ca.vertcat(*[row for _, row in rows])
    for is_state, f in enumerate([rows] + ([state] if state is not None else [])):
        J = ca.jacobian(f, z)
        HS = [ca.jacobian(J[i, :].T, z) @ Sz for i in range(f.numel())]
        mean = ca.vertcat(*[0.5 * ca.trace(h) for h in HS])
        if is_state:  # the covariance of the state's quadratic terms
            n = f.numel()
            spread = ca.blockcat([[0.5 * ca.trace(HS[a] @ HS[b]) for b in range(n)]
                                  for a in range(n)])
        else:
            spread = ca.vertcat(*[0.5 * ca.trace(h @ h) for h in HS])
        outs += [f + mean, J, spread]
    deviations = [ek, ek1, el]
    outs = ca.substitute(outs, deviations, [ca.DM.zeros(v.shape) for v in deviations])
    return ca.Function("stage_linearised", [x, s, Sz], outs), names


def reliability(first, stage, x, calls: int, sigma_each, sigma_lot, neighbours=False):
    """(g, sd, names) of every row: the first stage's (first: (Function, names)), then `calls`
    stages (stage(k): (Function, names) of call k; the last call's state is not used): mean
    values (second order) and standard deviations (first order and the quadratic terms'),
    CasADi expressions of x (DM for a number x). neighbours: also (previous, cross), the index
    of each row's own in the call before when both calls are the same stage map (-1 where not:
    a numpy array) and their first-order covariance (0 where none)."""
    Se = ca.diag(ca.vertcat(*[s**2 for s in sigma_each]))
    Sl = ca.diag(ca.vertcat(*[s**2 for s in sigma_lot]))
    ne, nl = Se.shape[0], Sl.shape[0]
    fn, names = first
    ns = fn.size1_in(1)
    R, C, L = ca.DM.zeros(ns, ns), ca.DM.zeros(ns, ne), ca.DM.zeros(ns, nl)
    g, Gz, q, s, Fz, Q = fn(x, ca.DM.zeros(ns), _covariance(R, C, L, Se, Sl))
    gs, vs, labels = [g], [_variance(Gz, R, C, L, Se, Sl) + q], list(names)
    previous, cross, before = [-1] * len(names), [ca.DM.zeros(len(names))], None
    R, C, L = Q, Fz[:, ns:ns + ne], Fz[:, ns + 2 * ne:]
    for k in range(calls):
        here = stage(k)
        fn, names = here
        Sz = _covariance(R, C, L, Se, Sl)
        out = fn(x, s, Sz)
        g, Gz, q = out[:3]
        if neighbours and before is not None and before[0] is here:
            start = len(labels) - len(names)
            previous += list(range(start, start + len(names)))
            cross.append(_successive(before[1:], Gz, ns, ne))
        else:
            previous += [-1] * len(names)
            cross.append(ca.DM.zeros(len(names)))
        gs.append(g)
        labels += names
        vs.append(_variance(Gz, R, C, L, Se, Sl) + q)
        if k < calls - 1:
            s, Fz, Q = out[3:]
            before = (here, Gz, Sz, Fz)
            A, Bk = Fz[:, :ns], Fz[:, ns:ns + ne]
            Bk1, BL = Fz[:, ns + ne:ns + 2 * ne], Fz[:, ns + 2 * ne:]
            AC = A @ C + Bk
            R = A @ R @ A.T + AC @ Se @ AC.T + Q
            C, L = Bk1, A @ L + BL
    rows = (ca.vertcat(*gs), ca.sqrt(ca.vertcat(*vs) + VARIANCE_FLOOR), tuple(labels))
    if not neighbours:
        return rows
    import numpy as np

    return (*rows, np.array(previous), ca.vertcat(*cross))


def _successive(before, Gz, ns, ne):
    """First-order covariance of each row of a call with the same row of the call before
    (before: that call's row Jacobian G, input covariance Sz and state Jacobian F): the
    later row is Gs F z + G_k e_k1 + G_L e_lot in the earlier call's z = (s, e_k, e_k1,
    e_lot), its e_k being that call's e_k1 (the next part's e_k1 is independent of z)."""
    G0, Sz, F = before
    rows = Gz.shape[0]
    M = Gz[:, :ns] @ F + ca.horzcat(ca.DM.zeros(rows, ns + ne), Gz[:, ns:ns + ne],
                                    Gz[:, ns + 2 * ne:])
    return ca.sum2((G0 @ Sz) * M)


def _covariance(R, C, L, Se, Sl):
    """Covariance of z = (s, e_k, e_k1, e_lot) from the state's parts (R, C on e_k, L on
    the lot)."""
    ns, ne, nl = R.shape[0], Se.shape[0], Sl.shape[0]
    Z = ca.DM.zeros
    Ss = R + C @ Se @ C.T + L @ Sl @ L.T
    CS, LS = C @ Se, L @ Sl
    return ca.blockcat([[Ss, CS, Z(ns, ne), LS],
                        [CS.T, Se, Z(ne, ne), Z(ne, nl)],
                        [Z(ne, ns), Z(ne, ne), Se, Z(ne, nl)],
                        [LS.T, Z(nl, ne), Z(nl, ne), Sl]])


def _variance(Gz, R, C, L, Se, Sl):
    ns, ne = R.shape[0], Se.shape[0]
    Gs, Gk = Gz[:, :ns], Gz[:, ns:ns + ne]
    Gk1, GL = Gz[:, ns + ne:ns + 2 * ne], Gz[:, ns + 2 * ne:]
    return (_quad(Gs, R) + _quad(Gs @ C + Gk, Se) + _quad(Gk1, Se) + _quad(Gs @ L + GL, Sl))


def _quad(G, S):
    """diag(G S G^T) for a symmetric S."""
    return ca.sum2((G @ S) * G)


def failure_bound(g, sd, counted):
    """sum_i Phi(-beta_i) over the rows counted (a 0/1 DM a row), beta_i = g_i / sd_i (a row of
    no spread: 0 if it holds, else 1)."""
    beta = g / sd
    return ca.sum1(counted * 0.5 * (1.0 - ca.erf(beta / math.sqrt(2.0))))  # no erfc in CasADi


def nines(bound):
    """-log10 of the failure bound: 3 for a linearised yield of 99.9 %."""
    return -ca.log10(ca.fmax(bound, FAILURE_FLOOR))


def summary(g, sd, counted) -> dict:
    """The linearised yield of numeric rows (numpy g, sd; counted: a boolean mask): the union
    bound's yield, the failure bound, the smallest reliability index and the row count."""
    import numpy as np
    from scipy.special import ndtr

    with np.errstate(invalid="ignore"):  # a spread that leaves the closed forms: not a number
        beta = g / sd
    bound = float(np.sum(ndtr(-beta[counted])))  # NaN where the spread leaves the closed forms
    return {"yield": max(0.0, 1.0 - bound), "failure_bound": bound,
            "min_beta": float(beta[counted].min()), "rows": int(counted.sum())}


# erfc(x) = t exp(-x^2 + P(t)), t = 1 / (1 + x / 2), x >= 0: a Chebyshev fit of fractional error
# below 1.2e-7 everywhere (Press et al., Numerical Recipes, "erfcc"), so its logarithm is right
# far into the tail, where 1 - erf(x) is 0 in floating point (beta above 8.3)
_ERFC = (-1.26551223, 1.00002368, 0.37409196, 0.09678418, -0.18628806, 0.27886807,
         -1.13520398, 1.48851587, -0.82215223, 0.17087277)


def log_tail(beta):
    """log Phi(-beta) of every element (CasADi), smooth and accurate at any beta: beta >= 0
    from the fit's logarithm, beta < 0 as log(1 - Phi(-|beta|))."""
    x = ca.fabs(beta) / math.sqrt(2.0)
    t = 1.0 / (1.0 + 0.5 * x)
    poly = 0.0
    for c in reversed(_ERFC):
        poly = c + t * poly
    log_upper = ca.log(0.5 * t) - x**2 + poly  # log Phi(-|beta|)
    return ca.if_else(beta >= 0.0, log_upper, ca.log1p(-ca.exp(log_upper)))


# Gauss-Legendre nodes and weights on [0, 1], NODES a panel
NODES = 8


def _legendre():
    import numpy as np

    x, w = np.polynomial.legendre.leggauss(NODES)
    return (x + 1.0) / 2.0, w / 2.0


def log_new_failure(beta_a, beta_b, rho):
    """log P(g_a >= 0, g_b < 0) of two normal rows of reliability indices beta_a, beta_b and
    correlation rho (CasADi vectors, elementwise): the failures of b that a does not already
    have. With Z_b = -beta_b - t, t >= 0,
        P = phi(beta_b) int_0^inf exp(-beta_b t - t^2/2) Phi((beta_a - rho beta_b - rho t)/s) dt,
    s = sqrt(1 - rho^2), summed in logarithms (any tail) by Gauss-Legendre on three panels of
    [0, T]: the last factor is a step of width s / rho at t* = (beta_a - rho beta_b) / rho, which
    the middle panel, t* +- 8 s / rho, holds; T = 12 / (1 + the integrand's decay rate at 0)
    (beyond it the integrand is below about e^-12 of its start), + |beta_b| for beta_b < 0.
    Relative error below 3e-3 against scipy's quad where b holds at its mean (beta_b > 0), 3e-2
    where it fails there, over -1 <= beta <= 8, -0.5 <= rho <= 0.99999 (NODES = 8; 16 gave
    2e-4 everywhere at 1.5 times the cost of an optimisation)."""
    x, w = _legendre()
    rho = ca.fmin(ca.fmax(rho, -1.0 + 1e-9), 1.0 - 1e-9)
    s = ca.sqrt((1.0 - rho) * (1.0 + rho))
    c = (beta_a - rho * beta_b) / s
    # the integrand's decay rate at t = 0: beta_b, and the step's own where it is already
    # far past (c << 0: log Phi falls at about |c| rho / s)
    rate = ca.fmax(beta_b, 0.0) + ca.fmax(-c, 0.0) * ca.fmax(rho, 0.0) / s
    top = 12.0 / (1.0 + rate) + ca.fmax(-beta_b, 0.0)
    lean = ca.fmax(rho, 0.05)  # a step only where rho leans forward; elsewhere smooth
    centre, half = (beta_a - rho * beta_b) / lean, 8.0 * s / lean
    ends = [0.0 * top, ca.fmin(ca.fmax(centre - half, 0.0), top),
            ca.fmin(ca.fmax(centre + half, 0.0), top), top]
    terms = []
    for lo, hi in zip(ends[:-1], ends[1:], strict=True):
        width = ca.fmax(hi - lo, 1e-30 * top)
        for xi, wi in zip(x, w, strict=True):
            t = lo + xi * width
            terms.append(math.log(wi) + ca.log(width) - beta_b * t - 0.5 * t**2
                         + log_tail(rho * t / s - c))
    return -0.5 * beta_b**2 - 0.5 * math.log(2.0 * math.pi) + _logsumexp(terms)


def _logsumexp(terms):
    """log sum_i exp(terms_i), elementwise over vectors of the same length."""
    top = terms[0]
    for term in terms[1:]:
        top = ca.fmax(top, term)
    return top + ca.log(sum(ca.exp(term - top) for term in terms))


def tree_nines(g, sd, previous, cross):
    """-log10 of Hunter's bound on the failure probability: sum_i P(A_i) less, for every row
    with a previous one (the same row one stage before), P(A_prev and A_i), each row's term
    P(A_i and not A_prev) (log_new_failure), summed in logarithms. An upper bound (Hunter 1976:
    the edges form a forest), much below the union bound where the same row fails stage after
    stage (a drift)."""
    import numpy as np

    beta = g / sd
    alone = [int(i) for i in np.flatnonzero(previous < 0)]
    after = [int(i) for i in np.flatnonzero(previous >= 0)]
    logs = [log_tail(beta[alone])]
    if after:
        before = [int(previous[i]) for i in after]
        rho = cross[after] / (sd[before] * sd[after])
        logs.append(log_new_failure(beta[before], beta[after], rho))
    logs = ca.vertcat(*logs)
    top = ca.mmax(logs)
    return -(top + ca.log(ca.sum1(ca.exp(logs - top)))) / math.log(10.0)
