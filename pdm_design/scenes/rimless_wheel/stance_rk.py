"""The stance's numerical integration: phi'' = sin phi (in the time unit sqrt(2 / rate)) by the
Dormand-Prince 5(4) pair on plain floats, with terminal events located to rounding.

Written for the two-dimensional stance (y = (phi, phi')): scipy's solve_ivp spends most of a
stance in its general machinery (arrays of two numbers, its event bookkeeping) and its import.
Step control is the standard one (the error of the embedded fourth-order solution against
atol + rtol |y| in the root-mean-square norm, the step grown or shrunk by 0.9 err^(-1/5) within
[0.2, 10]). An event g(y) = 0 crossed in the wanted direction within an accepted step is
located by the Illinois method on g(y(t + h')), y(t + h') a fresh step of the pair from the
step's start (the integrator's own accuracy, not an interpolant's), to a few roundings of t.
A recorded trajectory is the steps' cubic Hermite interpolant (for plots).
"""

from __future__ import annotations

import math

# Dormand & Prince (1980): nodes, the stages' weights, the fifth-order weights (also the last
# stage's, FSAL), and the fifth-order less the fourth-order weights (the error estimate)
C = (0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0)
A = ((),
     (1 / 5,),
     (3 / 40, 9 / 40),
     (44 / 45, -56 / 15, 32 / 9),
     (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
     (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656))
B = (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84)
E = (71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40)
SAFETY, GROW, SHRINK = 0.9, 10.0, 0.2
EVENT_ITERATIONS = 100


def _f(y):
    return (y[1], math.sin(y[0]))


def _step(y, f0, h):
    """(y after h (fifth order), f there, error norm's components (5th - 4th order))."""
    ks = [f0]
    for i in range(1, 6):
        a = A[i]
        p = y[0] + h * sum(a[j] * ks[j][0] for j in range(i))
        v = y[1] + h * sum(a[j] * ks[j][1] for j in range(i))
        ks.append(_f((p, v)))
    new = (y[0] + h * sum(B[j] * ks[j][0] for j in range(6)),
           y[1] + h * sum(B[j] * ks[j][1] for j in range(6)))
    f1 = _f(new)
    ks.append(f1)
    err = (h * sum(E[j] * ks[j][0] for j in range(7)), h * sum(E[j] * ks[j][1] for j in range(7)))
    return new, f1, err


class Dense:
    """The steps' cubic Hermite interpolant: sol(t) -> (phi, phi') (for plots)."""

    def __init__(self):
        self.ts, self.ys, self.fs = [], [], []

    def add(self, t, y, f):
        self.ts.append(t)
        self.ys.append(y)
        self.fs.append(f)

    def sol(self, t):
        import bisect

        i = min(max(bisect.bisect_right(self.ts, t) - 1, 0), len(self.ts) - 2)
        t0, h = self.ts[i], self.ts[i + 1] - self.ts[i]
        if h <= 0.0:
            return self.ys[i]
        s = (t - t0) / h
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        return tuple(h00 * self.ys[i][d] + h10 * h * self.fs[i][d]
                     + h01 * self.ys[i + 1][d] + h11 * h * self.fs[i + 1][d] for d in (0, 1))


def integrate(y0, span, events, rtol, atol, dense=False):
    """Integrate from y0 (phi, phi') at t = 0 to the first event or `span`. events: [(g(y),
    direction)], direction +1 (g rises through 0), -1 (falls) or 0. (t, y, index of the event
    or None, Dense or None)."""
    t, y, f = 0.0, (float(y0[0]), float(y0[1])), _f(y0)
    g_now = [g(y) for g, _ in events]
    h = min(0.01, span)
    out = Dense() if dense else None
    if out is not None:
        out.add(t, y, f)
    while t < span:
        h = min(h, span - t)
        new, f1, err = _step(y, f, h)
        scale = [atol + rtol * max(abs(y[d]), abs(new[d])) for d in (0, 1)]
        norm = math.sqrt(0.5 * sum((err[d] / scale[d]) ** 2 for d in (0, 1)))
        if norm > 1.0:
            h *= max(SHRINK, SAFETY * norm ** -0.2)
            continue
        g_new = [g(new) for g, _ in events]
        hit = _first_event(events, g_now, g_new, y, f, h)
        if hit is not None:
            dt, index = hit
            y_hit = _step(y, f, dt)[0] if dt > 0.0 else y
            if out is not None:
                out.add(t + dt, y_hit, _f(y_hit))
            return t + dt, y_hit, index, out
        t, y, f, g_now = t + h, new, f1, g_new
        if out is not None:
            out.add(t, y, f)
        h *= min(GROW, SAFETY * norm ** -0.2) if norm > 0.0 else GROW
    return t, y, None, out


def _first_event(events, g_now, g_new, y, f, h):
    """(time into the step, index) of the earliest event crossed in this step, or None."""
    found = None
    for i, ((g, direction), a, b) in enumerate(zip(events, g_now, g_new)):
        crossed = (a < 0.0 <= b) if direction > 0 else (a > 0.0 >= b) if direction < 0 else (
            a * b <= 0.0 and a != 0.0)
        if not crossed:
            continue
        dt = _locate(lambda s, g=g: g(_step(y, f, s)[0]), h, a, b)
        if found is None or dt < found[0]:
            found = (dt, i)
    return found


def _locate(g_at, h, g0, g1):
    """The root of g_at(s) in [0, h] (g_at(0) = g0, g_at(h) = g1 of opposite signs or g1 = 0),
    by the Illinois method, to a few roundings of the step."""
    lo, hi, glo, ghi = 0.0, h, g0, g1
    if g1 == 0.0:
        return h
    side = 0
    for _ in range(EVENT_ITERATIONS):
        s = hi - ghi * (hi - lo) / (ghi - glo) if ghi != glo else 0.5 * (lo + hi)
        if not lo < s < hi:
            s = 0.5 * (lo + hi)
        gs = g_at(s)
        if gs == 0.0 or hi - lo <= 4.0 * math.ulp(max(hi, 1.0)):
            return s
        if (gs > 0.0) == (ghi > 0.0):
            hi, ghi = s, gs
            if side == 1:
                glo *= 0.5
            side = 1
        else:
            lo, glo = s, gs
            if side == -1:
                ghi *= 0.5
            side = -1
    return hi
