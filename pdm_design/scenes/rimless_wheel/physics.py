"""Closed forms of the rimless wheel (docs/rimless_wheel.md), for floats, numpy arrays and CasADi
symbols alike (physics/ops.py).

Frame: x downhill, y up. The stance spoke's angle phi is measured from the vertical, positive
forward (phi > 0: the hub is ahead of the foothold). Spokes are 2 alpha apart, alpha = pi / n.
A step's chord angle beta is the slope (below the horizontal) of the line from one foothold to
the next: the slope on a ramp, asin(rise / chord) on stairs (chord = 2 l sin alpha). An impact
happens when the leading spoke's tip reaches the next foothold, at phi = beta + alpha; the new
stance spoke then stands at phi = beta - alpha.

With m the whole mass, I_c the inertia about the hub (the centre of mass), k^2 = I_c / m and
I_p = m (k^2 + l^2) about the tip:
    stance      I_p phi'' = m g l sin phi,  so  omega^2 - rate (1 - cos phi) = E is constant,
                rate = 2 g l / (k^2 + l^2)
    impact      angular momentum about the new foothold: (k^2 + l^2 cos 2 alpha) omega- =
                (k^2 + l^2) omega+,  omega+ = eta omega-,  eta = 1 - 2 l^2 sin^2 alpha / (k^2 + l^2)
    step map    E' = eta^2 (E + rate (1 - cos(beta + alpha))) - rate (1 - cos(beta - alpha)),
                affine in E with slope eta^2 (the return map's multiplier)
    orbit       omega*^2 = eta^2 rate 2 sin(alpha) sin(beta) / (1 - eta^2)
"""

from __future__ import annotations

import math

import numpy as np

from ...physics.ops import asin, cos, fabs, fmax, fmin, sin, sqrt, where


def half_pitch(spokes):
    """alpha = pi / n: half the angle between two spokes."""
    return math.pi / spokes


def total_mass(mass, spoke_mass, spokes):
    return mass + spokes * spoke_mass


def gyration_squared(mass, gyration, spoke_mass, spokes, leg):
    """k^2 = I_c / m: the hub's m_h k_h^2 and n uniform rods' n m_s l^2 / 3 about the hub."""
    inertia = mass * gyration**2 + spokes * spoke_mass * leg**2 / 3.0
    return inertia / total_mass(mass, spoke_mass, spokes)


def chord(leg, alpha):
    """Distance between two successive footholds: 2 l sin alpha."""
    return 2.0 * leg * sin(alpha)


def impact_ratio(k2, leg, alpha):
    """eta = omega+ / omega- = (k^2 + l^2 cos 2 alpha) / (k^2 + l^2), written as
    1 - 2 l^2 sin^2 alpha / (k^2 + l^2) (no cancellation for many spokes)."""
    return 1.0 - 2.0 * leg**2 * sin(alpha) ** 2 / (k2 + leg**2)


def energy_loss(k2, leg, alpha):
    """1 - eta^2 = (1 - eta)(1 + eta), without cancellation."""
    loss = 2.0 * leg**2 * sin(alpha) ** 2 / (k2 + leg**2)
    return loss * (2.0 - loss)


def stance_rate(gravity, k2, leg):
    """rate = 2 m g l / I_p = 2 g l / (k^2 + l^2) (1/s^2): omega^2 gains rate (cos phi0 -
    cos phi) from phi0 to phi."""
    return 2.0 * gravity * leg / (k2 + leg**2)


def versine(angle):
    """1 - cos(angle), as 2 sin^2(angle / 2) (no cancellation at small angles)."""
    return 2.0 * sin(0.5 * angle) ** 2


def stance_energy(omega, phi, rate):
    """E = omega^2 - rate (1 - cos phi): constant over a stance; the squared speed where the
    stance spoke is vertical."""
    return omega**2 - rate * versine(phi)


def speed_squared(energy, phi, rate):
    """omega^2 at angle phi of a stance of energy E."""
    return energy + rate * versine(phi)


def step_energy(energy, beta, alpha, eta, rate):
    """E of the next stance from a stance of energy E that ends on a chord of angle beta
    (the return map; affine in E, slope eta^2)."""
    before = energy + rate * versine(beta + alpha)
    return eta**2 * before - rate * versine(beta - alpha)


def step_offset(beta, alpha, eta, rate):
    """The step map's constant term: E' = eta^2 E + step_offset(beta)."""
    return rate * (eta**2 * versine(beta + alpha) - versine(beta - alpha))


