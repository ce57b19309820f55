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
"""

from __future__ import annotations

from .ops import fabs, sqrt


def impact_speed_vertical(gravity, drop_height):
    """Vertical speed at an impact after falling drop_height from rest vertically: sqrt(2 g h)."""
    return sqrt(2.0 * gravity * drop_height)


def periodic_rise(drop_height, restitution):
    """Step rise that makes every impact equal to the first: (1 - eps^2) h0."""
    return (1.0 - restitution**2) * drop_height


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


def periodic_tread(vx, gravity, drop_height, restitution):
    """Horizontal distance between periodic impacts (paper eqs. 9 and 18): vx T."""
    return vx * flight_time(gravity, drop_height, restitution)


def periodic_impact_speed(vx, gravity, drop_height):
    """Speed of the ball just before each periodic impact: sqrt(vx^2 + 2 g h0)."""
    return sqrt(vx**2 + 2.0 * gravity * drop_height)
