"""The chain of moments walked call by call and its converged tail in closed form: the cost of
one evaluation independent of the number of stages (docs/optimizer.md section 10, "Cost").

On a uniform row every middle call is one map of the carried state X = (s, R, C, L) and the
same inputs u. Where that map moves some state coordinates T only by a translation (the
middle stage is equivariant in them: they pass through with coefficient 1, nothing else
reads them, and each row is at most quadratic in them), the state splits into X_N, a
recursion of its own (the mean, R's other entries, C, L's other rows: with a contracting
stage, a Stein recursion that converges geometrically), and the drift entries P (s_T, the
T x T block of R, L's T rows), which each call moves by an increment D that is a function
of X_N alone. Once X_N has settled, X_{K+j} = X_K + j D exactly: each later call's rows (mean,
variance) are polynomials of degree 2 in j, fitted through the last three calls walked, and
the last call's state is X_K + (calls - K) D. `_drift` finds T from the middle call's SX
graph (symbolic dependencies, once); `walk` stops walking at the first K where the
per-call change of X_N and of D, relative, is settled: below ROUNDING, or its geometric
bound on everything still to come, e rho / (1 - rho) (rho the larger of its last two decay
ratios), below TOL. The stage map is linear to the step's square near its fixed point, so
the observed rho is the tail's to that order. A row that does not settle is walked to its
end: the answer is the plain chain's in every case, to TOL a call in the tail.
"""

from __future__ import annotations

import itertools

import casadi as ca
import numpy as np

TOL = 1e-14  # the bound on X_N's and D's relative change still to come where a walk stops
# the same for the walk that carries the derivatives (only the gradient and Hessian are read
# from it: 1e-11, about 10 calls fewer where the row contracts by 0.55 a call)
TOL_DERIVATIVES = 1e-11
ROUNDING = 4e-16  # a relative change this small is rounding: settled
FLOOR = 1e-9  # of a block's largest entry: the size an entry near 0 is measured against
MIN_WALK = 4  # calls walked before a stop


def drift_entries(shapes, T) -> list[int]:
    """Indices in the packed state (_pack of s, R, C, L, column-major) of s_T, R_TT, L_T."""
    ns = shapes[0][0]
    at_R, at_C = ns, ns + ns * ns
    at_L = at_C + shapes[2][0] * shapes[2][1]
    nl = shapes[3][1]
    return (list(T) + [at_R + r + c * ns for c in T for r in T]
            + [at_L + r + c * ns for c in range(nl) for r in T])


def _drift(step, shapes):
    """The drift entries P (numpy indices; empty where none) of the middle call `step`
    (state, u) -> (state', rows..): the largest T whose entries pass through (state'[P] -
    state[P] and state'[not P] free of state[P]) and in which every row output is at most
    quadratic."""
    X, U = ca.SX.sym("X", step.size1_in(0)), ca.SX.sym("U", step.size1_in(1))
    after, *rows = step(X, U)
    ns = shapes[0][0]
    for size in range(ns, 0, -1):
        for T in itertools.combinations(range(ns), size):
            P = drift_entries(shapes, T)
            if _passes(X, after, rows, P):
                return np.array(P, dtype=int)
    return np.array([], dtype=int)


def _passes(X, after, rows, P):
    XP = ca.vertcat(*[X[i] for i in P])
    others = [i for i in range(X.numel()) if i not in set(P)]
    moved = ca.vertcat(*[after[i] - X[i] for i in P], *[after[i] for i in others])
    if not _zero(ca.jacobian(moved, XP)):  # (X_P + a) - X_P is no symbol-free expression
        return False
    for o in rows:
        curvature = ca.jacobian(ca.jacobian(o, XP), XP)
        if ca.depends_on(curvature, XP):
            return False
    return True


def _zero(J) -> bool:
    """Whether the SX J is the constant 0 (its entries folded by CasADi's simplification)."""
    return J.nnz() == 0 or (J.is_constant() and not np.any(np.asarray(ca.DM(J))))