def periodic_speed_squared(beta, alpha, eta, rate, loss=None):
    """omega*^2 just after each impact of the period-one orbit on chords of angle beta:
    eta^2 rate (cos(beta - alpha) - cos(beta + alpha)) / (1 - eta^2). loss: 1 - eta^2 (from
    `energy_loss`, exact for many spokes); from eta when left out."""
    loss = (1.0 - eta) * (1.0 + eta) if loss is None else loss
    return eta**2 * rate * 2.0 * sin(alpha) * sin(beta) / loss


def periodic_energy(beta, alpha, eta, rate, loss=None):
    """E* of the orbit: omega*^2 less rate (1 - cos(beta - alpha))."""
    return periodic_speed_squared(beta, alpha, eta, rate, loss) - rate * versine(beta - alpha)


def contraction(eta):
    """The return map's multiplier d omega+' / d omega+ at the orbit (and dE'/dE anywhere):
    eta^2."""
    return eta**2


def over_the_top_demand(beta, alpha, rate):
    """omega+^2 the stance needs to vault its spoke: rate (1 - cos(beta - alpha)) when it starts
    behind the vertical (beta < alpha), else 0 (it starts past the top)."""
    return rate * versine(fmin(beta - alpha, 0.0))


def stance_forces(phi, omega2, ground, leg, gravity, k2):
    """(normal, tangential) ground force on the stance tip per unit mass (m/s^2) at angle phi,
    speed^2 omega2, on ground whose normal is `ground` rad forward of the vertical (the slope on
    a ramp, 0 on a tread). Newton on the centre of mass, which moves on a circle of radius l
    about the tip: radial R_r = g cos phi - l omega^2, tangential R_t = -g sin phi k^2 /
    (k^2 + l^2); projected on the ground with psi = phi - ground. tangential > 0 pushes
    downhill."""
    radial = gravity * cos(phi) - leg * omega2
    across = -gravity * sin(phi) * k2 / (k2 + leg**2)
    psi = phi - ground
    normal = radial * cos(psi) - across * sin(psi)
    tangential = radial * sin(psi) + across * cos(psi)
    return normal, tangential


def impact_impulses(eta, alpha, beta, ground):
    """(normal, tangential) impulse at the new foothold per unit m l omega-: the centre of mass's
    velocity change l (omega+ e_t(phi - 2 alpha) - omega- e_t(phi)), phi = beta + alpha, on the
    ground's normal and tangent (delta = beta - ground)."""
    delta = beta - ground
    normal = sin(alpha + delta) + eta * sin(alpha - delta)
    tangential = eta * cos(alpha - delta) - cos(alpha + delta)
    return normal, tangential


def impact_friction_demand(eta, alpha, beta, ground):
    """|tangential| / normal impulse the impact needs (Coulomb: at most the friction). On a
    ramp (beta = ground) (1 - eta) / (1 + eta) cot alpha; tan alpha for a point mass."""
    normal, tangential = impact_impulses(eta, alpha, beta, ground)
    return fabs(tangential) / normal


def nose_reach(leg, alpha, beta):
    """The farthest the nose of a tread may be ahead of its foothold for the landing spoke to
    pass over it: l sin 2 alpha / cos(alpha - beta) (the corner stays on the wheel's side of the
    leading spoke, worst at the impact; for beta >= alpha the spoke swings through the vertical
    of the corner's direction and the bound is l sin 2 alpha)."""
    return leg * sin(2.0 * alpha) / cos(fmax(alpha - beta, 0.0))


def stairs_chord_angle(rise, leg, alpha):
    """beta of a step of `rise`: asin(rise / chord)."""
    return asin(rise / chord(leg, alpha))


def stairs_advance(rise, leg, alpha):
    """Horizontal distance between footholds on treads `rise` apart: sqrt(chord^2 - rise^2)."""
    c = chord(leg, alpha)
    return sqrt(fmax(c**2 - rise**2, 0.0))


# Gauss-Legendre nodes and weights on [-1, 1], computed once per order
_GAUSS: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _gauss(order):
    if order not in _GAUSS:
        _GAUSS[order] = np.polynomial.legendre.leggauss(order)
    return _GAUSS[order]


