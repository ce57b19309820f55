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

import math

from ...physics.ops import asin, cos, fabs, fmax, fmin, sin, sqrt, tan, where


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


def carry_speed_squared(u, alpha, theta, *, gravity, link_length, friction=0.0):
    """v(theta)^2 on the carry arc after leaving -alpha at speed u (energy balance).

    With links and pivot friction (carry_terms) gravity is the carry's effective gravity and
    friction the Coulomb pivot torque per carried mass: its work over the swing from -alpha
    takes 2 friction (theta + alpha) off v^2 (a monotone forward swing)."""
    return (u**2 + 2.0 * gravity * link_length * cos_difference(alpha, theta)
            - 2.0 * friction * (theta + alpha))


def top_speed_squared_needed(alpha, *, gravity, link_length, friction=0.0):
    """u^2 needed to carry the object from -alpha over the top: 2 g l (1 - cos a) without pivot
    friction. With it the swing slows down until gravity's push beats the friction, at
    sin th* = friction / (g l) past the top (friction_balance_angle), so the speed must stay
    positive up to th*: u^2 > 2 g l (cos th* - cos a) + 2 friction (a + th*)."""
    need = 4.0 * gravity * link_length * sin(0.5 * alpha) ** 2
    if is_exact_zero(friction):
        return need
    star = friction_balance_angle(friction, gravity=gravity, link_length=link_length)
    return (need - 4.0 * gravity * link_length * sin(0.5 * star) ** 2
            + 2.0 * friction * (alpha + star))


def friction_balance_angle(friction, *, gravity, link_length):
    """th* past the top where the carry's gravity torque equals the pivot friction torque:
    sin th* = friction / (g l) (clipped to pi/2: friction that gravity never beats)."""
    return asin(fmin(friction / (gravity * link_length), 1.0))


def contraction(alpha, beta, mass_ratio):
    """Slope of the handover-speed map at its fixed point: (m/(m+M))^2 cos^2(alpha + beta)."""
    return (momentum_fraction(mass_ratio) * cos(alpha + beta)) ** 2


def energy_gain_squared(alpha, beta, *, gravity, link_length, friction=0.0):
    """D = 2 g l (cos a - cos b) - 2 friction (a + b): what one carry adds to the squared
    speed (carry_speed_squared)."""
    return (2.0 * gravity * link_length * cos_difference(alpha, beta)
            - 2.0 * friction * (alpha + beta))


def contraction_complement(alpha, beta, mass_ratio):
    """1 - c without cancellation: (1 - k cos x)(1 + k cos x), k = m/(m+M), x = a + b, using
    1 - k cos x = 1/(1+q) + 2 k sin^2(x/2) (exact when k -> 1 and x -> 0)."""
    k = momentum_fraction(mass_ratio)
    x = alpha + beta
    return (1.0 / (1.0 + mass_ratio) + 2.0 * k * sin(0.5 * x) ** 2) * (1.0 + k * cos(x))


def handover_speed_squared(alpha, beta, mass_ratio, *, gravity, link_length, friction=0.0):
    """Squared fixed-point handover speed s*^2 = D / (1 - c); not positive when beta <= alpha
    (or when pivot friction takes more than gravity gives)."""
    gain = energy_gain_squared(alpha, beta, gravity=gravity, link_length=link_length,
                               friction=friction)
    return gain / contraction_complement(alpha, beta, mass_ratio)


def next_handover_speed(speed, alpha, beta, mass_ratio, *, gravity, link_length, friction=0.0):
    """One step of the handover-speed map s -> sqrt(c s^2 + D) (nominal geometry, stuck carry)."""
    c = contraction(alpha, beta, mass_ratio)
    d = energy_gain_squared(alpha, beta, gravity=gravity, link_length=link_length,
                            friction=friction)
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


def lift_off_capacity(theta, *, gravity, link_length, along=None):
    """g l cos theta: the squared speed below which the palm at theta still presses the stuck
    object (the contact force m (g cos th - v^2 / l) r is a push only while v^2 < g l cos th).

    along: A = l th'' - g sin th (carry_along), the object's tangential acceleration beyond
    gravity's when links or pivot friction are modelled; the palm's force is then
    m (A t + (g cos th - v^2 / l) r), whose normal part N / m = (g cos th - v^2/l) cos th -
    A sin th is a push while v^2 < g l cos th - l A tan th. None: A = 0 (the paper's device)."""
    held = gravity * link_length * cos(theta)
    return held if along is None else held - link_length * along * tan(theta)


def carry_force_point(theta, height, ratio=None):
    """Where the contact force on the stuck object crosses its base, from the base's centre,
    forward (+x) positive: friction / normal = tan th puts it (h / 2) tan th behind for th > 0
    and ahead for th < 0 (ratio: friction / normal when it is not tan th, carry_force_ratio)."""
    return -0.5 * height * (tan(theta) if ratio is None else ratio)