def _relative(change, value, blocks):
    """The largest relative change, entry by entry, over the Taylor blocks (an entry below
    FLOOR of its block's largest measured against that floor)."""
    value = np.abs(value).reshape(blocks, -1)
    if value.size == 0:
        return 0.0
    size = np.maximum(value, FLOOR * value.max(axis=1)[:, None])
    change = np.abs(change).reshape(blocks, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = change / size
    ratio[change == 0.0] = 0.0  # no change is settled, whatever its size (0 / 0 too)
    return float(ratio.max())


class _Settling:
    """The per-call change of X_N and of the drift's increment, and whether it has settled."""

    def __init__(self, size, drift, blocks, tol):
        mask = np.zeros(size, bool)
        mask[drift] = True
        self.P, self.N = np.tile(mask, blocks), ~np.tile(mask, blocks)
        self.blocks, self.errors, self.states, self.tol = blocks, [], [], tol

    def settled(self, X) -> bool:
        self.states = (self.states + [X])[-3:]
        if len(self.states) < 3:
            return False
        a, b, c = self.states
        P, N, n = self.P, self.N, self.blocks
        step = _relative(c[N] - b[N], c[N], n) if N.any() else 0.0
        if P.any():
            step = max(step, _relative((c[P] - b[P]) - (b[P] - a[P]), c[P] - b[P], n))
        self.errors.append(step)
        if step <= ROUNDING:
            return True
        if len(self.errors) < 3 or not np.isfinite(step):
            return False
        rho = max(self.errors[-1] / max(self.errors[-2], 1e-300),
                  self.errors[-2] / max(self.errors[-3], 1e-300))
        return rho < 1.0 and step * rho / (1.0 - rho) <= self.tol


def walk(pieces, functions, u, blocks: int, tol: float = TOL):
    """Each output column's rows (g, variance) as arrays (blocks, rows) of the chain `pieces`
    at the numbers u, and the calls walked: the calls walked until the state settles
    (_Settling), the rest of the middle calls on the drift's line (_line) and the last call
    at its end.
    functions: (head, step, tail), pieces' own or their Taylor versions (`blocks` stacked
    coefficients in each input and output)."""
    head, step, tail = functions
    out = head(u)
    X, columns = _flat(out[0]), [[_blocked(o, blocks)] for o in out[1:]]
    middle = pieces.calls - 1
    walked, settling = 0, _Settling(X.size // blocks, pieces.drift, blocks, tol)
    settling.settled(X)
    while walked < middle:
        out = step(X, u)
        before, X = X, _flat(out[0])
        walked += 1
        for column, o in zip(columns, out[1:], strict=True):
            column.append(_blocked(o, blocks))
        if settling.settled(X) and MIN_WALK <= walked < middle:
            break
    left = middle - walked
    if left:
        P = np.tile(np.isin(np.arange(X.size // blocks), pieces.drift), blocks)
        D = np.where(P, X - before, 0.0)
        for column, o in zip(columns, _line(step, X, D, u, left, blocks), strict=True):
            column.append(o)
        X = X + left * D
    if tail is not None:
        for column, o in zip(columns, tail(X, u), strict=True):
            column.append(_blocked(o, blocks))
    return [np.concatenate(column, axis=1) for column in columns], walked


def _line(step, X, D, u, calls, blocks):
    """Each row output of the calls at X + t D, t = 0 .. calls - 1, as (blocks, calls * rows):
    quadratic in t, so interpolated through the calls at t = 0, (calls - 1) / 2 and calls - 1
    (interpolation across the whole line: rounding is not magnified as in an extrapolation)."""
    if calls < 3:
        outs = [[_blocked(o, blocks) for o in step(X + t * D, u)[1:]] for t in range(calls)]
        return [np.concatenate(c, axis=1) for c in zip(*outs, strict=True)]
    h = 0.5 * (calls - 1)
    nodes = [[_blocked(o, blocks) for o in step(X + t * D, u)[1:]] for t in (0.0, h, 2.0 * h)]
    s = np.arange(calls, dtype=float)[:, None, None] / h  # t / h: nodes at 0, 1, 2
    weights = [0.5 * (s - 1.0) * (s - 2.0), s * (2.0 - s), 0.5 * s * (s - 1.0)]
    out = []
    for a, b, c in zip(*nodes, strict=True):
        rows = weights[0] * a[None] + weights[1] * b[None] + weights[2] * c[None]
        out.append(np.transpose(rows, (1, 0, 2)).reshape(a.shape[0], -1))
    return out


def _blocked(o, blocks):
    return np.asarray(o, float).reshape(blocks, -1)


def _flat(o):
    return np.asarray(o, float).ravel()


class Buffered:
    """A Function evaluated through CasADi's numeric buffer (Function.buffer): numpy arrays in
    and out, no DM built a call (the walk's step costs its arithmetic and about as much again
    in conversions otherwise); every output dense, shaped as the Function's. Inputs must be
    dense (the chain's are)."""

    def __init__(self, fn):
        import casadi as ca

        args = [ca.MX.sym(f"i{k}", fn.sparsity_in(k)) for k in range(fn.n_in())]
        self.fn = ca.Function(f"{fn.name()}_buffered", args,
                              [ca.densify(o) for o in fn.call(args)])
        self.ins = [np.zeros(fn.nnz_in(k)) for k in range(fn.n_in())]
        self.outs = [np.zeros(self.fn.nnz_out(k)) for k in range(self.fn.n_out())]
        self.shapes = [self.fn.size_out(k) for k in range(self.fn.n_out())]
        self.buffer, self.trigger = self.fn.buffer()
        for k, a in enumerate(self.ins):
            self.buffer.set_arg(k, memoryview(a))
        for k, o in enumerate(self.outs):
            self.buffer.set_res(k, memoryview(o))

    def __call__(self, *values):
        for a, v in zip(self.ins, values, strict=True):
            a[:] = np.asarray(v, float).ravel()
        self.trigger()
        return [o.reshape(shape, order="F").copy() for o, shape in zip(self.outs, self.shapes)]


def buffered(functions):
    """(head, step, tail) as Buffered, where every input is dense (else as they are)."""
    return tuple(f if f is None or not all(f.sparsity_in(k).is_dense() for k in range(f.n_in()))
                 else Buffered(f) for f in functions)


class Walked(ca.Callback):
    """v -> the bound `reduce` of the walked chain (taylor None), or -> (bound, gradient,
    Hessian) in v (taylor: the moving mask of u's entries, ChainPieces.taylor): `series`
    gives u and its second-order Taylor coefficients in v. Remembers its last answer (the
    NLP's gradient and Hessian at one point share one walk)."""

    def __init__(self, pieces, reduce, series, nv, moving, nu):
        ca.Callback.__init__(self)
        from .chain_moments import _pairs

        self.pieces, self.series, self.nv, self.nu = pieces, series, nv, nu
        self.blocks = 1 if moving is None else 1 + nv + len(_pairs(nv))
        self.functions = buffered((pieces.head, pieces.step, pieces.tail) if moving is None
                                  else pieces.taylor(nv, moving))
        self.reduce = _reducer(reduce, len(pieces.names), nv, self.blocks)
        self.last, self.walked = (None, None), 0
        self.construct(f"chain_walked_{self.blocks}", {})

    def get_n_in(self):
        return 1

    def get_n_out(self):
        return 1 if self.blocks == 1 else 3

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(self.nv, 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(*[(1, 1), (self.nv, 1), (self.nv, self.nv)][i])

    def eval(self, args):
        key = bytes(memoryview(np.ascontiguousarray(args[0].full())))
        found, answer = self.last
        if found != key:
            u = self.series(args[0]).full().ravel()
            if self.blocks == 1:
                u = u[:self.nu]
            columns, self.walked = walk(self.pieces, self.functions, u, self.blocks,
                                        TOL if self.blocks == 1 else TOL_DERIVATIVES)
            answer = self.reduce(*[c.reshape(-1) for c in columns])
            answer = list(answer) if isinstance(answer, (list, tuple)) else [answer]
            self.last = (key, answer)
        return answer


def _reducer(reduce, rows, nv, blocks):
    """Function (g, variance: the blocks' coefficients stacked) -> the bound, or (the bound,
    its gradient, its Hessian) in the Taylor directions."""
    from .chain_moments import VARIANCE_FLOOR, _series

    g, var = ca.MX.sym("g", blocks * rows), ca.MX.sym("variance", blocks * rows)
    if blocks == 1:
        return ca.Function("bound", [g, var], [reduce(g, ca.sqrt(var + VARIANCE_FLOOR))])
    eps = ca.MX.sym("eps", nv)
    split = [[c[k * rows:(k + 1) * rows] for k in range(blocks)] for c in (g, var)]
    gs, vs = (_series(c, eps) for c in split)
    b = reduce(gs, ca.sqrt(vs + VARIANCE_FLOOR))
    grad = ca.jacobian(b, eps)
    at = ca.substitute([b, grad.T, ca.jacobian(grad, eps)], [eps], [ca.DM.zeros(nv)])
    return ca.Function("bound_taylor", [g, var], at)