def step_time(energy, phi0, phi1, rate, order=32):
    """Time of a stance from phi0 to phi1: int dphi / sqrt(E + rate (1 - cos phi)), by
    Gauss-Legendre quadrature of `order` nodes (the integrand is smooth while the wheel keeps
    moving; its peak where the speed is least needs more nodes as that speed nears 0)."""
    nodes, weights = _gauss(order)
    half, mid = 0.5 * (phi1 - phi0), 0.5 * (phi1 + phi0)
    total = 0.0
    for x, w in zip(nodes, weights):
        total = total + float(w) / sqrt(speed_squared(energy, mid + half * float(x), rate))
    return half * total


def arc_points(phi0, phi1, count):
    """`count` angles spread over [phi0, phi1], both ends included (count >= 2)."""
    return [phi0 + (phi1 - phi0) * i / (count - 1) for i in range(count)]


def stance_conditions(energy, phi0, phi1, ground, leg, gravity, k2, rate, friction, count=9):
    """[(angle, (flight capacity, flight demand), (slip capacity, slip demand))] at `count`
    angles of the stance [phi0, phi1]. No flight: the normal force N = capacity - demand > 0,
    capacity = g (cos phi cos psi + kappa sin phi sin psi) (gravity's part), demand = l omega^2
    cos psi (the centripetal part), kappa = k^2 / (k^2 + l^2). No slip: |F| <= mu N."""
    out = []
    for phi in arc_points(phi0, phi1, count):
        w2 = speed_squared(energy, phi, rate)
        normal, tangential = stance_forces(phi, w2, ground, leg, gravity, k2)
        centripetal = leg * w2 * cos(phi - ground)
        out.append((phi, (normal + centripetal, centripetal), (friction * normal,
                                                                fabs(tangential))))
    return out


def stance_rows(wheel, energy, beta_prev, beta, ground):
    """[(name, g)] of one stance's failure rows, each g >= 0 where it holds (per unit g, or
    E / rate): the stance on chord angles beta_prev (where it starts) to beta (where it ends) at
    energy E, of a wheel of alpha, rate, leg, gravity, k2, eta and friction (floats, arrays or
    CasADi alike; docs/rimless_wheel.md section 13). over_the_top is E / rate behind the
    vertical and 1 (always holds) when the wheel's nominal chord starts past it."""
    p_n, p_t = impact_impulses(wheel.eta, wheel.alpha, beta, ground)
    return arc_rows(wheel, energy, beta_prev - wheel.alpha, beta + wheel.alpha, ground, p_n, p_t)


def arc_rows(wheel, energy, phi0, phi1, ground, p_n, p_t):
    """`stance_rows` of a stance from phi0 to phi1 whose impact gives impulses (p_n, p_t)."""
    w = wheel
    out = [("over_the_top", where(w.beta - w.alpha < 0.0, energy / w.rate, 1.0 + 0.0 * energy))]
    top = where(phi0 < 0.0, where(phi1 > 0.0, 0.0 * phi0, phi0), phi0)
    for name, phi in (("start", phi0), ("top", top), ("end", phi1)):
        normal, tangential = stance_forces(phi, speed_squared(energy, phi, w.rate), ground,
                                           w.leg, w.gravity, w.k2)
        out.append((f"no_flight ({name})", normal / w.gravity))
        out.append((f"no_slip ({name})", (w.friction * normal - fabs(tangential)) / w.gravity))
    out.append(("impact_friction (pushes)", p_n))
    out.append(("impact_friction", w.friction * p_n - fabs(p_t)))
    return out


def next_foothold(s, chord_length, beta, tread_before):
    """s_k = s_{k-1} + c cos beta_k - tread_{k-1}: the foothold's place from the back of the
    tread it lands on, from the one before on the tread before (the footholds' drift)."""
    return s + chord_length * cos(beta) - tread_before


def landing_rows(wheel, s_prev, beta, tread_before, tread_after, scale, chord_length=None,
                 reach=None):
    """[(name, g)] of one step's landing on stairs, per unit `scale` (a tread), g >= 0 where
    it holds: the nose of the tread before lies tread_before - s_prev ahead of the foothold,
    within nose_reach(beta) (nose_clearance); the new foothold falls short of the nose of the
    tread after (landing). chord_length and reach: a build's spokes' (the design's when left
    out). Floats, arrays or CasADi alike (docs/rimless_wheel.md, section 13)."""
    chord_length = chord(wheel.leg, wheel.alpha) if chord_length is None else chord_length
    reach = nose_reach(wheel.leg, wheel.alpha, beta) if reach is None else reach
    s = next_foothold(s_prev, chord_length, beta, tread_before)
    return [("nose_clearance", (reach - (tread_before - s_prev)) / scale),
            ("landing", (tread_after - s) / scale)]