def friction_demand(theta, ratio=None):
    """Friction-to-normal force ratio needed to keep the object stuck at angle theta: |tan th|
    (|ratio| when links or pivot friction make it speed-dependent: carry_force_ratio)."""
    return fabs(tan(theta) if ratio is None else ratio)


def slide_accelerations(theta, omega, *, object_mass, palm_mass, friction, sgn, gravity,
                        link_length, weight=None, pivot=0.0):
    """Accelerations and normal force of the sliding carry (the object sliding on a palm that
    swings at th' = omega; sgn the sign of the slip speed s', the friction on the object -mu N
    sgn).

    Object: m (l th'' t - l th'^2 r + s'' i) = (-f, N - m g), f = mu N sgn.
    Palm along t: M l th'' = f cos th + N sin th + M g sin th. With c = mu sgn cos th + sin th:
      th'' = [m c (g - l th'^2 cos th) + M g sin th] / (l (M + m c sin th))
    (with links and pivots: M is the palm-plus-links mass felt along the swing, M g becomes the
    `weight` that turns the palm, and `pivot` = (tau + d th') / l is taken off the numerator:
    the phase moves forward, th' >= 0)
      N    = m (g - l th'' sin th - l th'^2 cos th)
      s''  = -mu sgn N / m - l th'' cos th + l th'^2 sin th
    Returns (th'', N, s'', D) with D = M + m c sin th (the sliding contact is consistent iff
    D > 0)."""
    m, M, mu, g, l = object_mass, palm_mass, friction, gravity, link_length
    sn, cs = sin(theta), cos(theta)
    c = mu * sgn * cs + sn
    d = M + m * c * sn
    w2 = omega * omega
    weight = M if weight is None else weight
    thdd = (m * c * (g - l * w2 * cs) + weight * g * sn - pivot) / (l * d)
    normal = m * (g - l * thdd * sn - l * w2 * cs)
    sdd = -mu * sgn * normal / m - l * thdd * cs + l * w2 * sn
    return thdd, normal, sdd, d


def slide_force_point(sgn, friction, height):
    """Where the sliding contact force N (-mu sgn, 1) crosses the object's base, from its
    centre."""
    return 0.5 * height * friction * sgn


# ---------------------------------------------------------------- the mechanism as built
# Palm (mass M) on a parallelogram of links whose inertia about their pivots is I (all links)
# and whose weight acts at half their length (a link symmetric end to end), with a Coulomb
# friction torque tau summed over the joints. Lagrange's equation of palm + links + stuck object
# in theta (docs/physics.md, section 2.1):
#     (m + M + J) l^2 th'' = (m + M + W) g l sin th - tau sgn(th'),  J = I / l^2, W = m_links / 2
# so the carry is the paper's with an effective gravity g (m + M + W) / (m + M + J) and a friction
# per carried mass tau / (m + M + J), and the landing's momentum fraction is m / (m + M + J).

def links_inertia_mass(*, link_mass, link_length, link_inertia=None):
    """J = I / l^2 (kg): the links' inertia about their pivots felt as a mass along the swing.
    link_mass and link_inertia are of all links together; None: uniform rods, I = m l^2 / 3."""
    return link_mass / 3.0 if link_inertia is None else link_inertia / link_length**2


def carry_terms(mass_ratio, *, object_mass, gravity, link_length, link_mass=0.0,
                link_inertia=None, friction_torque=0.0):
    """(q_e, g_e, f) of the carry of the stuck object by palm + links:
    q_e = m / (M + J) (the momentum fraction at a landing is q_e / (1 + q_e)),
    g_e = g (m + M + W) / (m + M + J) (the carry's effective gravity, W = link_mass / 2) and
    f = tau / (m + M + J) (the pivot friction torque per carried mass, m^2/s^2 per radian).
    With no links and no friction these are q, g and 0 exactly (bit for bit)."""
    q, m = mass_ratio, object_mass
    j = links_inertia_mass(link_mass=link_mass, link_length=link_length,
                           link_inertia=link_inertia)
    # the same values, without 0 * symbol in an NLP
    if is_exact_zero(j) and is_exact_zero(link_mass):
        q_e, g_e = q, gravity
    else:
        q_e = q / (1.0 + q * (j / m))
        g_e = gravity * (1.0 + q + q * (0.5 * link_mass / m)) / (1.0 + q + q * (j / m))
    f = 0.0 if is_exact_zero(friction_torque) else (friction_torque / m) * momentum_fraction(q_e)
    return q_e, g_e, f


