"""Impact maps of the stairs scene, scalar and vectorised, and many bounces at once.

`impact_once` is the scalar map the event simulator applies; `impact_map` the same on numpy
arrays; `bounce_sequence` advances many samples many bounces down a uniform staircase with the
closed-form flights (no event location), for Monte-Carlo checks and long runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


def impact_once(vx, vy, omega, eps, mu, r, m, inertia):
    """Scalar impact map: (vx+, vy+, omega+, slipped, friction demand |P_roll| / Pn)."""
    vy_after = -eps * vy
    if mu == 0.0:
        return vx, vy_after, omega, False, 0.0
    slip = vx + r * omega
    share = inertia / (inertia + m * r * r)        # (impulse that stops the slip) / (m c)
    need = abs(slip) * share                       # |P_roll| / m
    normal = (1.0 + eps) * abs(vy)                 # Pn / m
    demand = need / normal if normal > 0.0 else (0.0 if need == 0.0 else math.inf)
    if need <= mu * normal:
        vx_after = vx - slip * share               # = (m r^2 vx - J r omega) / (m r^2 + J)
        return vx_after, vy_after, -vx_after / r, False, demand
    dv = -math.copysign(mu * normal, slip)
    return vx + dv, vy_after, omega + m * r * dv / inertia, True, demand


class Impact(NamedTuple):
    """Velocities just after an impact with a tread (arrays), and where the contact slid."""

    vx: np.ndarray
    vy: np.ndarray
    omega: np.ndarray
    slipped: np.ndarray


def impact_map(vx, vy, omega, eps, mu, r, m, J) -> Impact:
    """The stairs impact map on numpy arrays (broadcast; any argument may be a scalar).

    vy is the vertical velocity before the impact (< 0). Newton restitution vy+ = -eps vy;
    frictionless (mu = 0): vx and omega unchanged. With Coulomb friction mu the contact slip
    c = vx + r omega needs |P| = |c| m J / (J + m r^2) to stop; if |P| <= mu m (1 + eps)|vy| the
    impact ends rolling (vx+ = vx - c J / (J + m r^2), omega+ = -vx+ / r), otherwise it slides
    throughout (P = -sign(c) mu Pn). J = 0 with friction: the spin follows at once (rolling).
    Friction needs r > 0 (mu > 0 with r = 0 gives NaN spin).
    """
    vx = np.asarray(vx, dtype=float)
    vy = np.asarray(vy, dtype=float)
    omega = np.asarray(omega, dtype=float)
    vy_after = -eps * vy
    if np.ndim(mu) == 0 and mu == 0.0:
        shape = np.broadcast_shapes(vx.shape, vy.shape, omega.shape)
        return Impact(np.broadcast_to(vx, shape).copy(), np.broadcast_to(vy_after, shape).copy(),
                      np.broadcast_to(omega, shape).copy(), np.zeros(shape, dtype=bool))
    with np.errstate(divide="ignore", invalid="ignore"):
        vx_after, omega_after, slipped = _impact_arrays(vx, vy, omega, eps, mu, r, m, J)
    return Impact(vx_after, np.broadcast_to(vy_after, vx_after.shape).copy(), omega_after,
                  slipped)


def _impact_arrays(vx, vy, omega, eps, mu, r, m, J):
    """Tangential part of impact_map on arrays: (vx+, omega+, slipped)."""
    slip = vx + r * omega
    share = J / (J + m * (r * r))
    stick = slip * share                                # -(impulse to stop the slip) / m
    limit = mu * (1.0 + eps) * np.abs(vy)              # mu Pn / m
    rolls = np.abs(stick) <= limit
    dv = np.where(rolls, -stick, -np.copysign(limit, slip))
    vx_after = vx + dv
    omega_after = np.where(rolls, -vx_after / r, omega + m * r * dv / J)
    if np.ndim(mu) or mu == 0.0:
        frictionless = np.asarray(mu) == 0.0
        if np.any(frictionless):
            vx_after = np.where(frictionless, vx, vx_after)
            omega_after = np.where(frictionless, omega, omega_after)
            rolls = rolls | frictionless
    return vx_after, omega_after, ~rolls


# --------------------------------------------------------------------------------------------
# Vectorised bounces on a uniform staircase
# --------------------------------------------------------------------------------------------

BOUNCE_FAILURES = ("", "double_landing", "skipped_step", "nose_hit", "riser_hit")


@dataclass(frozen=True)
class BounceSequence:
    """State of many samples after bounce_sequence: the state just before the last impact
    reached (landing offset from the back of the tread, velocities), time since the first impact,
    bounces completed, and a failure code (index into BOUNCE_FAILURES; 0 = none), plus the
    extremes of the landing offset seen."""

    landing: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    omega: np.ndarray
    time: np.ndarray
    bounces: np.ndarray
    failure: np.ndarray
    landing_min: np.ndarray
    landing_max: np.ndarray

    def failure_kinds(self) -> list[str]:
        return [BOUNCE_FAILURES[i] for i in self.failure]


def bounce_sequence(landing, vx, vy, omega, *, bounces: int, rise: float, tread: float,
                    eps: float, mu: float = 0.0, r: float = 0.0, m: float = 1.0, J: float = 0.0,
                    g: float = 9.81, check_nose: bool = True) -> BounceSequence:
    """Advance many samples `bounces` bounces down a uniform staircase with plain numpy.

    Each sample starts just before an impact on a tread: landing offset from the tread's back,
    vx, vy (< 0), omega. A bounce = impact_map + the closed-form flight to the next tread:
        same-level return x = s + vx 2 vy+/g  (<= tread: double_landing; < 0: riser_hit, the
        ball went back), time to the next tread t = (vy+ + sqrt(vy+^2 + 2 g rise)) / g,
        s' = s + vx t - tread (> tread: skipped_step; it passes the next nose).
    check_nose (r > 0): the nose between the treads can only be touched when the same-level
    return is less than r beyond it; for those samples the centre path's distance to the nose
    is minimised by safeguarded Newton steps, exact when vx^2 + vy+^2 > g r (distance^2 convex
    there; any ball small against the flight's curvature radius). A failed sample is frozen
    with its failure code. Memory is O(samples) whatever `bounces` is.
    """
    s, vx, vy, om = (np.array(np.broadcast_arrays(landing, vx, vy, omega), dtype=float))
    frictionless = mu == 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return _bounce_loop(s, vx, vy, om, int(bounces), rise, tread, eps, mu, r, m, J, g,
                            check_nose, frictionless)


def _bounce_loop(s, vx, vy, om, bounces, rise, tread, eps, mu, r, m, J, g, check_nose,
                 frictionless):
    n = s.shape
    time, comp = np.zeros(n), np.zeros(n)
    done = np.zeros(n, dtype=np.int64)
    code = np.zeros(n, dtype=np.int8)
    lo, hi = s.copy(), s.copy()
    alive = np.ones(n, dtype=bool)
    all_alive = True
    two_g_rise = 2.0 * g * rise
    for _ in range(bounces):
        up = -eps * vy
        if frictionless:
            vx_a, om_a = vx, om
        else:
            vx_a, om_a, _ = _impact_arrays(vx, vy, om, eps, mu, r, m, J)
        x_same = s + vx_a * (2.0 / g) * up
        root = np.sqrt(up * up + two_g_rise)
        t = (up + root) / g
        s_next = s + vx_a * t - tread
        bad = (x_same <= tread) | (s_next > tread)
        if check_nose and r > 0.0:
            near = (x_same - tread < r) & ~bad
            if near.any():
                idx = np.flatnonzero(near)
                hit = corner_hits(tread - s[idx], vx_a[idx], up[idx], r, g, t[idx])
                nose = np.zeros(n, dtype=bool)
                nose[idx[hit]] = True
                bad |= nose
            else:
                nose = None
        else:
            nose = None
        if all_alive and not bad.any():
            s, vx, om, vy = s_next, vx_a, om_a, -root
            y = t - comp                               # Kahan summation of the flight times
        else:
            fail = np.where(x_same <= tread, np.where(x_same < 0.0, 4, 1),
                            np.where(s_next > tread, 2, 0)).astype(np.int8)
            if nose is not None:
                fail[nose] = 3
            newly = alive & (fail != 0)
            code[newly] = fail[newly]
            alive &= fail == 0
            all_alive = False
            if not alive.any():
                break
            s = np.where(alive, s_next, s)
            vx = np.where(alive, vx_a, vx)
            om = np.where(alive, om_a, om)
            vy = np.where(alive, -root, vy)
            y = np.where(alive, t, 0.0) - comp
        tt = time + y
        comp = (tt - time) - y
        time = tt
        done += alive
        np.minimum(lo, s, out=lo)
        np.maximum(hi, s, out=hi)
    return BounceSequence(s, vx, vy, om, time, done, code, lo, hi)


def corner_hits(d, vx, up, r, g, t_land, h=0.0):
    """True where a ball of radius r touches a corner before t_land: its lowest point starts h
    above the corner's level and d behind it (horizontally), moving at (vx > 0, up).

    Contact needs the lowest point at or below the corner's level and the centre above it (below,
    the ball is past the corner and moving away), so it is sought between t0, the lowest point at
    the corner's level, and t1, the centre at it (or t_land): the least of
    f(t) = (vx t - d)^2 + (r + h + up t - g t^2/2)^2 - r^2 there, by safeguarded Newton steps on
    f'. Exact where f is convex over that window: f'' >= 2 (vx^2 + up^2 + 2 g h - g r) > 0, any
    ball small against its path's curvature radius. Only meaningful for samples whose lowest point
    passes the corner's level less than r beyond it (elsewhere there is no contact)."""
    t0 = (up + np.sqrt(up * up + 2.0 * g * h)) / g          # lowest point at the corner's level
    t1 = np.minimum((up + np.sqrt(up * up + 2.0 * g * (h + r))) / g, t_land)  # centre at it

    def grad(t):  # f, f', f''
        dx = vx * t - d
        dy = r + h + up * t - 0.5 * g * t * t
        vyc = up - g * t
        f = dx * dx + dy * dy - r * r
        return f, 2.0 * (vx * dx + dy * vyc), 2.0 * (vx * vx + vyc * vyc - g * dy)

    lo, hi = np.broadcast_arrays(t0, t1)
    lo, hi = lo.copy(), hi.copy()
    t = hi.copy()
    best = np.minimum(grad(lo)[0], grad(hi)[0])
    for _ in range(8):                                      # safeguarded Newton on f'
        f, d1, d2 = grad(t)
        best = np.minimum(best, f)
        lo = np.where(d1 < 0.0, t, lo)
        hi = np.where(d1 >= 0.0, t, hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = t - d1 / d2
        inside = (d2 > 0.0) & (newton > lo) & (newton < hi)
        t = np.where(inside, newton, 0.5 * (lo + hi))
    best = np.minimum(best, grad(t)[0])
    return best < 0.0
