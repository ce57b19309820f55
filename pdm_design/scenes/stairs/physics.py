"""Closed forms of a ball bouncing down stairs (paper, section 3.1 and 3.2), derived afresh.

Frame: x along the stairs (downhill), y up; spin omega is counter-clockwise positive, so a ball
rolling without slip in +x has ``vx = -radius * omega``. Heights are of the ball's lowest point.

Frictionless (Newton restitution eps, no tangential impulse), launched horizontally at speed v0
with its lowest point h0 above the first tread:
    vertical impact speed  v = sqrt(2 g h0);        rebound  eps * v
    periodic drop          rise  = (1 - eps^2) h0   (same impact speed on every tread)
    time between impacts   T = (1 + eps) v / g
    periodic step length   tread = vx * T
With friction the first impact may change vx and omega (rolling_impact); afterwards the contact
point is at rest at every impact, no tangential impulse is needed, and vx stays constant.

Step-nose clearance (flight_clearances, launch_clearances, from corner_gaps and corner_heights):
the exact gap between the ball (a disc of radius r) and a nose corner its flight passes, from the
closed-form nearest point of the centre's parabola (docs/physics.md, "Nose clearance, exactly"),
over the flight up to its landing. Written with the ops dispatch like every closed form here: the
analysis calls them on floats, and the NLP's exact nose rows on CasADi symbols (only when a spec
asks for them: they cost IPOPT iterations, docs/optimizer.md, section 2).
"""

from __future__ import annotations

import math

from ...physics.ops import (
    acos,
    acosh,
    asinh,
    cos,
    cosh,
    fabs,
    fmax,
    fmin,
    is_symbolic,
    sinh,
    sqrt,
    where,
)

_TINY = 1e-30  # keeps the unused branch of a root formula finite
# keeps acos / acosh off their infinite-slope ends; that moves a root (by ~1e-6 of itself) only next
# to a double root, where the distance is flat to third order
_EDGE = 1e-12


def impact_speed_vertical(gravity, drop_height):
    """Vertical speed at an impact after falling drop_height from rest vertically: sqrt(2 g h)."""
    return sqrt(2.0 * gravity * drop_height)


def periodic_rise(drop_height, restitution):
    """Step rise that makes every impact equal to the first: (1 - eps^2) h0."""
    return (1.0 - restitution**2) * drop_height


def periodic_vertical_speed(gravity, rise, restitution):
    """Vertical impact speed of the orbit with one bounce a step of `rise`: each bounce leaves at
    eps v* and falls `rise` further, so v*^2 (1 - eps^2) = 2 g rise; 1 - eps^2 is taken as
    (1 - eps)(1 + eps), exact as eps -> 1. (A rise of (1 - eps^2) h0 gives sqrt(2 g h0).)"""
    return sqrt(2.0 * gravity * rise / ((1.0 - restitution) * (1.0 + restitution)))


def flight_time(gravity, drop_height, restitution):
    """Time between two periodic impacts: (1 + eps) sqrt(2 h0 / g)."""
    return (1.0 + restitution) * sqrt(2.0 * drop_height / gravity)


def rolling_impact(vx, omega, *, radius, mass, inertia):
    """Velocities after an impact that ends in rolling without slip: (vx+, omega+).

    Tangential impulse P acts at the contact point (0, -r) from the centre:
        m (vx+ - vx) = P,   J (omega+ - omega) = r P,   vx+ = -r omega+.
    Eliminating P gives vx+ = (m r^2 vx - J r omega) / (m r^2 + J) and omega+ = -vx+ / r.
    (The paper's eq. 14 drops the minus sign of omega+; see docs/physics.md.)
    """
    mr2 = mass * radius**2
    vx_after = (mr2 * vx - inertia * radius * omega) / (mr2 + inertia)
    return vx_after, -vx_after / radius


def sliding_impact(vx, omega, vy_impact, restitution, friction, *, radius, mass, inertia):
    """Velocities after an impact friction cannot end in rolling: (vx+, omega+).

    The contact slides throughout, so the tangential impulse is Coulomb's whole
    P = -sign(c) mu m (1 + eps) |vy|, c = vx + r omega, at the contact point (0, -r):
    m (vx+ - vx) = P, J (omega+ - omega) = r P.
    """
    slip = vx + radius * omega
    against = where(slip >= 0.0, -1.0, 1.0)  # the impulse opposes the slip
    impulse = against * friction * mass * (1.0 + restitution) * fabs(vy_impact)
    return vx + impulse / mass, omega + radius * impulse / inertia