def palm_terms(mass_ratio, *, object_mass, gravity, link_length, link_mass=0.0,
               link_inertia=None, friction_torque=0.0):
    """(M_e, g_p, f_p) of the palm swinging alone: M_e = M + J (kg, the palm-plus-links mass felt
    along the swing), g_p = g (M + W) / (M + J), f_p = tau / (M + J)."""
    palm = object_mass / mass_ratio
    j = links_inertia_mass(link_mass=link_mass, link_length=link_length,
                           link_inertia=link_inertia)
    felt = palm + j
    return felt, gravity * (palm + 0.5 * link_mass) / felt, friction_torque / felt


def carry_along(theta, *, gravity, carry_gravity, friction, link_length):
    """A = l th'' - g sin th on a forward stuck carry: the object's tangential acceleration
    beyond what gravity alone gives it, (g_e - g) sin th - f / l (zero on the paper's device;
    f, carry_terms' friction, is a torque per carried mass: l^2 th'' = g_e l sin th - f)."""
    return (carry_gravity - gravity) * sin(theta) - friction / link_length


def carry_contact_force(theta, v2, *, gravity, link_length, along):
    """(friction, normal) per object mass of the palm's force m (A t + (g cos th - v^2 / l) r)
    on the stuck object moving at v (v2 = v^2): its parts along the palm (x) and across it,
    A cos th + B sin th and B cos th - A sin th, B = g cos th - v^2 / l."""
    radial = gravity * cos(theta) - v2 / link_length
    return along * cos(theta) + radial * sin(theta), radial * cos(theta) - along * sin(theta)


def carry_force_ratio(theta, v2, *, gravity, link_length, along):
    """Friction / normal of the palm's force m (A t + (g cos th - v^2 / l) r) on the stuck object
    moving at v (v2 = v^2): tan th + A / (cos th N / m), N / m = (g cos th - v^2 / l) cos th -
    A sin th (the friction part A cos th + (g cos th - v^2 / l) sin th over N)."""
    normal = (gravity * cos(theta) - v2 / link_length) * cos(theta) - along * sin(theta)
    return tan(theta) + along / (cos(theta) * normal)


def carry_contact_curvature(*, carry_gravity, fastest_u2, friction, link_length, span):
    """S >= |d2N/dth2| and |d2F/dth2| (per object mass, carry_contact_force) along a forward
    stuck carry from any stop a in [0, span] to any th with th + a <= span, landing speed
    u^2 <= fastest_u2 (docs/physics.md section 2.1). With c = cos th, s = sin th, k = f / l and
    P = u^2 / l + 2 g_e cos a the closed-form carry gives
        N = g - g_e + 3 g_e c^2 - P c + k (2 (th + a) c + s),
        F = s (3 g_e c - P + 2 k (th + a)) - k c,
        N'' = -6 g_e cos 2th + P c - k (5 s + 2 (th + a) c),
        F'' = -6 g_e sin 2th + P s + k (5 c - 2 (th + a) s),
    so both are at most 6 g_e + P + k (5 + 2 span) <= 8 g_e + u^2 / l + k (5 + 2 span)."""
    return (8.0 * carry_gravity + fastest_u2 / link_length
            + friction / link_length * (5.0 + 2.0 * span))


def carry_contact_at(theta, u, alpha, *, gravity, carry_gravity, friction, link_length):
    """(friction, normal) per object mass on the stuck object at theta of a closed-form carry
    that left -alpha at speed u (carry_speed_squared, carry_along, carry_contact_force)."""
    v2 = carry_speed_squared(u, alpha, theta, gravity=carry_gravity, link_length=link_length,
                             friction=friction)
    along = carry_along(theta, gravity=gravity, carry_gravity=carry_gravity, friction=friction,
                        link_length=link_length)
    return carry_contact_force(theta, v2, gravity=gravity, link_length=link_length, along=along)


# Cells of a real-link carry whose ends hold its contact rows with the curvature bound's
# allowance (docs/physics.md section 2.1): the NLP's (formulation/rows.py), the analysis' and
# the stage maps' (formulation/offsets.py)
CARRY_CELLS = 8


def carry_contact_nodes(u, alpha, *, start, end, fastest_u2, gravity, carry_gravity, friction,
                        link_length, cells):
    """The whole carry's cells (docs/physics.md section 2.1, "Over the whole carry"): ([(F, N)]
    per object mass at cells + 1 angles evenly from -start to end, on the closed-form carry that
    left -alpha at u; bend = S h^2 / 2), h = (start + end) / cells and S the curvature bound of
    every carry from a stop in [0, start + end] with a landing speed^2 at most fastest_u2
    (carry_contact_curvature). Floats, numpy arrays (one carry per entry) or CasADi."""
    span = start + end
    step = span / cells
    terms = dict(gravity=gravity, carry_gravity=carry_gravity, friction=friction,
                 link_length=link_length)
    bend = carry_contact_curvature(carry_gravity=carry_gravity, fastest_u2=fastest_u2,
                                   friction=friction, link_length=link_length,
                                   span=span) * step**2 / 2
    return [carry_contact_at(-start + i * step, u, alpha, **terms) for i in range(cells + 1)], bend


