"""Closed forms of an object passed along a row of parallelogram manipulators (paper, 3.3).

Frame: origin at the first pivot, x along the row, y up. A manipulator's angle theta is measured
clockwise from the vertical; the palm stays horizontal and its top surface centre is at
pivot + l (sin theta, cos theta). It rests on a back stop at theta = -alpha and hands the object
over at theta = beta. Unit vectors: radial r = (sin th, cos th), tangent t = (cos th, -sin th).

Derivations (docs/physics.md has them in full):
* Plastic landing of the object (mass m) on the resting palm (mass M): the massless links carry
  only radial impulse, so momentum along t at -alpha is kept by object + palm:
      u = m / (m + M) * (V . t(-alpha)),   t(-alpha) = (cos a, sin a).
* Carry with the object stuck: the palm translates on the circle like a point pendulum,
      l theta'' = g sin theta,   v(theta)^2 = u^2 + 2 g l (cos a - cos theta).
* Contact force on the stuck object: m (g cos th - v^2 / l) along r. Hence lift-off when
  v^2 > g l cos th, friction/normal = tan th (slip when |tan th| > mu) and the force crosses the
  object's base (h/2) tan th behind its centre (tipping when that leaves the support).
* Handover at beta with speed s onto the next palm at -alpha: V . t(-alpha) = s cos(alpha + beta).
  The paper's eq. 28 writes cos(beta - alpha): cos b cos a - sin b sin a is cos(a + b).
  Fixed point of s'^2 = c s^2 + D with c = (m/(m+M))^2 cos^2(a+b), D = 2 g l (cos a - cos b):
      s*^2 = D / (1 - c),   and ds'/ds = c at s*: the contraction factor.
"""

from __future__ import annotations

from .ops import cos, fabs, sin, sqrt, tan


def momentum_fraction(mass_ratio):
    """m / (m + M) written with the mass ratio q = m / M: q / (1 + q)."""
    return mass_ratio / (1.0 + mass_ratio)


def landing_speed(vx, vy, alpha, mass_ratio):
    """Speed u of object + palm just after a plastic landing at -alpha (paper eq. 21)."""
    return momentum_fraction(mass_ratio) * (vx * cos(alpha) + vy * sin(alpha))


def landing_impulse(vx, vy, alpha, mass_ratio):
    """Impulse per object mass the palm gives the object at a plastic sticking landing: (px, py)."""
    u = landing_speed(vx, vy, alpha, mass_ratio)
    return u * cos(alpha) - vx, u * sin(alpha) - vy


def cos_difference(a, b):
    """cos a - cos b = 2 sin((a+b)/2) sin((b-a)/2), exact to rounding even for tiny angles."""
    return 2.0 * sin(0.5 * (a + b)) * sin(0.5 * (b - a))


def carry_speed_squared(u, alpha, theta, *, gravity, link_length):
    """v(theta)^2 on the carry arc after leaving -alpha at speed u (energy conservation)."""
    return u**2 + 2.0 * gravity * link_length * cos_difference(alpha, theta)


def top_speed_squared_needed(alpha, *, gravity, link_length):
    """u^2 needed to carry the object from -alpha over the top (theta = 0): 2 g l (1 - cos a)."""
    return 4.0 * gravity * link_length * sin(0.5 * alpha) ** 2


def contraction(alpha, beta, mass_ratio):
    """Slope of the handover-speed map at its fixed point: (m/(m+M))^2 cos^2(alpha + beta)."""
    return (momentum_fraction(mass_ratio) * cos(alpha + beta)) ** 2


def energy_gain_squared(alpha, beta, *, gravity, link_length):
    """D = 2 g l (cos a - cos b): what one carry adds to the squared speed."""
    return 2.0 * gravity * link_length * cos_difference(alpha, beta)


def contraction_complement(alpha, beta, mass_ratio):
    """1 - c without cancellation: (1 - k cos x)(1 + k cos x), k = m/(m+M), x = a + b, using
    1 - k cos x = 1/(1+q) + 2 k sin^2(x/2) (exact when k -> 1 and x -> 0)."""
    k = momentum_fraction(mass_ratio)
    x = alpha + beta
    return (1.0 / (1.0 + mass_ratio) + 2.0 * k * sin(0.5 * x) ** 2) * (1.0 + k * cos(x))


def handover_speed_squared(alpha, beta, mass_ratio, *, gravity, link_length):
    """Squared fixed-point handover speed s*^2 = D / (1 - c); not positive when beta <= alpha."""
    gain = energy_gain_squared(alpha, beta, gravity=gravity, link_length=link_length)
    return gain / contraction_complement(alpha, beta, mass_ratio)


def next_handover_speed(speed, alpha, beta, mass_ratio, *, gravity, link_length):
    """One step of the handover-speed map s -> sqrt(c s^2 + D) (nominal geometry, stuck carry)."""
    c = contraction(alpha, beta, mass_ratio)
    d = energy_gain_squared(alpha, beta, gravity=gravity, link_length=link_length)
    return sqrt(c * speed**2 + d)


def paper_handover_speed_squared(alpha, beta, mass_ratio, *, gravity, link_length):
    """The paper's eq. 29/30 as printed, with cos(beta - alpha): kept only to show it is wrong."""
    k = momentum_fraction(mass_ratio)
    d = energy_gain_squared(alpha, beta, gravity=gravity, link_length=link_length)
    return d / (1.0 - (k * cos(beta - alpha)) ** 2)


def pitch(alpha, beta, link_length):
    """(x, y) from one pivot to the next: l (sin a + sin b) along, l (cos a - cos b) down."""
    return (
        link_length * (sin(alpha) + sin(beta)),
        link_length * cos_difference(alpha, beta),
    )


def palm_centre(pivot_x, pivot_y, theta, link_length):
    """Centre of the palm's top surface at angle theta."""
    return pivot_x + link_length * sin(theta), pivot_y + link_length * cos(theta)


def lift_off_ratio(speed_squared, theta, *, gravity, link_length):
    """v^2 / (g l cos theta): the palm's normal force vanishes when this reaches 1."""
    return speed_squared / (gravity * link_length * cos(theta))


def friction_demand(theta):
    """Friction-to-normal force ratio needed to keep the object stuck at angle theta: |tan th|."""
    return fabs(tan(theta))
