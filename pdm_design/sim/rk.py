"""Explicit Runge-Kutta integration with events, for the small systems of an event simulator,
in plain Python floats.

A port of scipy.integrate.solve_ivp with method "RK45" or "DOP853", no t_eval, and events
(scipy/integrate/_ivp/ivp.py, rk.py, common.py, scipy 1.17): the same coefficients (read from
scipy), the same initial step, step-size control, error norms, dense output and event location
(Brent's method on the dense output to 4 machine epsilons, sim.numerics.brentq being a
line-by-line port of scipy's). Where scipy sums with numpy (a dot product, a norm), the sums
here run term by term in order: the same steps and events up to rounding. For a system of four
or six states scipy's per-step overhead (arrays of a few numbers, validation, wrappers) is most
of the time; here a step costs its right-hand sides and little more.
"""

from __future__ import annotations

import math
from functools import cache

from .numerics import brentq

EPS = 2.220446049250313e-16
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0  # scipy's (rk.py)
TOO_SMALL_STEP = "Required step size is less than spacing between numbers."
MESSAGES = {0: "The solver successfully reached the end of the integration interval.",
            1: "A termination event occurred."}


def _rows(matrix, count):
    """[(j, a_j) for the nonzero a_j of a row] of the first `count` columns, row by row."""
    return tuple(tuple((j, float(a)) for j, a in enumerate(row[:count]) if a != 0.0)
                 for row in matrix)


@cache
def tableau(method: str) -> dict:
    """scipy's Butcher tableau of `method`, as tuples of floats (nonzero terms only)."""
    from scipy.integrate._ivp import rk

    if method == "RK45":
        m = rk.RK45
        return {"stages": m.n_stages, "order": m.error_estimator_order,
                "A": _rows(m.A, m.n_stages), "C": tuple(map(float, m.C)),
                "B": tuple(enumerate(map(float, m.B))), "E": tuple(enumerate(map(float, m.E))),
                "P": tuple(tuple(map(float, row)) for row in m.P)}
    if method == "DOP853":
        from scipy.integrate._ivp import dop853_coefficients as d

        m, s = rk.DOP853, rk.DOP853.n_stages
        return {"stages": s, "order": m.error_estimator_order,
                "A": _rows(m.A, s), "C": tuple(map(float, m.C)),
                "B": tuple(enumerate(map(float, m.B))),
                "E3": tuple(enumerate(map(float, m.E3))),
                "E5": tuple(enumerate(map(float, m.E5))),
                "A_EXTRA": _rows(d.A[s + 1:], d.N_STAGES_EXTENDED),
                "C_EXTRA": tuple(map(float, d.C[s + 1:])),
                "D": _rows(d.D, d.N_STAGES_EXTENDED)}
    raise ValueError(f"method must be RK45 or DOP853, got {method!r}")


@cache
def _stepper(method: str, n: int):
    """rk_step for `n` states written out term by term (tableau's nonzero terms, in order):
    step(fun, t, y, f, h) -> (y_new, f_new, K). Each sum runs left to right."""
    tab = tableau(method)
    lines = ["def step(fun, t, y, f, h):", "    k0 = f"]

    def combo(row, i):
        return " + ".join(f"k{j}[{i}] * {a!r}" for j, a in row) or "0.0"

    for s in range(1, tab["stages"]):
        ys = ", ".join(f"y[{i}] + ({combo(tab['A'][s], i)}) * h" for i in range(n))
        lines.append(f"    k{s} = fun(t + {tab['C'][s]!r} * h, [{ys}])")
    ys = ", ".join(f"y[{i}] + h * ({combo(tab['B'], i)})" for i in range(n))
    lines.append(f"    y_new = [{ys}]")
    lines.append("    f_new = [float(v) for v in fun(t + h, y_new)]")
    ks = ", ".join(f"k{s}" for s in range(tab["stages"]))
    lines.append(f"    return y_new, f_new, [{ks}, f_new]")
    # the error estimate's sums over the stages, component by component: (E5 . K, E3 . K) for
    # DOP853, (E . K,) for RK45
    lines.append("def errors(K):")
    lines.append("    " + ", ".join(f"k{s}" for s in range(tab["stages"] + 1)) + " = K")
    sums = [", ".join(f"{combo(tab[e], i)}" for i in range(n))
            for e in (("E5", "E3") if method == "DOP853" else ("E",))]
    lines.append("    return " + ", ".join(f"[{x}]" for x in sums) + ",")
    if method == "DOP853":  # the dense output's extra stages and F[3:] = h D . K
        first = tab["stages"] + 1
        lines.append("def extra(fun, t_old, y_old, h, K):")
        lines.append("    " + ", ".join(f"k{s}" for s in range(first)) + " = K")
        for s, (row, c) in enumerate(zip(tab["A_EXTRA"], tab["C_EXTRA"]), start=first):
            ys = ", ".join(f"y_old[{i}] + ({combo(row, i)}) * h" for i in range(n))
            lines.append(f"    k{s} = fun(t_old + {c!r} * h, [{ys}])")
        rows = ", ".join("[" + ", ".join(f"h * ({combo(row, i)})" for i in range(n)) + "]"
                         for row in tab["D"])
        lines.append(f"    return [{rows}]")
    scope: dict = {}
    exec("\n".join(lines), scope)  # source made above from the tableau's floats
    return scope["step"], scope["errors"], scope.get("extra")


