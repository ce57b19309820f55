"""The step map for long runs and many walkers: fixed-step RK4 vectorised over walkers (numpy),
the heel strike located inside its RK4 step by the secant method on the step's length.

Each walker walks its own rough ground (its own slope error every step) until it falls or has
taken `steps` steps. The same conventions and falls as the event simulator (simulate.py), the
stance phase's force conditions checked at every RK4 step (not located); within 1e-7 of the
event simulator's states at 3 deg (tests/test_compass_gait_fastmap.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import physics as phys

FALLS = ("fell_forward", "fell_backward", "scuffed", "slip", "flight", "too_long")
STEP_FRACTION = 0.04  # RK4 step, x sqrt(l / g): 6e-8 from the event simulator's states
MAX_STEP_TIME = 20.0  # x sqrt(l / g)
SECANT_ITERATIONS = 4


@dataclass
class Walk:
    """Many walks: steps taken by each walker, its fall (index into FALLS, -1: none) and its
    last post-strike state (n x 4)."""

    steps: np.ndarray
    fall: np.ndarray
    state: np.ndarray

    def falls(self) -> dict[str, int]:
        return {name: int(np.sum(self.fall == k)) for k, name in enumerate(FALLS)
                if np.any(self.fall == k)}


def _rhs(x, p):
    a1, a2 = phys.accelerations(x[0], x[1], x[2], x[3], p)
    return np.array([x[2], x[3], a1, a2])


def _rk4(x, h, p, k1=None):
    k1 = _rhs(x, p) if k1 is None else k1
    k2 = _rhs(x + 0.5 * h * k1, p)
    k3 = _rhs(x + 0.5 * h * k2, p)
    k4 = _rhs(x + h * k3, p)
    return x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def walk(params: phys.Params, starts, slope, steps: int, friction: float = math.inf,
         slope_errors=None, rise: float = 0.0, rise_errors=None) -> Walk:
    """Walk every walker from its post-strike start (n x 4) for `steps` steps down a ramp of
    `slope` plus slope_errors[i, k] (rad) for walker i's step k (None: a smooth ramp); stairs
    when rise (per leg length) or rise_errors[i, k] (per leg length) is given: each step's
    tread tilted by `slope` plus its error, one rise plus its error below the last."""
    x = np.array(starts, dtype=float).T.copy()  # 4 x n
    n = x.shape[1]
    taken = np.zeros(n, dtype=int)
    fall = np.full(n, -1)
    for k in range(steps):
        alive = np.flatnonzero(fall < 0)
        if alive.size == 0:
            break
        gamma = np.full(alive.size, float(slope))
        if slope_errors is not None:
            gamma = gamma + np.asarray(slope_errors)[alive, k]
        r = None
        if rise != 0.0 or rise_errors is not None:
            r = np.full(alive.size, float(rise))
            r = r if rise_errors is None else r + np.asarray(rise_errors)[alive, k]
        after, code = _step(params, x[:, alive], gamma, friction, r)
        x[:, alive] = after
        fall[alive] = code
        taken[alive[code < 0]] += 1
    return Walk(taken, fall, x.T)


def _step(params, x, gamma, friction, rise=None):
    """One step of every column of x on its slope (and its rise per leg length: None on a
    ramp): (post-strike states, fall code or -1). The walkers still in their step are held
    compressed (xs, ...) and written back only when some end."""
    h = STEP_FRACTION * math.sqrt(params.l / params.g)
    out, code = x.copy(), np.full(x.shape[1], -2)  # -2: still in its step
    idx = np.arange(x.shape[1])
    xs, g, passed = x.copy(), gamma.copy(), x[0] > x[1]
    k1 = _rhs(xs, params)
    r = 0.0 if rise is None else rise.copy()
    guard = phys.strike_guard(xs[0], xs[1], g, r)
    for _ in range(int(MAX_STEP_TIME / STEP_FRACTION)):
        new = _rk4(xs, h, params, k1)
        k0, k1 = k1, _rhs(new, params)
        fell = _falls(params, new, k1, g, passed, friction, (xs, k0))
        guard_new = phys.strike_guard(new[0], new[1], g, r)
        ahead = new[0] > new[1]
        # a fall with the swing foot under the ground since the legs passed: a scuff
        fell[(fell >= 0) & ahead & (guard_new < 0)] = FALLS.index("scuffed")
        strikes = ahead & (guard > 0) & (guard_new <= 0) & (fell < 0)
        ended = strikes | (fell >= 0)
        if np.any(ended):
            if np.any(strikes):
                end = _locate(params, xs[:, strikes], g[strikes], h, guard[strikes],
                              guard_new[strikes], r if rise is None else r[strikes])
                out[:, idx[strikes]], code[idx[strikes]] = _strike(params, end, g[strikes],
                                                                   friction)
            down = fell >= 0
            out[:, idx[down]], code[idx[down]] = new[:, down], fell[down]
            keep = ~ended
            idx, new, k1, g = idx[keep], new[:, keep], k1[:, keep], g[keep]
            r = r if rise is None else r[keep]
            guard_new, ahead, passed = guard_new[keep], ahead[keep], passed[keep]
            if idx.size == 0:
                return out, code
        xs, guard, passed = new, guard_new, passed | ahead
    code[idx] = FALLS.index("too_long")
    return out, code


def _falls(params, x, rates, gamma, passed, friction, before=None):
    """Fall codes (-1: none) of states x inside a step; rates: their derivative (_rhs);
    before: (states, rates) one RK4 step earlier, to tell which of slip and flight came first
    where both hold (the first to cross 0 on a straight line between the two points)."""
    code = np.full(x.shape[1], -1)
    normal, tangential = phys.reaction(x[0], x[1], x[2], x[3], rates[2], rates[3], gamma,
                                       params)
    slip = np.abs(tangential) > friction * normal
    code[slip] = FALLS.index("slip")
    flight = (normal <= 0) & ~(slip & _slip_first(params, before, normal, tangential, gamma,
                                                   friction))
    code[flight] = FALLS.index("flight")
    code[flight & (x[0] > gamma) & (x[0] < x[1])] = FALLS.index("fell_forward")
    code[passed & (x[0] < x[1])] = FALLS.index("scuffed")
    code[(x[2] < 0) & (x[0] < 0)] = FALLS.index("fell_backward")
    code[x[0] - gamma > math.pi / 2] = FALLS.index("fell_forward")
    return code


def _slip_first(params, before, normal, tangential, gamma, friction):
    """Whether the friction margin f N - |T| crossed 0 before the normal force N did, each
    taken as a straight line from `before` (states, rates) to now; False without `before`."""
    if before is None or not math.isfinite(friction):
        return np.zeros(normal.shape, dtype=bool)
    x, r = before
    n0, t0 = phys.reaction(x[0], x[1], x[2], x[3], r[2], r[3], gamma, params)
    m0, m1 = friction * n0 - np.abs(t0), friction * normal - np.abs(tangential)
    with np.errstate(divide="ignore", invalid="ignore"):
        return m0 / (m0 - m1) < n0 / (n0 - normal)


def _locate(params, x, gamma, h, g0, g1, rise=0.0):
    """The state at the guard's zero inside an RK4 step of length h from x: the secant method
    on the length of one RK4 step from x."""
    s0, s1 = np.zeros_like(g0), np.full_like(g0, h)
    end = None
    for _ in range(SECANT_ITERATIONS):
        s = s1 - g1 * (s1 - s0) / np.where(g1 != g0, g1 - g0, 1.0)
        end = _rk4(x, s, params)
        s0, g0, s1, g1 = s1, g1, s, phys.strike_guard(end[0], end[1], gamma, rise)
    return end


def _strike(params, end, gamma, friction):
    after = np.array(phys.heel_strike(end[0], end[1], end[2], end[3], params))
    normal, tangential = phys.strike_impulse(end[0], end[1], end[2], end[3], params, gamma)
    code = np.full(end.shape[1], -1)
    code[np.abs(tangential) > friction * normal] = FALLS.index("slip")
    code[normal <= 0] = FALLS.index("flight")
    return after, code