def rolling_impulse_ratio(vx, omega, vy_impact, restitution, *, radius, mass, inertia):
    """|tangential impulse| / normal impulse that rolling-without-slip requires at an impact.

    The contact point slides at c = vx + r omega; stopping it takes |P| = |c| m J / (J + m r^2).
    The normal impulse is m (1 + eps) |vy|. Coulomb friction can stop the slip during the impact
    exactly when this ratio is at most mu.
    """
    slip = vx + radius * omega
    tangential = fabs(slip) * mass * inertia / (inertia + mass * radius**2)
    normal = mass * (1.0 + restitution) * fabs(vy_impact)
    return tangential / normal


RISER_KNEE = 1e-3  # (x radius) below this rise, riser_reach is its tangent line


def riser_reach(rise, radius):
    """How far ahead of the riser behind it the ball's centre must land for its disc to clear
    the riser: the radius when the riser is at least that high; below, the disc resting on the
    tread (centre `radius` above it) only meets the riser's top corner, at distance
    sqrt(x^2 + (radius - rise)^2) = radius when x = sqrt(rise (2 radius - rise)). Under
    RISER_KNEE radii that square root's slope grows without bound (IPOPT stalled on a flat
    floor, the optimum of a restitution free up to 1): there its tangent at the knee, above it
    (the root is concave), at most 0.023 radius at a rise of 0. A point ball's reach is 0."""
    if not is_symbolic(radius) and radius == 0.0:
        return 0.0 * rise
    low = fmin(fmax(rise, 0.0), radius)  # the part of the riser the disc can reach
    knee = RISER_KNEE * radius
    at_knee = math.sqrt(knee * (2.0 - RISER_KNEE) * radius)
    tangent = at_knee + (radius - knee) / at_knee * (low - knee)
    return where(low >= knee, sqrt(fmax(low * (2.0 * radius - low), 0.0)), tangent)


def periodic_tread(vx, gravity, drop_height, restitution):
    """Horizontal distance between periodic impacts (paper eqs. 9 and 18): vx T."""
    return vx * flight_time(gravity, drop_height, restitution)


def periodic_impact_speed(vx, gravity, drop_height):
    """Speed of the ball just before each periodic impact: sqrt(vx^2 + 2 g h0)."""
    return sqrt(vx**2 + 2.0 * gravity * drop_height)


def corner_gaps(vx, gravity, apex_height, corner_dx, start_dx, radius, end_dx=None):
    """(start, rising, falling): the ball's gaps (m) to a corner it flies past.

    Frame of the flight's apex: the centre is at (u, H - u^2 / (2 R)) for start_dx <= u <= end_dx,
    with H = apex_height its height above the corner, R = vx^2 / g the path's radius of curvature
    at the apex, start_dx <= 0 where the flight starts (0: launched at its apex) and end_dx >= 0
    where it lands (None: never); the corner is at (corner_dx, 0). Each gap is a distance from the
    corner to the centre less the radius (negative: they overlap): start, at the start; rising,
    the smallest over (start_dx, 0) when it is inside, else not below `start`; falling, the
    smallest over [0, end_dx]. So the smallest of the three is the smallest gap of the whole
    flight, exactly. (Past the landing the parabola can come nearer the corner: a ball of radius
    above the rise lands with its centre above the nose level, 14 mm nearer for radius 0.3 m and
    rise 0.0975 m.)

    The squared distance is a quartic in u; its local minima are the smallest and the largest real
    root of its derivative, the depressed cubic (u/R)^3 + 2 (1 - H/R) (u/R) - 2 corner_dx/R = 0,
    so the minimum over an interval is at an end or at one of those roots clipped into it. A root
    before the start adds its squared distance to the start (C1, and never below `start`): that
    keeps the take-off out of `rising`, whose gap goes flat (d^2 / 2r) as a take-off d behind the
    corner nears it, and which the optimizer need not back off from (the ball leaves the corner
    there). Each gap is C1 where one root is the minimiser (a clipped root moves the distance to
    second order only).
    """
    R = vx**2 / gravity

    def dist2(u):
        return (u - corner_dx) ** 2 + (apex_height - u**2 / (2.0 * R)) ** 2

    def rising_at(root):
        return dist2(fmin(fmax(root, start_dx), 0.0)) + fmax(start_dx - root, 0.0) ** 2

    p, q = 2.0 * (1.0 - apex_height / R), -2.0 * corner_dx / R
    low, high = -R * _largest_root(p, -q), R * _largest_root(p, q)
    def falling_at(root):  # the root clipped into [0, end_dx]
        inside = fmax(root, 0.0)
        return dist2(inside if end_dx is None else fmin(inside, end_dx))

    rising = fmin(rising_at(low), rising_at(high))
    falling = fmin(dist2(0.0), fmin(falling_at(low), falling_at(high)))
    return (sqrt(dist2(start_dx)) - radius, sqrt(rising) - radius, sqrt(falling) - radius)