def _norm(values) -> float:
    """RMS norm (common.norm: numpy's 2-norm over the square root of the size)."""
    return math.sqrt(sum(v * v for v in values)) / len(values) ** 0.5


class Interpolant:
    """Dense output of one step (t_old, t]: scipy's RkDenseOutput or Dop853DenseOutput, the
    coefficients held component by component."""

    __slots__ = ("t_old", "t", "h", "columns", "kind")

    def __init__(self, t_old, t, y_old, F, kind):
        self.t_old, self.t, self.h, self.kind = t_old, t, t - t_old, kind
        if kind == "DOP853":  # (F6, F5, ..., F0, y_old) of each component
            self.columns = tuple(zip(*reversed(F), y_old))
        elif kind == "RK45":  # (Q_i0, .., Q_i3, y_old_i)
            self.columns = tuple((*row, y0) for row, y0 in zip(F, y_old))
        else:
            self.columns = tuple(F)

    def __call__(self, t):
        if self.kind == "constant":
            return list(self.columns)
        x = (t - self.t_old) / self.h
        if self.kind == "DOP853":  # y = 0; y = (y + F_r) (x or 1 - x) from F6 down to F0
            u = 1 - x
            return [(((((((f6 * x + f5) * u + f4) * x + f3) * u + f2) * x + f1) * u + f0) * x
                     + y0) for f6, f5, f4, f3, f2, f1, f0, y0 in self.columns]
        x2 = x * x
        x3 = x2 * x
        x4 = x3 * x
        h = self.h
        return [h * (q0 * x + q1 * x2 + q2 * x3 + q3 * x4) + y0
                for q0, q1, q2, q3, y0 in self.columns]


class Solution:
    """What solve returns: scipy's OdeResult fields that the simulators read (t and y: the last
    point only), and sol(t) over the steps when dense output was asked."""

    def __init__(self, t, y, status, message, t_events, y_events, interpolants):
        self.t_last, self.y_last, self.status, self.message = t, y, status, message
        self.t_events, self.y_events = t_events, y_events
        self._pieces = interpolants

    def sol(self, t):
        """The state at t (dense output; within the steps taken); at an array of times, an
        array of one row per state."""
        import bisect

        if not isinstance(t, float | int):
            import numpy as np

            return np.array([self.sol(float(v)) for v in np.ravel(t)]).T
        ends = [p.t for p in self._pieces]
        i = min(bisect.bisect_left(ends, t), len(self._pieces) - 1)
        return self._pieces[i](t)