def carry_row_cells(nodes, c1, c2, bend):
    """A lower bound of the row c1 N + c2 F (lift-off: N; slip: mu N -+ F; tip: d N +- (h/2) F)
    over each cell between carry_contact_nodes' nodes: |r''| <= (|c1| + |c2|) S
    (carry_cell_least)."""
    values = [c1 * N + c2 * F for F, N in nodes]
    size = (abs(c1) + abs(c2)) * bend  # abs: floats, arrays and CasADi alike
    return [carry_cell_least(values[i], values[i + 1], size) for i in range(len(values) - 1)]


def carry_row_least(nodes, c1, c2, bend):
    """The least of carry_row_cells over the whole carry (a lower bound of the row on it)."""
    cells = carry_row_cells(nodes, c1, c2, bend)
    least = cells[0]
    for value in cells[1:]:
        least = fmin(least, value)
    return least


def carry_cell_least(ra, rb, bend):
    """A lower bound of r over a cell [0, h] from its ends r(0) = ra, r(h) = rb and |r''| <= S,
    bend = S h^2 / 2 (> 0): r lies above its chord less S t (h - t) / 2, and the least of
    ra + D x - bend x (1 - x) over x in [0, 1] (D = rb - ra) is (ra + rb) / 2 - D^2 / (4 bend)
    - bend / 4 where |D| <= bend and min(ra, rb) = (ra + rb) / 2 - |D| / 2 elsewhere: a row
    with a continuous slope, exact at the ends where the row is steep across the cell."""
    d = rb - ra
    huber = where(fabs(d) <= bend, d**2 / (4 * bend) + bend / 4, fabs(d) / 2)
    return (ra + rb) / 2 - huber


def is_exact_zero(value) -> bool:
    """A plain number that is exactly zero (a symbol never is)."""
    return isinstance(value, (int, float)) and value == 0.0


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


# ---------------------------------------------------------------- viscous damping: integrated

def damping_rate(effective_mass_ratio, *, object_mass, link_length, damping):
    """delta = c / (l (m + M + J)) (m/s): viscous pivot damping c takes 2 delta v off v^2 per
    radian of the carry (q_e: carry_terms' effective mass ratio)."""
    if is_exact_zero(damping):
        return 0.0
    return (damping / (object_mass * link_length)) * momentum_fraction(effective_mass_ratio)


def carry_steps(rtol, span=1.0):
    """Fourth-order steps for an integrated carry over `span` rad whose relative error is at most
    about rtol: the step h = 2 rtol^(1/4) (the error is C h^4 with C measured from 5e-5 to
    0.03 on damped carries; results/bench_links.md; at least 4 steps)."""
    return max(4, math.ceil(span / (2.0 * rtol**0.25)))


def integrated_carry_speed_squared(u, alpha, theta, *, gravity, link_length, friction=0.0,
                                   damping=0.0, steps=64, lowest=False):
    """v(theta)^2 after leaving -alpha at speed u, by classical Runge-Kutta in the angle on
    y = v^2:  dy/dth = 2 g l sin th - 2 friction - 2 damping sqrt(y)  (the energy balance of
    carry_speed_squared with the viscous torque's work; damping = damping_rate). No closed form
    exists with damping; with damping = 0 this is the closed form to the method's error. y is
    clipped at 1e-200 inside the square root (a swing that stops has no further meaning; the
    over-the-top condition looks at the smallest y). lowest=True: (y(theta), smallest y at the
    steps). Works on floats, numpy arrays and CasADi symbols (a fixed number of steps)."""
    gl2, f2 = 2.0 * gravity * link_length, 2.0 * friction
    h = (theta + alpha) / steps

    def slope(th, y):
        # floored at 1e-200, not 0: a finite slope of the root where an NLP steps to y <= 0
        return gl2 * sin(th) - f2 - 2.0 * damping * sqrt(fmax(y, 1e-200))

    y, th, low = u * u, -alpha, u * u
    for _ in range(steps):
        k1 = slope(th, y)
        k2 = slope(th + 0.5 * h, y + 0.5 * h * k1)
        k3 = slope(th + 0.5 * h, y + 0.5 * h * k2)
        k4 = slope(th + h, y + h * k3)
        y = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        th = th + h
        low = fmin(low, y)
    return (y, low) if lowest else y