def corner_heights(vx, gravity, apex_height, corner_dx, radius):
    """(rising, falling): height (m) of the ball's lowest point above the corner's level where the
    centre passes over the corner, on the apex's side (rising: corner_dx clipped to <= 0, falling:
    to >= 0; frame of `corner_gaps`). Negative rising: the corner is behind the take-off (the ball
    landed beyond the nose); negative falling: the ball comes down before the corner."""
    R = vx**2 / gravity
    before, after = fmin(corner_dx, 0.0), fmax(corner_dx, 0.0)
    return (apex_height - radius - before**2 / (2.0 * R),
            apex_height - radius - after**2 / (2.0 * R))


def _largest_root(p, q):
    """Largest real root of u^3 + p u + q = 0, by Chebyshev's hyperbolic and trigonometric forms.

    p >= 0: one root, -2 a sinh(asinh(q / (2 a^3)) / 3), a = sqrt(p/3). p < 0, m = sqrt(-p/3),
    x = -q / (2 m^3): |x| <= 1, three roots, the largest 2 m cos(acos(x) / 3); |x| > 1, one root,
    sign(x) 2 m cosh(acosh(|x|) / 3). Every branch is evaluated on clipped arguments (`where`
    evaluates both sides), so none is NaN.
    """
    a = sqrt(fmax(p / 3.0, _TINY**2))  # sqrt never at 0: its infinite slope would give NaN
    single_p = -2.0 * a * sinh(asinh(q / (2.0 * a**3)) / 3.0)
    m = sqrt(fmax(-p / 3.0, _TINY**2))
    x = -q / (2.0 * m**3)
    three = 2.0 * m * cos(acos(fmin(fmax(x, _EDGE - 1.0), 1.0 - _EDGE)) / 3.0)
    single_m = 2.0 * m * cosh(acosh(fmax(fabs(x), 1.0 + _EDGE)) / 3.0)
    return where(p >= 0.0, single_p,
                 where(x > 1.0, single_m, where(x >= -1.0, three, -single_m)))


def flight_clearances(vx, vy_up, gravity, radius, nose_dx, rise):
    """Clearances (m) of a flight leaving a tread at (vx > 0, vy_up) from the contact point, the
    tread's nose nose_dx ahead at the same level, to land on the tread `rise` below:
    (behind, start, rising, falling, beyond) =
        behind  lowest point above the nose level where the centre passes over the nose, on the
                rising side (negative: the take-off is beyond the nose, nose_dx < 0)
        start, rising, falling   gaps to the nose corner (`corner_gaps`): at the take-off, while
                the ball rises, while it comes down
        beyond  as `behind`, on the falling side (negative: it comes down before the nose).
    The flight clears the step iff all five are >= 0 (the riser below the nose is never nearer
    than the corner to a ball that clears it). Its centre's apex is vy_up vx / g ahead, r +
    vy_up^2 / (2 g) above the contact point."""
    apex_dx = vy_up * vx / gravity
    apex_height = radius + vy_up**2 / (2.0 * gravity)
    land_dx = vx * sqrt(vy_up**2 + 2.0 * gravity * rise) / gravity  # apex to landing
    gaps = corner_gaps(vx, gravity, apex_height, nose_dx - apex_dx, -apex_dx, radius, land_dx)
    behind, beyond = corner_heights(vx, gravity, apex_height, nose_dx - apex_dx, radius)
    return (behind, *gaps, beyond)


def launch_clearances(v0, gravity, radius, height, nose_dx, rise):
    """Clearances (m) of the launch over the top landing: horizontal at v0 from its apex, the
    lowest point `height` above the landing, its nose nose_dx ahead (negative: already past it),
    to land on tread 1 `rise` below it: (falling, beyond) as in `flight_clearances`. `beyond` asks
    height >= 0 even when the launch is past the nose (exact for a launch above the landing; a
    launch below it is not modelled)."""
    land_dx = v0 * sqrt(2.0 * fmax(height + rise, 0.0) / gravity)
    _, _, falling = corner_gaps(v0, gravity, height + radius, nose_dx, 0.0, radius, land_dx)
    _, beyond = corner_heights(v0, gravity, height + radius, nose_dx, radius)
    return falling, beyond
