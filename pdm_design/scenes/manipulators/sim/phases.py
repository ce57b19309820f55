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
from dataclasses import dataclass, replace

from ....sim.numerics import carlson_rf
from .. import physics as phys

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


def impact(vx, vy, w, theta, *, m, inv_M=None, mu, eps, mass_ratio=None) -> Impact:
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
    approach (k_n <= 0) has no solution: `jam` (Painleve).

    The palm's mass enters as inv_M = 1/M or, equivalently and safe for any size of m,
    mass_ratio = m/M (one of them; 0 is a palm held by a stop)."""
    s, c = math.sin(theta), math.cos(theta)
    g_t, g_n = vx - w * c, vy + w * s
    # m W, with q = m / M: the impact in velocity units (impulses / m), whatever the masses' size
    q = m * inv_M if mass_ratio is None else mass_ratio
    w_tt, w_tn, w_nn = 1.0 + c * c * q, -s * c * q, 1.0 + s * s * q
    scale = abs(g_t) + abs(g_n) + 1e-300
    p_t = p_n = palm = 0.0
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
        if sigma != 0.0:
            dg_t = w_tt * rate_t + w_tn
            dg_n = w_tn * rate_t + w_nn
            palm_rate = rate_t * c - s  # palm impulse per unit P (times -1/M)
        else:  # sticking: the Schur complement det(mW) / (mW)_tt with det(mW) = 1 + q exactly
            dg_t = 0.0  # (w_nn - w_tn^2 / w_tt cancels to 1e-16 q for a light palm)
            dg_n = (1.0 + q) / w_tt
            palm_rate = -s / w_tt  # rate_t c - s without the same cancellation
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
        palm += palm_rate * dp
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
    return Impact(vx + p_t, vy + p_n, w - palm * q, m * p_t, m * p_n, stick)


def impact_force_point(pt, pn, height):
    """Where the impulse line through the centre of mass crosses the base, from its centre."""
    return -0.5 * height * pt / pn


# ---------------------------------------------------------------- the palm as a pendulum

def speed_squared(theta, theta0, v0, *, gravity, link_length):
    """v(th)^2 = v0^2 + 2 g l (cos th0 - cos th): palm (with a stuck object, or alone).

    cos th0 - cos th = 2 sin((th0 + th)/2) sin((th - th0)/2) (physics.manipulators.
    cos_difference, here in scalar math: this is evaluated inside the root finder)."""
    diff = 2.0 * math.sin(0.5 * (theta0 + theta)) * math.sin(0.5 * (theta - theta0))
    return v0 * v0 + 2.0 * gravity * link_length * diff


def energy_gap(theta0, v0, *, gravity, link_length):
    """E = C - 1 with C = cos th0 + v0^2 / (2 g l): v(th)^2 = 2 g l (E + 2 sin^2(th/2)).

    E > 0: the swing passes the top; E < 0: it turns where sin(th/2)^2 = -E/2. Written as
    v0^2 / (2 g l) - 2 sin^2(th0/2), without the cancellation of cos th0 - 1."""
    half = math.sin(0.5 * theta0)
    return v0 * v0 / (2.0 * gravity * link_length) - 2.0 * half * half


def turning_angle(theta0, v0, *, gravity, link_length, forward=True):
    """Angle where the swing from th0 at speed v0 stops (v = 0), or None if it passes the top.

    Moving forward from th0 < 0 the swing turns at -acos(cos th0 + v0^2 / (2 g l)); moving
    backward from th0 > 0 at +acos(...). Computed as 2 asin(sqrt(-E / 2)) (E = energy_gap),
    which keeps full relative accuracy for turning points near the top."""
    e = energy_gap(theta0, v0, gravity=gravity, link_length=link_length)
    if (forward and theta0 >= 0.0) or (not forward and theta0 <= 0.0) or e >= 0.0:
        return None
    turn = 2.0 * math.asin(min(1.0, math.sqrt(-0.5 * e)))
    return -turn if forward else turn


def swing_time(a, b, theta0, v0, *, gravity, link_length, turn=None):
    """Time to swing from angle a to b (|v| > 0 inside), energy fixed by (th0, v0).

    dt = l dth / v(th) with v^2 = 2 g l (E + 2 sin^2(th/2)) integrates in closed form to
    Carlson's R_F (exact to rounding):
      E > 0 (over the top): T(th) = sqrt(2 l / g) sin(th/2) R_F(E cos^2(th/2), E + 2 sin^2(th/2),
            E), the time from the top to th (odd in th); the swing time is |T(b) - T(a)|.
      E < 0 (turning at |th| = th_t, r = sin(th_t/2)): with s = sin(|th|/2), the time from the
            turning point is S(th) = 2 sqrt(l / g) sqrt(s - r) R_F((1 - r^2)(s + r),
            2 r (1 + r)(1 - s), 2 r (1 - r)(1 + s)) (Carlson's formula for a quartic with the
            turning point as a root), so the 1/sqrt singularity there is exact; s - r is taken
            as a product of sines. a and b lie on one side of the turning point.
      E = 0 (the top reached in infinite time): sqrt(l / g) |ln tan(|b|/4) - ln tan(|a|/4)|.
    `turn`, when given, is the turning angle the caller located (it fixes r)."""
    if a == b:
        return 0.0
    g, l = gravity, link_length
    e = energy_gap(theta0, v0, gravity=g, link_length=l)
    if turn is not None:
        half = math.sin(0.5 * abs(turn))
        e = -2.0 * half * half
    if e > 0.0:
        return math.sqrt(2.0 * l / g) * abs(_time_between(a, b, e))
    if e < 0.0:
        th_t = 2.0 * math.asin(min(1.0, math.sqrt(-0.5 * e))) if turn is None else abs(turn)
        return (2.0 * math.sqrt(l / g)
                * abs(_time_from_turn(b, th_t) - _time_from_turn(a, th_t)))
    if a * b <= 0.0:
        return math.inf
    return math.sqrt(l / g) * abs(math.log(math.tan(0.25 * abs(b)) / math.tan(0.25 * abs(a))))


def _time_between(a, b, e):
    """T(b) - T(a) of swing_time (E > 0, T(th) = sin(th/2) R_F(E cos^2(th/2), E + 2 sin^2(th/2),
    E) the scaled time from the top) with one R_F: by the addition theorem of
    F(phi | m), m = -2/E, F(phi_b) - F(phi_a) = F(sigma) with (D = E + 2 sa^2 sb^2, sx, cx the
    sine and cosine of phi_x = th_x / 2, Dx = sqrt(E + 2 sx^2))
        sin sigma = sqrt(E) (sb ca Da - sa cb Db) / D,  cos sigma = (E ca cb + sa sb Da Db) / D,
    and F(sigma) / sqrt(E) = sin sigma R_F(E cos^2 sigma, E + 2 sin^2 sigma, E) while
    |sigma| <= pi/2; beyond, F(sigma) = 2 K - F(pi - sigma). On one side of the top the
    numerator of sin(sigma) cancels; there it is sin(pb - pa) sin(pb + pa) D / (sb ca Da +
    sa cb Db) (multiply by the conjugate: ca^2 - cb^2 = sb^2 - sa^2 = sin(pb - pa) sin(pb + pa)).
    """
    sa, ca = math.sin(0.5 * a), math.cos(0.5 * a)
    sb, cb = math.sin(0.5 * b), math.cos(0.5 * b)
    da, db = math.sqrt(e + 2.0 * sa * sa), math.sqrt(e + 2.0 * sb * sb)
    d = e + 2.0 * sa * sa * sb * sb
    if sa * sb > 0.0:  # same side of the top: sb ca Da - sa cb Db = sin(pb - pa) sin(pb + pa) d
        s_unit = (math.sin(0.5 * (b - a)) * math.sin(0.5 * (b + a))
                  / (sb * ca * da + sa * cb * db))  # (sin(sigma) / sqrt(E), no cancellation)
    else:
        s_unit = (sb * ca * da - sa * cb * db) / d  # sin(sigma) / sqrt(E): the terms add
    c = (e * ca * cb + sa * sb * da * db) / d
    s2 = e * s_unit * s_unit  # sin^2(sigma)
    value = math.sqrt(e) * s_unit * carlson_rf(e * c * c, e + 2.0 * s2, e)
    if c < 0.0:  # |sigma| > pi/2
        value = math.copysign(2.0 * carlson_rf(0.0, e + 2.0, e), s_unit) - value
    return value


def _time_from_turn(theta, th_t):
    """sqrt(s - r) R_F(...) of swing_time, s = sin(|th|/2), r = sin(th_t/2); 0 at the turn."""
    x = abs(theta)
    if x <= th_t:
        return 0.0
    s, r = math.sin(0.5 * x), math.sin(0.5 * th_t)
    gap = 2.0 * math.cos(0.25 * (x + th_t)) * math.sin(0.25 * (x - th_t))  # s - r
    return math.sqrt(gap) * carlson_rf((1.0 - r * r) * (s + r), 2.0 * r * (1.0 + r) * (1.0 - s),
                                       2.0 * r * (1.0 - r) * (1.0 + s))


def free_palm_arrival(theta0, w0, *, gravity, link_length, back_stop, front_stop):
    """Where and when a palm swinging alone from (th0, speed w0 along t) comes to a stop.

    Returns (dt, stop_angle, speed_at_stop). A palm exactly balanced at the top never arrives."""
    g, l = gravity, link_length
    forward = w0 > 0.0 or (w0 == 0.0 and theta0 > 0.0)
    if w0 == 0.0 and theta0 == 0.0:
        return math.inf, 0.0, 0.0
    v0 = abs(w0)
    turn = turning_angle(theta0, v0, gravity=g, link_length=l, forward=forward)
    kw = dict(gravity=g, link_length=l)
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


def stuck_crossings(theta0, v0, cap, *, gravity, link_length, height, support, mu):
    """First crossings of the stuck carry's guards on [theta0, cap] (cap < pi/2), in closed form:
    [(angle, priority, kind)] for lift-off (0), tip (1) and slip (2): the start if already
    violated, else the root, on its violated side (so the next phase starts inside its guards).

      lift-off  v^2 - g l cos th = v0^2 + 2 g l cos th0 - 3 g l cos th: falls until th = 0, then
                rises through 0 at sin^2(th/2) = (g l (1 + 4 sin^2(th0/2)) - v0^2) / (6 g l);
      tip       the force point -h tan(th)/2 leaves the support [lo, hi]: -h tan th / 2 - hi
                falls (fires at the start or never), lo + h tan th / 2 rises through 0 at
                th = atan(-2 lo / h);
      slip      tan th - mu rises through 0 at atan(mu); -tan th - mu falls."""
    g, l = gravity, link_length
    lo, hi = support
    gl = g * l
    half = math.sin(0.5 * theta0)

    def lift(th):
        return lift_off_guard(th, theta0, v0, gravity=g, link_length=l)

    guards = [
        (lift, 0, "lift_off", None),
        (lambda th: stuck_force_point(th, height) - hi, 1, "tip", "falls"),
        (lambda th: lo - stuck_force_point(th, height), 1, "tip", math.atan(-2.0 * lo / height)),
        (lambda th: math.tan(th) - mu, 2, "slip", math.atan(mu)),
        (lambda th: -math.tan(th) - mu, 2, "slip", "falls"),
    ]
    share = (gl * (1.0 + 4.0 * half * half) - v0 * v0) / (6.0 * gl)
    lift_root = 2.0 * math.asin(math.sqrt(share)) if 0.0 <= share <= 1.0 else None
    out = []
    for guard, prio, kind, root in guards:
        if guard(theta0) >= 0.0:
            out.append((theta0, prio, kind))
            continue
        if root is None:
            root = lift_root
        if root == "falls" or root is None or not theta0 < root <= cap:
            continue
        for _ in range(16):  # the violated side of the root (a few ulp away at most)
            if guard(root) >= 0.0 or root >= cap:
                break
            root = math.nextafter(root, math.inf)
        if guard(root) >= 0.0:
            out.append((root, prio, kind))
    return out


# ---------------------------------------------------------------- sliding carry

@dataclass(frozen=True)
class SlideParams:
    m: float
    M: float  # the palm's mass felt along the swing (palm plus links: physics.palm_terms)
    mu: float
    gravity: float
    link_length: float
    sgn: float  # sign of the slip velocity s' (friction on the object is -mu N sgn)
    weight: float | None = None  # the mass whose weight turns the palm (M + links / 2; None: M)
    torque: float = 0.0  # Coulomb pivot friction torque (N m), against a forward swing
    damping: float = 0.0  # viscous pivot damping (N m s / rad)


def slide_accelerations(theta, omega, p: SlideParams):
    """(th'', N, s'', D) of the sliding carry (physics.slide_accelerations)."""
    return phys.slide_accelerations(
        theta, omega, object_mass=p.m, palm_mass=p.M, friction=p.mu, sgn=p.sgn,
        gravity=p.gravity, link_length=p.link_length, weight=p.weight,
        pivot=(p.torque + p.damping * omega) / p.link_length)


def slide_rhs(p: SlideParams):
    """Vector field of the sliding carry on the state (th, th', s, s')."""

    def rhs(t, y):
        thdd, _, sdd, _ = slide_accelerations(y[0], y[1], p)
        return [y[1], thdd, y[3], sdd]

    return rhs


def slide_direction(theta, omega, p: SlideParams) -> float:
    """Direction a slip starting from s' = 0 takes: the sgn whose s'' agrees with it."""
    for sgn in (1.0, -1.0):
        q = replace(p, sgn=sgn)
        _, _, sdd, _ = slide_accelerations(theta, omega, q)
        if sgn * sdd > 0.0:
            return sgn
    return -math.copysign(1.0, theta)


