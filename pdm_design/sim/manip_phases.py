"""Phases of the manipulators scene as pure functions: impacts, the stuck carry (closed form in the
palm angle), the sliding carry and the free palm (vector fields and guards).

Notation: palm angle th clockwise from the vertical, radial r = (sin th, cos th), tangent
t = (cos th, -sin th) (direction of increasing th). w = l th' is the palm's tangential speed.
The object (mass m) sits on the palm's top surface at s along the palm from its centre; the palm
(mass M, inv_M = 1/M, 0 for a palm held by a stop) hangs on massless links, which carry only
radial force. docs/manipulators_model.md derives everything here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.integrate import quad

from ..physics.manipulators import cos_difference
from .core import locate

# ---------------------------------------------------------------- impacts

@dataclass(frozen=True)
class Impact:
    """Result of one impact of the object on a palm.

    vx, vy: object velocity after; w: palm tangential speed after; pt, pn: impulse on the object
    (N s, along x and y); stick: the contact ends with no relative tangential velocity;
    jam: no consistent sliding impact exists (Painleve-type; pt, pn are then nan)."""

    vx: float
    vy: float
    w: float
    pt: float
    pn: float
    stick: bool
    jam: bool = False


def impact(vx, vy, w, theta, *, m, inv_M, mu, eps) -> Impact:
    """Impact of the object (velocity vx, vy) on a palm at angle theta moving at speed w along t.

    Relative contact velocity: tangential g_t = vx - w cos th, normal g_n = vy + w sin th (< 0:
    approaching). An impulse (p_t, p_n) on the object changes it by W (p_t, p_n), with the
    Delassus matrix W = [[1/m + c^2/M, -s c/M], [-s c/M, 1/m + s^2/M]] (the palm takes -p plus a
    radial link impulse: M dw = -p_t cos th + p_n sin th).

    Darboux-Keller: the impact is followed in the growing normal impulse P, with Coulomb's law
    at every instant (slip: dp_t = -sigma mu dP; stick while the sticking ratio -W_tn/W_tt is
    inside the cone), so g is piecewise linear in P and each piece is closed form. Compression
    ends when g_n = 0; restitution (Stronge's energetic coefficient eps) ends when the normal
    impulse has given back eps^2 of the work it took in compression. With eps = 0 this is the
    plastic rule: stick iff the sticking impulse is inside the cone (|px| <= mu py at a resting
    palm), else Coulomb sliding throughout. In one contact mode the separation speed is
    eps |g_n| (Newton's rule); where the mode changes during the impact Newton's rule can create
    energy and this one cannot. A compression that can neither stop slipping nor reduce the
    approach (k_n <= 0) has no solution: `jam` (Painleve)."""
    s, c = math.sin(theta), math.cos(theta)
    g_t, g_n = vx - w * c, vy + w * s
    w_tt, w_tn, w_nn = 1.0 / m + c * c * inv_M, -s * c * inv_M, 1.0 / m + s * s * inv_M
    scale = abs(g_t) + abs(g_n) + 1e-300
    p_t = p_n = 0.0
    work_c = 0.0  # work of the normal impulse in compression (<= 0)
    restitution, remaining = False, 0.0
    for _ in range(12):
        slipping = abs(g_t) > 1e-14 * scale
        if not slipping:
            g_t = 0.0
            ratio = -w_tn / w_tt
            if abs(ratio) <= mu:
                rate_t, sigma = ratio, 0.0
            else:
                sigma = math.copysign(1.0, w_tn)
                rate_t = -sigma * mu
        else:
            sigma = math.copysign(1.0, g_t)
            rate_t = -sigma * mu
        dg_t = w_tt * rate_t + w_tn if sigma != 0.0 else 0.0
        dg_n = w_tn * rate_t + w_nn
        steps = []
        if slipping and dg_t * sigma < 0.0:
            steps.append((-g_t / dg_t, "stick"))
        if not restitution:
            if dg_n > 0.0:
                steps.append((-g_n / dg_n, "compressed"))
        else:
            disc = g_n * g_n + 2.0 * dg_n * remaining
            if dg_n == 0.0:
                steps.append((remaining / g_n if g_n > 0.0 else math.inf, "done"))
            elif disc >= 0.0:
                steps.append((2.0 * remaining / (g_n + math.sqrt(disc)), "done"))
            else:  # the approach resumes before eps^2 of the work is given back: contact ends
                steps.append((-g_n / dg_n, "done"))
        if not steps:
            return Impact(vx, vy, w, math.nan, math.nan, False, True)
        dp, what = min(steps)
        dp = max(dp, 0.0)
        work = g_n * dp + 0.5 * dg_n * dp * dp
        p_t += rate_t * dp
        p_n += dp
        g_t, g_n = g_t + dg_t * dp, g_n + dg_n * dp
        if what == "stick":
            g_t = 0.0
        if restitution:
            remaining -= work
        else:
            work_c += work
        if what == "compressed":
            g_n = 0.0
            if eps == 0.0:
                break
            restitution, remaining = True, -eps * eps * work_c
            if remaining <= 0.0:
                break
        elif what == "done":
            break
    stick = g_t == 0.0
    return Impact(vx + p_t / m, vy + p_n / m, w - (p_t * c - p_n * s) * inv_M, p_t, p_n, stick)


def impact_force_point(pt, pn, height):
    """Where the impulse line through the centre of mass crosses the base, from its centre."""
    return -0.5 * height * pt / pn


# ---------------------------------------------------------------- the palm as a pendulum

def speed_squared(theta, theta0, v0, *, gravity, link_length):
    """v(th)^2 = v0^2 + 2 g l (cos th0 - cos th): palm (with a stuck object, or alone)."""
    return v0 * v0 + 2.0 * gravity * link_length * cos_difference(theta0, theta)


def turning_angle(theta0, v0, *, gravity, link_length, forward=True):
    """Angle where the swing from th0 at speed v0 stops (v = 0), or None if it passes the top.

    Moving forward from th0 < 0 the swing turns at -acos(cos th0 + v0^2 / (2 g l)); moving
    backward from th0 > 0 at +acos(...)."""
    k = math.cos(theta0) + v0 * v0 / (2.0 * gravity * link_length)
    if (forward and theta0 >= 0.0) or (not forward and theta0 <= 0.0) or k >= 1.0:
        return None
    return -math.acos(k) if forward else math.acos(k)


def swing_time(a, b, theta0, v0, *, gravity, link_length, tol, turn=None):
    """Time to swing from angle a to b (|v| > 0 inside), energy fixed by (th0, v0).

    dt = l dth / v(th); where an end is the turning point `turn` the integrand has a 1/sqrt
    singularity, integrated exactly by quad's algebraic weight."""
    if a == b:
        return 0.0
    lo, hi = (a, b) if a < b else (b, a)
    g, l = gravity, link_length

    def v2(th):
        return speed_squared(th, theta0, v0, gravity=g, link_length=l)

    opts = dict(epsabs=max(tol, 1e-15), epsrel=1e-12, limit=200)
    if turn is not None and (turn == lo or turn == hi):
        # v^2 = 2 g l (cos turn - cos th), written without cancellation. On x in [0, 1] with
        # |th - turn| = span (1 - x), dt = sqrt(span) * smooth(x) * (1 - x)^(-1/2) dx.
        span = hi - lo

        sign = 1.0 if turn == lo else -1.0

        def smooth(x):
            gap = (1.0 - x) * span
            if gap == 0.0:
                return l / math.sqrt(2.0 * g * l * abs(math.sin(turn)))
            delta = sign * gap  # th - turn
            k = 4.0 * g * l * math.sin(turn + 0.5 * delta) * math.sin(0.5 * delta)
            return l * math.sqrt(gap / abs(k))

        opts["epsabs"] = opts["epsabs"] / math.sqrt(span)
        value, _ = quad(smooth, 0.0, 1.0, weight="alg", wvar=(0.0, -0.5), **opts)
        value *= math.sqrt(span)
    else:
        value, _ = quad(lambda th: l / math.sqrt(max(v2(th), 1e-300)), lo, hi, **opts)
    return value


def free_palm_arrival(theta0, w0, *, gravity, link_length, back_stop, front_stop, tol):
    """Where and when a palm swinging alone from (th0, speed w0 along t) comes to a stop.

    Returns (dt, stop_angle, speed_at_stop). A palm exactly balanced at the top never arrives."""
    g, l = gravity, link_length
    forward = w0 > 0.0 or (w0 == 0.0 and theta0 > 0.0)
    if w0 == 0.0 and theta0 == 0.0:
        return math.inf, 0.0, 0.0
    v0 = abs(w0)
    turn = turning_angle(theta0, v0, gravity=g, link_length=l, forward=forward)
    kw = dict(gravity=g, link_length=l, tol=tol)
    if turn is None:
        target = front_stop if forward else back_stop
        dt = swing_time(theta0, target, theta0, v0, **kw)
    else:
        target = back_stop if forward else front_stop
        dt = (swing_time(theta0, turn, theta0, v0, turn=turn, **kw)
              + swing_time(turn, target, theta0, v0, turn=turn, **kw))
    v2 = speed_squared(target, theta0, v0, gravity=g, link_length=l)
    return dt, target, math.sqrt(max(v2, 0.0))


# ---------------------------------------------------------------- stuck carry guards (in th)

def lift_off_guard(theta, theta0, v0, *, gravity, link_length):
    """>= 0 when the palm no longer pushes the object: v^2 - g l cos th."""
    return (speed_squared(theta, theta0, v0, gravity=gravity, link_length=link_length)
            - gravity * link_length * math.cos(theta))


def stuck_force_point(theta, height):
    """Where the contact force m (g cos th - v^2/l) r crosses the base, from its centre."""
    return -0.5 * height * math.tan(theta)


def first_crossing(guard, a, b, tol, breaks=()):
    """First th in [a, b] where guard goes from < 0 to >= 0, to tol; None if it does not.

    guard must be monotone between consecutive `breaks`; a guard already >= 0 at a fires at a.
    The angle returned is within tol of the root and on its violated side (guard >= 0)."""
    if guard(a) >= 0.0:
        return a
    points = [a] + sorted(p for p in breaks if a < p < b) + [b]
    for lo, hi in zip(points, points[1:]):
        g_lo, g_hi = guard(lo), guard(hi)
        if g_lo < 0.0 <= g_hi:
            if g_hi == 0.0:
                return hi
            root = locate(guard, lo, hi, tol)
            for _ in range(8):  # report a point on the violated side, so the next phase
                if guard(root) >= 0.0:  # starts strictly inside its own guards
                    return root
                root = min(hi, root + tol)
            return hi
    return None


# ---------------------------------------------------------------- sliding carry

@dataclass(frozen=True)
class SlideParams:
    m: float
    M: float
    mu: float
    gravity: float
    link_length: float
    sgn: float  # sign of the slip velocity s' (friction on the object is -mu N sgn)


def slide_accelerations(theta, omega, p: SlideParams):
    """Accelerations and normal force of the sliding carry.

    Object: m (l th'' t - l th'^2 r + s'' i) = (-f, N - m g), f = mu N sgn.
    Palm along t: M l th'' = f cos th + N sin th + M g sin th. With c = mu sgn cos th + sin th:
      th'' = [m c (g - l th'^2 cos th) + M g sin th] / (l (M + m c sin th))
      N    = m (g - l th'' sin th - l th'^2 cos th)
      s''  = -mu sgn N / m - l th'' cos th + l th'^2 sin th
    Returns (th'', N, s'', D) with D = M + m c sin th (the sliding contact is consistent iff D > 0).
    """
    m, M, mu, g, l = p.m, p.M, p.mu, p.gravity, p.link_length
    sn, cs = math.sin(theta), math.cos(theta)
    c = mu * p.sgn * cs + sn
    d = M + m * c * sn
    w2 = omega * omega
    thdd = (m * c * (g - l * w2 * cs) + M * g * sn) / (l * d)
    normal = m * (g - l * thdd * sn - l * w2 * cs)
    sdd = -mu * p.sgn * normal / m - l * thdd * cs + l * w2 * sn
    return thdd, normal, sdd, d


def slide_rhs(p: SlideParams):
    """Vector field of the sliding carry on the state (th, th', s, s')."""

    def rhs(t, y):
        thdd, _, sdd, _ = slide_accelerations(y[0], y[1], p)
        return [y[1], thdd, y[3], sdd]

    return rhs


def slide_direction(theta, omega, p: SlideParams) -> float:
    """Direction a slip starting from s' = 0 takes: the sgn whose s'' agrees with it."""
    for sgn in (1.0, -1.0):
        q = SlideParams(p.m, p.M, p.mu, p.gravity, p.link_length, sgn)
        _, _, sdd, _ = slide_accelerations(theta, omega, q)
        if sgn * sdd > 0.0:
            return sgn
    return -math.copysign(1.0, theta)


def slide_force_point(sgn, mu, height):
    """Where the sliding contact force N (-mu sgn, 1) crosses the base, from its centre."""
    return 0.5 * height * mu * sgn


def object_state_on_palm(pivot, theta, omega, s, sd, link_length):
    """Object bottom centre and velocity when it sits at s on the palm (s' = sd)."""
    l = link_length
    x = pivot[0] + l * math.sin(theta) + s
    y = pivot[1] + l * math.cos(theta)
    return x, y, l * omega * math.cos(theta) + sd, -l * omega * math.sin(theta)
