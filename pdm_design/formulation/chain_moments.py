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

The chain is three SX Functions (the first stage, a call that carries the state on, the last
call) with the middle one iterated by mapaccum (ChainPieces): one graph at any number of
stages. In an NLP the scene's bound is one node of the free symbols (second_order_term): its
value the plain chain's, its gradient and Hessian carried along the chain as second-order
Taylor coefficients (docs/optimizer.md section 10, "Cost"); without neighbours the chain is
walked call by call until it settles and its tail added in closed form (chain_tail.py).

The failure probability: the union bound sum_i Phi(-beta_i) (failure_bound, nines; in
logarithms union_nines), or
Hunter's bound over each row and its own one call before (tree_nines, log_new_failure), in
logarithms with a tail-accurate log Phi (log_tail).
"""

from __future__ import annotations

import math

import casadi as ca

FAILURE_FLOOR = 1e-300  # the union bound never below this: its logarithm stays finite
VARIANCE_FLOOR = 1e-24  # added to every row's variance: a row no deviation moves has sd 1e-12
# A row of more calls is walked until it settles, its tail in closed form (chain_tail.py); a
# shorter one is one mapaccum graph (a walk, a Python call a call, could not stop much before
# its end: the long row settles in about 60 calls)
WALKED_FROM = 40


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

def active(values) -> tuple[bool, ...]:
    """Which of the sigmas `values` (numbers or SX) can be other than 0: a deviation of sigma
    0 moves nothing, and the chain leaves it out of z."""
    return tuple(not (isinstance(v, (int, float)) and v == 0.0) for v in values)


def _picked(v, keep):
    """The elements of the SX column v that `keep` marks (all of them when it is None)."""
    if keep is None:
        return v
    return ca.vertcat(ca.SX(0, 1), *[v[i] for i in range(v.numel()) if keep[i]])


def linearise(rows, state, x, s, ek, ek1, el, active_each=None, active_lot=None):
    """(Function (x, s, Sz) -> (g + tr(H Sz) / 2, dg/dz, tr((H Sz)^2) / 2 of each row[,
    s' + tr(H Sz) / 2, ds'/dz, tr(H_a Sz H_b Sz) / 2 of the state's]), row names) at zero
    deviation, z = (s, ek, ek1, el), Sz the covariance of z. rows: [(name, expression)];
    state: the next state (None for a last stage). active_each, active_lot: the part and lot
    deviations z holds (`active`; every one by default), the others 0."""
    z = ca.vertcat(s, _picked(ek, active_each), _picked(ek1, active_each),
                   _picked(el, active_lot))
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
    outs = ca.cse(ca.substitute(outs, deviations, [ca.DM.zeros(v.shape) for v in deviations]))
    return ca.Function("stage_linearised", [x, s, Sz], outs), names


class ChainPieces:
    """A row of stage maps as three SX Functions of u = (x, sigma_each, sigma_lot) (nx, ne,
    nl numbers) and the state carried from call to call (the mean s, R, C, L of the module
    docstring, and with neighbours the call's row Jacobian, input covariance and state
    Jacobian, for the next call's cross terms):
        head(u) -> (state, g, variance[, cross])            the first stage (first)
        step(state, u) -> (state', g, variance[, cross])    calls 0 .. calls - 2 (middle)
        tail(state, u) -> (g, variance[, cross])            the last call (last, or middle)
    g: the rows' means (second order); variance: first order and the quadratic terms'; cross:
    each row's first-order covariance with its own in the call before (0 where none).
    `compose` iterates step with mapaccum: an MX graph of the same size at any number of
    calls, each call one SX Function evaluated once. names: every row's, in order; previous
    (neighbours): the index of each row's own in the call before when both calls are the
    same map, else -1."""

    def __init__(self, first, middle, calls: int, nx: int, ne: int, nl: int, last=None,
                 neighbours: bool = False):
        fn, names = first
        mid, mid_names = middle
        end, end_names = last if last is not None else middle
        self.calls, self.sizes = calls, (nx, ne, nl)
        ns, nr = fn.size1_in(1), len(mid_names)
        nz = ns + 2 * ne + nl
        shapes = [(ns, 1), (ns, ns), (ns, ne), (ns, nl)] + ([(nr, nz), (nz, nz), (ns, nz)]
                                                             if neighbours else [])
        layout = (nx, ne, nl, shapes, neighbours)
        crossed = neighbours and end is mid and calls > 1
        self.head = _call(fn, layout, crossed=False, carries=True, first=True)
        self.step = _call(mid, layout, crossed=neighbours, carries=True) if calls > 1 else None
        self.tail = _call(end, layout, crossed=crossed, carries=False) if calls else None
        self.names = (tuple(names) + tuple(mid_names) * max(calls - 1, 0)
                      + (tuple(end_names) if calls else ()))
        previous = [-1] * (len(names) + (nr if calls > 1 else 0))
        previous += [len(names) + i for i in range(nr * max(calls - 2, 0))]
        if calls:
            at = len(previous)
            previous += list(range(at - nr, at)) if crossed else [-1] * len(end_names)
        self.previous = previous
        self._taylor: dict = {}
        self.shapes = shapes
        # the state's entries that drift (None: the walk is not shortened; _drift)
        self.drift = None
        if not neighbours and calls > WALKED_FROM:
            from .chain_tail import _drift

            self.drift = _drift(self.step, shapes)

    def compose(self, u, pieces=None, blocks: int = 1):
        """[g, variance(, cross)] of every row, MX of the MX column u; with pieces (head,
        step, tail) whose outputs stack `blocks` coefficients of each row (taylor's), each a
        list of those coefficients' vectors."""
        head, step, tail = pieces or (self.head, self.step, self.tail)
        out = head(u)
        state, columns = out[0], [[o] for o in out[1:]]
        if step is not None:
            carried = step.mapaccum("chain", self.calls - 1)(state, u)
            state = carried[0][:, -1]
            for column, o in zip(columns, carried[1:], strict=True):
                column.append(o)
        if tail is not None:
            for column, o in zip(columns, tail(state, u), strict=True):
                column.append(o)
        return [[ca.vertcat(*[ca.vec(_block(o, k, blocks)) for o in column])
                 for k in range(blocks)] for column in columns]

    def rows_function(self):
        """Function (x, sigma_each, sigma_lot) -> (g, sd[, cross]) of every row."""
        args = [ca.MX.sym(n, k) for n, k in zip(("x", "sigma_each", "sigma_lot"), self.sizes)]
        outs = [o[0] for o in self.compose(ca.vertcat(*args))]
        outs[1] = ca.sqrt(outs[1] + VARIANCE_FLOOR)
        return ca.Function("chain_rows", args, outs)

    def taylor(self, nv: int, moving: tuple[bool, ...]):
        """(head, step, tail) carrying every input's, state's and output's second-order Taylor
        coefficients in nv directions (_taylor; moving: the entries of u that depend on the
        directions, the others' derivatives 0), built once per nv and moving."""
        key = (nv, moving)
        if key not in self._taylor:
            self._taylor[key] = tuple(None if f is None else _taylor(f, nv, moving)
                                      for f in (self.head, self.step, self.tail))
        return self._taylor[key]


def _block(o, k, blocks):
    """The k-th of `blocks` equal row blocks of o."""
    n = o.size1() // blocks
    return o[k * n:(k + 1) * n, :]


def _call(fn, layout, crossed, carries, first=False):
    """One call of the stage map fn as an SX Function ([state,] u) -> ([state',] g, variance
    [, cross]): first, the first stage (no state in: its parts 0); crossed, its cross terms
    with the call before (the state's last three parts: _successive), else 0."""
    nx, ne, nl, shapes, neighbours = layout
    ns = shapes[0][0]
    u = ca.SX.sym("u", nx + ne + nl)
    x, se, sl = u[:nx], u[nx:nx + ne], u[nx + ne:]
    state = ca.SX.sym("state", sum(a * b for a, b in shapes))
    s, R, C, L, *before = _unpack(ca.SX.zeros(state.shape) if first else state, shapes)
    Se, Sl = ca.diag(se**2), ca.diag(sl**2)
    Sz = _covariance(R, C, L, Se, Sl)
    g, Gz, q, *more = fn(x, s, Sz)
    outs = [g, _variance(Gz, R, C, L, Se, Sl) + q]
    if neighbours:
        outs.append(_successive(before, Gz, ns, ne) if crossed else ca.SX.zeros(g.shape))
    if carries:
        s1, Fz, Q = more
        A, Bk = Fz[:, :ns], Fz[:, ns:ns + ne]
        Bk1, BL = Fz[:, ns + ne:ns + 2 * ne], Fz[:, ns + 2 * ne:]
        AC = A @ C + Bk
        after = [s1, A @ R @ A.T + AC @ Se @ AC.T + Q, Bk1, A @ L + BL] if not first else \
            [s1, Q, Bk, BL]  # the first stage's e_k is the next call's part
        if neighbours:  # the first stage is no call of the map: nothing crosses with it
            after += [ca.SX.zeros(*shape) for shape in shapes[4:]] if first else [Gz, Sz, Fz]
        outs.insert(0, _pack(after))
    return ca.Function("stage_call", [u] if first else [state, u], ca.cse(outs))


def _taylor(fn, nv, moving):
    """fn (SX, column inputs and outputs, u the last input) on second-order Taylor
    coefficients in nv directions: each input and output the stack [value; d/dv_i (i < nv);
    d2/dv_i dv_j (i <= j)], so that a chain of such calls carries its outputs' first and
    second derivatives in those directions (forward-mode AD, symbolic on one call); the
    derivatives of u's entries not `moving` 0 (fewer terms)."""
    pairs = _pairs(nv)
    blocks = 1 + nv + len(pairs)
    eps = ca.SX.sym("eps", nv)
    ins = [ca.SX.sym(f"in{k}", blocks * fn.size1_in(k)) for k in range(fn.n_in())]
    mask = ca.DM([1.0 if m else 0.0 for m in moving])
    coefficients = [[_block(a, k, blocks) for k in range(blocks)] for a in ins]
    coefficients[-1] = coefficients[-1][:1] + [c * mask for c in coefficients[-1][1:]]
    outs = fn(*[_series(c, eps) for c in coefficients])
    o = ca.vertcat(*outs)  # differentiated together: one graph, its parts shared
    J = ca.jacobian(o, eps)
    parts = ca.substitute([o, *[J[:, i] for i in range(nv)], *_second(J, eps)], [eps],
                          [ca.DM.zeros(nv)])
    stacked, at = [], 0
    for size in (out.size1() for out in outs):
        stacked.append(ca.vertcat(*[q[at:at + size] for q in parts]))
        at += size
    return ca.Function(f"{fn.name()}_taylor", ins, stacked)


def _second(J, v):
    """The second derivatives d2/dv_i dv_j (i <= j, _pairs' order) from the Jacobian J in v:
    each column of J differentiated once."""
    out = []
    for i in range(v.numel()):
        Ji = ca.jacobian(J[:, i], v)
        out += [Ji[:, j] for j in range(i, v.numel())]
    return out


def _pairs(nv):
    return [(i, j) for i in range(nv) for j in range(i, nv)]


def _series(blocks, eps):
    """a_0 + sum_i a_i eps_i + sum_(i<=j) a_ij eps_i eps_j (times 1/2 where i = j) of the
    coefficients blocks = [a_0, a_i.., a_ij..] (SX or MX): its second derivatives at 0 are
    the a_ij."""
    nv = eps.numel()
    out = blocks[0]
    for i in range(nv):
        out = out + blocks[1 + i] * eps[i]
    for k, (i, j) in enumerate(_pairs(nv)):
        out = out + blocks[1 + nv + k] * (eps[i] * eps[j] * (0.5 if i == j else 1.0))
    return out


def second_order_term(pieces: ChainPieces, reduce, args):
    """reduce(g, sd[, cross]) (an MX scalar of every row's mean, sd and cross term: a bound,
    nines) at the SX arguments args = [x, sigma_each, sigma_lot] (expressions of a few free
    symbols v, or numbers: then a DM), as one node of the SX graph at any number of calls:
    its value the plain chain's (ChainPieces.compose), its first and second derivatives in v
    those of one pass carrying second-order Taylor coefficients in v along the chain
    (ChainPieces.taylor), remembered between the NLP's gradient and Hessian at one point."""
    import numpy as np

    u = ca.vertcat(*[ca.vec(ca.SX(a)) for a in args])
    free = ca.symvar(u)
    if not free:
        outs = [o[0] for o in pieces.compose(ca.MX(ca.evalf(u)))]
        return ca.evalf(reduce(outs[0], ca.sqrt(outs[1] + VARIANCE_FLOOR), *outs[2:]))
    v = ca.vertcat(*free)
    nv = v.numel()
    J = ca.jacobian(u, v)
    series = ca.Function("arguments", [v], [ca.vertcat(u, *[J[:, i] for i in range(nv)],
                                                       *_second(J, v))])
    vm, eps = ca.MX.sym("v", nv), ca.MX.sym("eps", nv)
    moving = tuple(bool(n) for n in np.asarray(ca.sum2(ca.DM(J.sparsity(), 1.0))).ravel())
    if pieces.drift is not None:  # walked call by call, the converged tail in closed form
        from .chain_tail import Walked

        plain = Walked(pieces, reduce, series, nv, None, u.numel())
        taylor = Walked(pieces, reduce, series, nv, moving, u.numel())
        _REMEMBERED.extend([plain, taylor])
        return _differentiated(vm, plain(vm), taylor)(v)
    outs = pieces.compose(series(vm), pieces.taylor(nv, moving), 1 + nv + len(_pairs(nv)))
    g, var, *cross = [_series(o, eps) for o in outs]
    b = reduce(g, ca.sqrt(var + VARIANCE_FLOOR), *cross)
    grad = ca.jacobian(b, eps)
    at = ca.substitute([b, grad.T, ca.jacobian(grad, eps)], [eps], [ca.DM.zeros(nv)])
    taylor = _Remembered(ca.Function("chain_taylor", [vm], at))
    _REMEMBERED.append(taylor)  # a Callback lives as long as the Python object does
    plain = [o[0] for o in pieces.compose(series(vm)[:u.numel()])]
    value = reduce(plain[0], ca.sqrt(plain[1] + VARIANCE_FLOOR), *plain[2:])
    return _differentiated(vm, value, taylor)(v)


def _differentiated(v, value, taylor):
    """Function v -> value (MX of the MX symbol v, a scalar) whose first and second
    derivatives are taylor(v)'s gradient and Hessian: its forward and reverse derivatives,
    and theirs, given as such (one direction at a time), so that an SX graph calling it as one
    node evaluates the value alone and its derivative functions the Taylor coefficients."""
    n = v.numel()
    _, G, H = taylor(v)

    def sym(name, size=n):
        return ca.MX.sym(name, size)

    def fn(name, ins, outs, cache=()):
        opts = {"never_inline": True, "max_num_dir": 1, "cache": {f.name(): f for f in cache}}
        return ca.Function(name, [v, *ins.values()], list(outs.values()), ["i0", *ins],
                           list(outs), opts)

    o, a, oa, fa, fo = sym("out_o0", 1), sym("adj_o0", 1), sym("out_adj_i0"), \
        sym("fwd_adj_o0", 1), sym("fwd_out_o0", 1)
    f1, f2, ff, ofo, afo, aa = sym("fwd_i0"), sym("fwd_i0_"), sym("fwd_fwd_i0"), \
        sym("out_fwd_o0", 1), sym("adj_fwd_o0", 1), sym("adj_adj_i0")
    adj = fn("adj1_V", {"out_o0": o, "adj_o0": a}, {"adj_i0": G * a}, [
        fn("fwd1_adj1_V", {"out_o0": o, "adj_o0": a, "out_adj_i0": oa, "fwd_i0": f1,
                           "fwd_out_o0": fo, "fwd_adj_o0": fa},
           {"fwd_adj_i0": H @ f1 * a + G * fa}),
        fn("adj1_adj1_V", {"out_o0": o, "adj_o0": a, "out_adj_i0": oa, "adj_adj_i0": aa},
           {"adj_i0": H @ aa * a, "adj_out_o0": ca.MX(1, 1), "adj_adj_o0": ca.dot(G, aa)})])
    fwd = fn("fwd1_V", {"out_o0": o, "fwd_i0": f1}, {"fwd_o0": ca.dot(G, f1)}, [
        fn("fwd1_fwd1_V", {"out_o0": o, "fwd_i0": f1, "out_fwd_o0": ofo, "fwd_fwd_i0_": f2,
                           "fwd_out_o0": fo, "fwd_fwd_i0": ff},
           {"fwd_fwd_o0": ca.bilin(H, f1, f2) + ca.dot(G, ff)}),
        fn("adj1_fwd1_V", {"out_o0": o, "fwd_i0": f1, "out_fwd_o0": ofo, "adj_fwd_o0": afo},
           {"adj_i0": H @ f1 * afo, "adj_out_o0": ca.MX(1, 1), "adj_fwd_i0": G * afo})])
    return fn("V", {}, {"o0": value}, [fwd, adj])


_REMEMBERED: list = []  # every _Remembered made: an NLP may call it as long as the process runs


class _Remembered(ca.Callback):
    """A Function that remembers its last answer: the NLP's objective, gradient and Hessian,
    evaluated one after the other at the same point, compute the chain once."""

    def __init__(self, fn):
        ca.Callback.__init__(self)
        self.fn, self.last = fn, (None, None)
        self.construct(f"{fn.name()}_remembered", {})

    def get_n_in(self):
        return self.fn.n_in()

    def get_n_out(self):
        return self.fn.n_out()

    def get_sparsity_in(self, i):
        return self.fn.sparsity_in(i)

    def get_sparsity_out(self, i):
        return self.fn.sparsity_out(i)

    def eval(self, args):
        key = tuple(bytes(memoryview(a.full())) for a in args)
        found, answer = self.last
        if found != key:
            answer = self.fn(*args)
            answer = list(answer) if isinstance(answer, (list, tuple)) else [answer]
            self.last = (key, answer)
        return answer


def _pack(parts):
    return ca.vertcat(*[ca.vec(p) for p in parts])


def _unpack(v, shapes):
    """The matrices of `shapes` from the column v (_pack's inverse)."""
    out, at = [], 0
    for rows, cols in shapes:
        out.append(ca.reshape(v[at:at + rows * cols], rows, cols))
        at += rows * cols
    return out


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


EXACT_BELOW = 5.0  # log Phi(-beta) from erf below this beta (1 - erf keeps 10 digits there)


def union_nines(g, sd, counted):
    """-log10 of the union bound sum_i Phi(-beta_i) over the counted rows (a 0/1 DM a row),
    summed in logarithms: each log Phi(-beta_i) from erf where beta_i < EXACT_BELOW (the
    numbers of failure_bound), from log_tail above, where 1 - erf cancels to 0. Its value and
    derivatives stay finite and consistent at any beta: in linear terms a design far inside
    (every beta above 8.3) has a bound of 0 while the bound's derivatives are not, and the
    nines' gradient came out 1e280. A NaN row stays a NaN."""
    import numpy as np

    rows = [int(i) for i in np.flatnonzero(np.asarray(ca.DM(counted)).ravel())]
    beta = (g / sd)[rows]
    # each branch's argument kept in its own range (a NaN stays one: fmin, fmax would drop it)
    near = beta - ca.fmax(beta - EXACT_BELOW, 0.0)
    exact = ca.log(0.5 * (1.0 - ca.erf(near / math.sqrt(2.0))))
    far = log_tail(beta + ca.fmax(EXACT_BELOW - beta, 0.0))
    return nines_of_logs(ca.if_else(beta < EXACT_BELOW, exact, far))


def nines_of_logs(logs):
    """-log10 of sum_i exp(logs_i): the nines of failure probabilities given by their
    logarithms (a log-sum-exp, exact at any size)."""
    top = ca.mmax(logs)
    return -(top + ca.log(ca.sum1(ca.exp(logs - top)))) / math.log(10.0)


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
    return nines_of_logs(ca.vertcat(*logs))
