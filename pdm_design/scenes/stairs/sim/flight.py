"""Flights of the stairs simulator: the next contact of a ballistic flight, in closed form.

Each flight is computed in a frame attached to the nose of the step it leaves (see
`pdm_design.scenes.stairs.sim`). Contacts: a tread (the descending root of a quadratic, without
cancellation), a nose corner (a quartic in t, companion-matrix roots polished by Newton), a riser
face (linear in t; only reachable when moving backwards).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .geometry import StairsGeometry

_MAX_STEPS_PER_FLIGHT = 100_000


def _descend(vy, height, g):
    """(t, vy(t)) when a body at height 0 moving up at vy, falling under g, passes `height`
    going down; None if it never gets that high. The root is taken without cancellation."""
    disc = vy * vy - 2.0 * g * height
    if disc < 0.0:
        return None
    s = math.sqrt(disc)
    t = (vy + s) / g if vy >= 0.0 else -2.0 * height / (s - vy)
    return t, -s


class Contact(NamedTuple):
    kind: str       # "tread", "corner", "face"
    step: int
    t: float
    x: float        # ball centre x at contact, frame of the step left
    vy: float       # vertical velocity at contact


def _corner_time(px, py, vx, vy, r, g, t_max, tol):
    """First time the centre, starting at the origin with (vx, vy) under gravity, comes within
    r of the corner (px, py), entering; None if not before t_max.

    Distance^2 - r^2 is the quartic (g^2/4) t^4 - g vy t^3 + (vx^2 + vy^2 + g py) t^2
    - 2 (vx px + vy py) t + px^2 + py^2 - r^2. It is only solved when a cheap window test
    (the centre within r of the corner horizontally and vertically) says contact is possible.
    """
    if vx > 0.0:
        ta, tb = (px - r) / vx, (px + r) / vx
    elif vx < 0.0:
        ta, tb = (px + r) / vx, (px - r) / vx
    else:
        if abs(px) > r:
            return None
        ta, tb = 0.0, t_max
    ta, tb = max(ta, 0.0), min(tb, t_max)
    if not ta <= tb:
        return None
    ea = vy * ta - 0.5 * g * ta * ta - py
    eb = vy * tb - 0.5 * g * tb * tb - py
    if min(ea, eb) >= r:
        return None
    tv = vy / g
    emax = vy * tv - 0.5 * g * tv * tv - py if ta < tv < tb else max(ea, eb)
    if emax <= -r:
        return None
    tau = tb if tb > 0.0 else 1.0          # time scale: roots of interest in [0, 1]
    gt2, vxt, vyt = g * tau * tau, vx * tau, vy * tau  # lengths: no overflow from g^2 tau^4
    c = (0.25 * gt2 * gt2, -gt2 * vyt, vxt * vxt + vyt * vyt + gt2 * py,
         -2.0 * (vxt * px + vyt * py), px * px + py * py - r * r)

    def f(t):
        return (((c[0] * t + c[1]) * t + c[2]) * t + c[3]) * t + c[4]

    def df(t):
        return ((4.0 * c[0] * t + 3.0 * c[1]) * t + 2.0 * c[2]) * t + c[3]

    scale = px * px + py * py + r * r
    lo, hi = ta / tau, tb / tau
    best = None
    for z in np.roots(c):
        if abs(z.imag) > 1e-4 * max(1.0, abs(z.real)):
            continue
        s = float(z.real)
        for _ in range(30):                # Newton polish (linear near a graze's double root)
            d = df(s)
            if d == 0.0:
                break
            step = f(s) / d
            s -= step
            if abs(step) * tau <= tol:
                break
        if abs(f(s)) > 1e-9 * scale or not (lo - 1e-9 <= s <= hi + 1e-9) or s * tau <= tol:
            continue
        if df(s) > 1e-7 * scale:
            continue                       # leaving: it touched at the start (landed on the nose)
        if best is None or s < best:
            best = s
    return None if best is None else best * tau


def next_contact(geo: StairsGeometry, k, x0, y0, vx, vy, r, g, tol):
    """First contact of a flight starting over step(s) near step k, in the frame of step k's
    nose: lowest point at (x0, y0), velocity (vx, vy)."""
    j0 = k if k > 0 else step_under(geo, k, x0)   # after an impact the ball is over step k
    if vx >= 0.0:
        return _forward(geo, k, j0, x0, y0, vx, vy, r, g, tol)
    return _backward(geo, k, j0, x0, y0, vx, vy, r, g, tol)


def step_under(geo, k, x):
    j = k
    back, nose, _ = geo.relative(k, j)
    while x > nose:
        j += 1
        back, nose, _ = geo.relative(k, j)
    while x < back:
        j -= 1
        back, nose, _ = geo.relative(k, j)
    return j


def _forward(geo, k, j, x0, y0, vx, vy, r, g, tol):
    passed = _overhung(geo, k, j, x0, r)
    for _ in range(_MAX_STEPS_PER_FLIGHT):
        _, nose, level = geo.relative(k, j)
        t, vy_hit = _descend(vy, level - y0, g)
        x = x0 + vx * t
        if x <= nose:
            landing = Contact("tread", j, t, x, vy_hit)
            break
        passed.append((j, nose, level))
        j += 1
    else:  # pragma: no cover - treads of positive length always stop the loop
        raise RuntimeError("flight passes more steps than the simulator searches")
    if r > 0.0:
        first = None
        for step, nose, level in passed:
            tc = _corner_time(nose - x0, level - y0 - r, vx, vy, r, g, landing.t, tol)
            if tc is not None and tc < landing.t - tol and (first is None or tc < first.t):
                first = Contact("corner", step, tc, x0 + vx * tc, vy - g * tc)
        if first is not None:
            return first
    return landing


def _overhung(geo, k, j, x0, r):
    """(step, nose, level) of the noses behind step j that the ball, centred at x0, still
    overhangs: a launch that starts just past the top landing's nose can come down on its corner
    while moving away from it."""
    out = []
    while j > 0:
        j -= 1
        _, nose, level = geo.relative(k, j)
        if nose <= x0 - r:
            break
        out.append((j, nose, level))
    return out


def _backward(geo, k, j, x0, y0, vx, vy, r, g, tol):
    apex = y0 + 0.5 * max(vy, 0.0) ** 2 / g
    found: list[Contact] = []
    while True:
        back, nose, level = geo.relative(k, j)
        landed = False
        hit = _descend(vy, level - y0, g) if apex >= level else None
        if hit is not None:
            x = x0 + vx * hit[0]
            if back <= x <= nose:
                found.append(Contact("tread", j, hit[0], x, hit[1]))
                landed = True
        if j == 0:
            break
        upper = geo.relative(k, j - 1)[2]
        if x0 > back + r:  # the riser face at the back of tread j, from `level` up to `upper`
            tf = (back + r - x0) / vx
            yc = y0 + r + vy * tf - 0.5 * g * tf * tf
            if level <= yc <= upper:
                found.append(Contact("face", j, tf, back + r, vy - g * tf))
        if r > 0.0:
            tc = _corner_time(back - x0, upper - y0 - r, vx, vy, r, g, math.inf, tol)
            if tc is not None:
                found.append(Contact("corner", j - 1, tc, x0 + vx * tc, vy - g * tc))
        if landed or apex < upper:
            break
        j -= 1
    if not found:  # pragma: no cover - a backward flight always meets a face, corner or tread
        raise RuntimeError(f"no contact found for a backward flight from step {k}")
    # earliest contact; a tread landing wins a tie with a corner or face it meets at its edge
    return min(found, key=lambda c: (c.t - (tol if c.kind == "tread" else 0.0)))