class _Solver:
    """One explicit Runge-Kutta integration (scipy's RungeKutta and its DOP853 / RK45)."""

    def __init__(self, fun, t0, y0, t_bound, method, rtol, atol, max_step):
        self.fun, self.method, self.tab = fun, method, tableau(method)
        self.t, self.y, self.t_bound = t0, [float(v) for v in y0], t_bound
        self.rtol, self.atol, self.max_step = rtol, atol, max_step
        if t_bound < t0:
            raise ValueError("forward integration only")
        self.f = [float(v) for v in fun(t0, self.y)]
        self.h_abs = self._initial_step()
        self.exponent = -1.0 / (self.tab["order"] + 1)
        self.K = [None] * (self.tab["stages"] + 1)
        self.stepper, self.errors, self.extra = _stepper(method, len(self.y))
        self.t_old = self.y_old = None
        self.status = "running"

    def _initial_step(self):
        """common.select_initial_step."""
        t0, y0, f0 = self.t, self.y, self.f
        interval = abs(self.t_bound - t0)
        if interval == 0.0:
            return 0.0
        scale = [self.atol + abs(v) * self.rtol for v in y0]
        d0 = _norm([v / s for v, s in zip(y0, scale)])
        d1 = _norm([v / s for v, s in zip(f0, scale)])
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, interval)
        y1 = [v + h0 * f for v, f in zip(y0, f0)]
        f1 = self.fun(t0 + h0, y1)
        d2 = _norm([(a - b) / s for a, b, s in zip(f1, f0, scale)]) / h0
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / (self.tab["order"] + 1))
        return min(100 * h0, h1, interval, self.max_step)

    def _rk_step(self, t, y, h):
        """rk.rk_step: the stages into self.K, (y_new, f_new)."""
        y_new, f_new, self.K = self.stepper(self.fun, t, y, self.f, h)
        return y_new, f_new

    def _error_norm(self, h, scale):
        """rk.RungeKutta._estimate_error_norm, DOP853's own for DOP853."""
        if self.method == "RK45":
            (err,) = self.errors(self.K)
            return _norm([e * h / c for e, c in zip(err, scale)])
        e5, e3 = self.errors(self.K)
        e5 = [e / c for e, c in zip(e5, scale)]
        e3 = [e / c for e, c in zip(e3, scale)]
        n5, n3 = math.sqrt(sum(v * v for v in e5)) ** 2, math.sqrt(sum(v * v for v in e3)) ** 2
        if n5 == 0 and n3 == 0:
            return 0.0
        return abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * len(scale))

    def step(self) -> str | None:
        """base.OdeSolver.step with rk.RungeKutta._step_impl."""
        t = self.t
        if t == self.t_bound:
            self.t_old, self.status = t, "finished"
            return None
        min_step = 10 * abs(math.nextafter(t, math.inf) - t)
        h_abs = min(self.h_abs, self.max_step) if self.h_abs > self.max_step else \
            max(self.h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step:
                self.status = "failed"
                return TOO_SMALL_STEP
            t_new = t + h_abs
            if t_new - self.t_bound > 0:
                t_new = self.t_bound
            h = t_new - t
            h_abs = abs(h)
            y_new, f_new = self._rk_step(t, self.y, h)
            scale = [self.atol + max(abs(a), abs(b)) * self.rtol for a, b in zip(self.y, y_new)]
            error = self._error_norm(h, scale)
            if error < 1:
                factor = MAX_FACTOR if error == 0 else min(MAX_FACTOR,
                                                           SAFETY * error ** self.exponent)
                h_abs *= min(1.0, factor) if rejected else factor
                break
            h_abs *= max(MIN_FACTOR, SAFETY * error ** self.exponent)
            rejected = True
        self.h_previous, self.y_old, self.t_old = h, self.y, t
        self.t, self.y, self.h_abs, self.f = t_new, y_new, h_abs, f_new
        if self.t - self.t_bound >= 0:
            self.status = "finished"
        return None

    def dense_output(self) -> Interpolant:
        if self.t == self.t_old:
            return Interpolant(self.t_old, self.t, self.y, self.y, "constant")
        h, y_old, tab = self.h_previous, self.y_old, self.tab
        if self.method == "RK45":
            K = self.K
            Q = [[sum(K[j][i] * tab["P"][j][c] for j in range(len(K)))
                  for c in range(len(tab["P"][0]))] for i in range(len(y_old))]
            return Interpolant(self.t_old, self.t, y_old, Q, "RK45")
        f_old = self.K[0]
        dy = [a - b for a, b in zip(self.y, y_old)]
        F = [dy, [h * f - d for f, d in zip(f_old, dy)],
             [2 * d - h * (f + g) for d, f, g in zip(dy, self.f, f_old)]]
        F += self.extra(self.fun, self.t_old, y_old, h, self.K)
        return Interpolant(self.t_old, self.t, y_old, F, "DOP853")


def _active(g, g_new, directions):
    """ivp.find_active_events."""
    out = []
    for i, (a, b, d) in enumerate(zip(g, g_new, directions)):
        if (a > 0 and b > 0) or (a < 0 and b < 0):  # no sign change: the common case
            continue
        up, down = a <= 0 and b >= 0, a >= 0 and b <= 0
        if (up and d > 0) or (down and d < 0) or ((up or down) and d == 0):
            out.append(i)
    return out


def solve(fun, t0, t_bound, y0, *, method, rtol, atol, events=(), dense_output=False,
          max_step=math.inf) -> Solution:
    """solve_ivp(fun, (t0, t_bound), y0, method=method, rtol=rtol, atol=atol, events=...,
    dense_output=..., max_step=...) with events given as (g(t, y), direction, terminal): the
    same steps and events up to rounding (module docstring)."""
    solver = _Solver(fun, float(t0), y0, float(t_bound), method, rtol, atol, max_step)
    funs = [e[0] for e in events]
    directions = [e[1] for e in events]
    terminal = [bool(e[2]) for e in events]
    g = [f(solver.t, solver.y) for f in funs]
    t_events = [[] for _ in funs]
    y_events = [[] for _ in funs]
    pieces, status, message = [], None, None
    t, y = solver.t, solver.y
    while status is None:
        message = solver.step()
        if solver.status == "finished":
            status = 0
        elif solver.status == "failed":
            status = -1
            break
        t_old, t, y = solver.t_old, solver.t, solver.y
        sol = solver.dense_output() if dense_output else None
        if sol is not None:
            pieces.append(sol)
        if funs:
            g_new = [f(t, y) for f in funs]
            active = _active(g, g_new, directions)
            if active:
                if sol is None:
                    sol = solver.dense_output()
                roots = [brentq(lambda tt, f=funs[i], sol=sol: f(tt, sol(tt)), t_old, t,
                                xtol=4 * EPS, rtol=4 * EPS) for i in active]
                hits = list(zip(active, roots))
                if any(terminal[i] for i in active):
                    hits.sort(key=lambda hit: hit[1])
                    last = next(n for n, (i, _) in enumerate(hits) if terminal[i])
                    hits = hits[:last + 1]
                    status, t = 1, hits[-1][1]
                    y = sol(t)
                for i, root in hits:
                    t_events[i].append(root)
                    y_events[i].append(sol(root))
            g = g_new
    return Solution(t, y, status, MESSAGES.get(status, message), t_events, y_events, pieces)