# --- spokes of their own lengths (a build's): the stance spoke a, the landing spoke b ---------
# The chord from the stance tip to the landing tip is fixed in the wheel: at phi = 0 it is
# (b sin 2 alpha, a - b cos 2 alpha), so its angle below the horizontal is phi - theta0, and the
# landing spoke lands on ground of chord angle beta at phi1 = theta0 + beta. With a = b = l:
# theta0 = alpha, the chord 2 l sin alpha (the equal spokes' forms above).


def chord_offset(a, b, alpha):
    """theta0 = atan2(a - b cos 2 alpha, b sin 2 alpha), as the asin of the rise over the chord
    (b sin 2 alpha > 0 for three spokes or more): the impact angle less the chord's."""
    return asin((a - b * cos(2.0 * alpha)) / chord_between(a, b, alpha))


def chord_between(a, b, alpha):
    """The distance between the tips of spokes a and b, 2 alpha apart."""
    return sqrt((b * sin(2.0 * alpha)) ** 2 + (a - b * cos(2.0 * alpha)) ** 2)


def impact_ratio_between(k2, a, b, alpha):
    """omega+ / omega- when spoke b lands as spoke a leaves: angular momentum about b's tip,
    (k^2 + a b cos 2 alpha) / (k^2 + b^2), written as 1 - b (2 b sin^2 alpha + (b - a)
    cos 2 alpha) / (k^2 + b^2) (`impact_ratio` when a = b, without cancellation)."""
    drop = b * (2.0 * b * sin(alpha) ** 2 + (b - a) * cos(2.0 * alpha))
    return 1.0 - drop / (k2 + b**2)


def impact_impulses_between(eta, a, b, alpha, phi1, ground):
    """(normal, tangential) impulse at b's tip per unit m omega- (m/s per rad/s): the centre of
    mass's velocity change b omega+ e_t(phi1 - 2 alpha) - a omega- e_t(phi1), e_t(t) =
    (cos t, -sin t), on the ground's normal (sin g, cos g) and tangent (cos g, -sin g). With
    a = b = l it is l times `impact_impulses`."""
    normal = a * sin(phi1 - ground) + eta * b * sin(ground - phi1 + 2.0 * alpha)
    tangential = eta * b * cos(phi1 - 2.0 * alpha - ground) - a * cos(phi1 - ground)
    return normal, tangential


def nose_reach_between(a, alpha, phi1):
    """Where the landing spoke crosses the level of the stance foothold at the impact, ahead of
    it: a sin 2 alpha / cos(phi1 - 2 alpha) (the farthest a nose may be; the swing's worst
    moment is the impact while phi1 <= 2 alpha, else the spoke's pass through 2 alpha).
    `nose_reach` when a = b."""
    return a * sin(2.0 * alpha) / cos(fmin(phi1 - 2.0 * alpha, 0.0))


def spoke_step(wheel, energy, phi0, beta, a, b, k2, ground):
    """(rows [(name, g)], the next stance's energy, phi1) of a stance on spoke a from phi0 to
    its impact on ground of chord angle beta, spoke b landing (a build's spokes and k^2;
    floats, arrays or CasADi alike; docs/rimless_wheel.md section 13): `stance_rows`' rows
    with the impulses per unit of the wheel's design leg, and E' = eta_ab^2 (E + rate_a
    vers(phi1)) - rate_b vers(phi1 - 2 alpha)."""
    from types import SimpleNamespace

    w = wheel
    phi1 = chord_offset(a, b, w.alpha) + beta
    rate_a, rate_b = stance_rate(w.gravity, k2, a), stance_rate(w.gravity, k2, b)
    eta = impact_ratio_between(k2, a, b, w.alpha)
    at = SimpleNamespace(alpha=w.alpha, beta=w.beta, rate=rate_a, leg=a, k2=k2,
                         gravity=w.gravity, friction=w.friction)
    p_n, p_t = impact_impulses_between(eta, a, b, w.alpha, phi1, ground)
    rows = arc_rows(at, energy, phi0, phi1, ground, p_n / w.leg, p_t / w.leg)
    after = eta**2 * speed_squared(energy, phi1, rate_a) - rate_b * versine(phi1 - 2.0 * w.alpha)
    return rows, after, phi1
