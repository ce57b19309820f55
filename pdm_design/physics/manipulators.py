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

from .ops import cos, fabs, fmax, fmin, sin, sqrt, tan


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


def lift_off_capacity(theta, *, gravity, link_length):
    """g l cos theta: the squared speed below which the palm at theta still presses the stuck
    object (the contact force m (g cos th - v^2 / l) r is a push only while v^2 < g l cos th)."""
    return gravity * link_length * cos(theta)


def carry_force_point(theta, height):
    """Where the contact force on the stuck object crosses its base, from the base's centre,
    forward (+x) positive: friction / normal = tan th puts it (h / 2) tan th behind for th > 0
    and ahead for th < 0."""
    return -0.5 * height * tan(theta)


def friction_demand(theta):
    """Friction-to-normal force ratio needed to keep the object stuck at angle theta: |tan th|."""
    return fabs(tan(theta))


def parked_palm_clearance(n, *, alpha, theta_end, link_length, front_stop, pitch_x, pitch_y,
                          offset_lo, offset_hi, reach, depth, shift=0.0):
    """Clearance (m; >= 0: no contact) between the object carried on a palm from -alpha to
    theta_end and the palm n places behind, parked at its front stop (docs/optimizer.md).

    Relative to the carrying palm's pivot, the object's base centre is at (l sin th + o, l cos th)
    (o: its offset on the palm, in [offset_lo, offset_hi]) and the parked palm's top centre at
    (l sin f - n pitch_x, l cos f + n pitch_y) (f: the front stop), the relative move of the two
    pivots at most `shift` on either axis. They touch inside the box |gap_x| < reach = (w + W)/2,
    -depth < gap_y < 0 (depth = T + h). Along the carry l sin th increases, so the object
    overlaps the parked palm along the row while lo < l sin th < hi (one interval). No contact
    iff the parked palm stays ahead (lo >= l sin theta_end), or the object starts past it
    (hi <= -l sin alpha), or the object is above the parked top wherever they overlap (on the
    falling side, the overlap ends before |sin th| exceeds s_top, the sine where l cos th meets
    the top; likewise on the rising side), or below its underside wherever they overlap (the
    overlap stays outside |sin th| < s_low). Exact with shift = 0 and one offset; with ranges an
    outer bound. Only sines, cosines and square roots under max and min: no asin, whose clipped
    arguments had stalled IPOPT (4 of 8 starts at 500 iterations on a random spec).
    """
    l = link_length
    base = l * sin(front_stop) - n * pitch_x
    lo = base - reach - offset_hi - shift  # overlap along the row: lo < l sin th < hi
    hi = base + reach - offset_lo + shift
    top = l * cos(front_stop) + n * pitch_y + shift  # the object must stay at or above
    low = top - 2.0 * shift - depth  # or at or below
    s_top = _sine_of_height(top / l, lower=True)
    s_low = _sine_of_height(low / l, lower=False)
    ahead = lo - l * sin(theta_end)
    behind = -l * sin(alpha) - hi
    above = fmin(fmax(l * s_top - hi, l * (s_top - sin(theta_end))),
                 fmax(lo + l * s_top, l * (s_top - sin(alpha))))
    below = fmax(low - l, fmax(-l * s_low - hi, lo - l * s_low))
    return fmax(fmax(ahead, behind), fmax(above, below))


def _sine_of_height(ratio, *, lower):
    """sin th >= 0 where cos th = ratio, ratio clipped to [0, 1] (cos th > 0 on a carry): a lower
    (lower=True) or upper bound within 1e-6, with a finite slope at ratio 1 (no inf * 0 where
    the clip's slope is 0 in an NLP's or a linearisation's derivatives)."""
    c = fmin(fmax(ratio, 0.0), 1.0)
    tiny = 1e-12
    return sqrt(1.0 - c * c + tiny) - (sqrt(tiny) if lower else 0.0)