def slide_force_point(sgn, mu, height):
    """Where the sliding contact force N (-mu sgn, 1) crosses the base, from its centre."""
    return phys.slide_force_point(sgn, mu, height)


def object_state_on_palm(pivot, theta, omega, s, sd, link_length):
    """Object bottom centre and velocity when it sits at s on the palm (s' = sd)."""
    l = link_length
    x = pivot[0] + l * math.sin(theta) + s
    y = pivot[1] + l * math.cos(theta)
    return x, y, l * omega * math.cos(theta) + sd, -l * omega * math.sin(theta)


# ---------------------------------------------------------------- links and pivots

@dataclass(frozen=True)
class Swing:
    """A palm on real links and pivots swinging with `load` kg stuck on it (0: alone):
    inertia = load + M + J (kg along the swing), weight = load + M + W (kg whose weight turns it),
    torque (N m, Coulomb) and damping (N m s / rad) at the pivots (physics.palm_terms)."""

    inertia: float
    weight: float
    torque: float
    damping: float
    gravity: float
    link_length: float


def swing_acceleration(theta, omega, sw: Swing, direction=None):
    """th'' of Lagrange's equation (m + M + J) l^2 th'' = (m + M + W) g l sin th - tau sgn - d th'
    (docs/physics.md, section 2.1). direction: the sign the Coulomb torque opposes (default
    the sign of th'; at th' = 0 pass the direction the palm starts to move)."""
    sgn = math.copysign(1.0, omega) if direction is None else direction
    l = sw.link_length
    torque = sw.weight * sw.gravity * l * math.sin(theta) - sw.torque * sgn - sw.damping * omega
    return torque / (sw.inertia * l * l)


def swing_rhs(sw: Swing):
    """Vector field of (th, th') for the swing."""

    def rhs(t, y):
        return [y[1], swing_acceleration(y[0], y[1], sw)]

    return rhs


def held_by_friction(theta, sw: Swing) -> bool:
    """A palm at rest at theta stays there: its weight's torque is within the Coulomb torque."""
    return abs(sw.weight * sw.gravity * sw.link_length * math.sin(theta)) <= sw.torque


def stuck_contact_force(theta, omega, thdd, *, gravity, link_length):
    """(friction, normal) per object mass of the palm's force on the stuck object:
    m (A t + B r) with A = l th'' - g sin th, B = g cos th - l th'^2, so
    friction = A cos th + B sin th (along x), normal = B cos th - A sin th."""
    sn, cs = math.sin(theta), math.cos(theta)
    along = link_length * thdd - gravity * sn
    radial = gravity * cs - link_length * omega * omega
    return along * cs + radial * sn, radial * cs - along * sn
