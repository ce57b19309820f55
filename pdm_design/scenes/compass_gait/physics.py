"""Closed forms of the compass gait, written once for floats, numpy arrays and CasADi symbols.

Frame: x downhill along the horizontal, y up; the stance foot at the origin. Each leg's angle is
of its axis from the vertical, from its foot to the hip, positive with the hip ahead (downhill)
of that foot: the hip is at l (sin q1, cos q1) and the swing foot at hip - l (sin q2, cos q2).
q1, q2: stance and swing angles; w1, w2 their rates. Masses are per hip mass: beta = leg mass /
hip mass; a = l - b and b are the leg's centre of mass from the foot and from the hip; k2 =
leg inertia / leg mass (the squared radius of gyration). Garcia's simplest walker is beta = 0,
b = l, k2 = 0: every formula holds there (the swing leg's equation and the trailing leg's
momentum are per leg mass). Derivations: docs/compass_gait.md.

Equations of motion (Lagrange; rows 1 per hip mass, 2 per leg mass), c12 = cos(q1 - q2):
    [l^2 + beta (a^2 + l^2 + k2)] a1 - beta l b c12 a2 = beta l b s12 w2^2 + g (l + beta (a + l)) s1
    -l b c12 a1 + (b^2 + k2) a2 = -l b s12 w1^2 - g b s2
Heel strike (legs swap, new angles (q2, q1)): angular momentum about the new stance foot (whole
walker, per hip mass) and about the hip (trailing leg, per leg mass) are conserved.
"""

from __future__ import annotations

from typing import NamedTuple

from ...physics.ops import cos, sin


class Params(NamedTuple):
    """A walker's numbers as the closed forms take them (SI; floats or CasADi symbols)."""

    beta: object  # leg mass / hip mass (0: the simplest walker)
    a: object  # leg centre of mass from the foot (m)
    b: object  # leg centre of mass from the hip (m)
    l: object  # leg length (m)
    k2: object  # leg inertia / leg mass (m^2)
    g: object  # gravity (m/s^2)


def params_of(walker, gravity) -> Params:
    """The closed forms' numbers of a scenes.compass_gait.Walker."""
    if walker.model == "simplest":
        return Params(0.0, 0.0, walker.leg_length, walker.leg_length, 0.0, float(gravity))
    l, b = walker.leg_length, walker.leg_com
    return Params(walker.leg_mass / walker.hip_mass, l - b, b, l, walker.leg_inertia /
                  walker.leg_mass, float(gravity))


def accelerations(q1, q2, w1, w2, p: Params):
    """(a1, a2): the angular accelerations of the stance and swing legs (Cramer's rule)."""
    s12, c12 = sin(q1 - q2), cos(q1 - q2)
    m11 = p.l**2 + p.beta * (p.a**2 + p.l**2 + p.k2)
    m12 = -p.beta * p.l * p.b * c12
    m21 = -p.l * p.b * c12
    m22 = p.b**2 + p.k2
    r1 = p.beta * p.l * p.b * s12 * w2**2 + p.g * (p.l + p.beta * (p.a + p.l)) * sin(q1)
    r2 = -p.l * p.b * s12 * w1**2 - p.g * p.b * sin(q2)
    det = m11 * m22 - m12 * m21
    return (r1 * m22 - m12 * r2) / det, (m11 * r2 - m21 * r1) / det


def heel_strike(q1, q2, w1, w2, p: Params):
    """The state just after a heel strike, (q1+, q2+, w1+, w2+) = (q2, q1, v1, v2): the legs swap
    and (v1, v2) solve
        -[l^2 + beta (a^2 + k2 + l^2 - b l c)] v1 + beta (l b c - b^2 - k2) v2 = L_foot
        b l c v1 - (b^2 + k2) v2 = (a b - k2) w1
    with c = cos(q1 - q2) and L_foot the angular momentum about the new stance foot before it
        L_foot = -l^2 c w1 + beta [(a b - 2 a l c - k2) w1 + (a b - k2) w2]."""
    c = cos(q1 - q2)
    beta, a, b, l, k2 = p.beta, p.a, p.b, p.l, p.k2
    foot = -l**2 * c * w1 + beta * ((a * b - 2 * a * l * c - k2) * w1 + (a * b - k2) * w2)
    hip = (a * b - k2) * w1
    m11 = -(l**2 + beta * (a**2 + k2 + l**2 - b * l * c))
    m12 = beta * (l * b * c - b**2 - k2)
    m21, m22 = b * l * c, -(b**2 + k2)
    det = m11 * m22 - m12 * m21
    return q2, q1, (foot * m22 - m12 * hip) / det, (m11 * hip - m21 * foot) / det


def kinetic_energy(q1, q2, w1, w2, p: Params):
    """Kinetic energy per hip mass (J/kg)."""
    c12 = cos(q1 - q2)
    return 0.5 * (p.l**2 + p.beta * (p.a**2 + p.l**2 + p.k2)) * w1**2 \
        - p.beta * p.l * p.b * c12 * w1 * w2 + 0.5 * p.beta * (p.b**2 + p.k2) * w2**2


def energy(q1, q2, w1, w2, p: Params):
    """Mechanical energy per hip mass (J/kg), height measured from the stance foot."""
    potential = p.g * ((p.l + p.beta * (p.a + p.l)) * cos(q1) - p.beta * p.b * cos(q2))
    return kinetic_energy(q1, q2, w1, w2, p) + potential


def momentum(q1, q2, w1, w2, p: Params):
    """(px, py): the walker's linear momentum per hip mass."""
    big, small = p.l + p.beta * (p.a + p.l), p.beta * p.b
    return (big * w1 * cos(q1) - small * w2 * cos(q2),
            -big * w1 * sin(q1) + small * w2 * sin(q2))


def ground_reaction(q1, q2, w1, w2, slope, p: Params):
    """(normal, tangential): the stance foot's ground force per hip mass (N/kg) along the ramp's
    normal and downhill along it. The force is the rate of the walker's momentum plus its weight:
    with sum m r = A u1 - B u2, u = (sin q, cos q), A = l + beta (a + l), B = beta b,
        R = A (a1 u1' - w1^2 u1) - B (a2 u2' - w2^2 u2) + (0, (1 + 2 beta) g),
    u' = (cos q, -sin q)."""
    a1, a2 = accelerations(q1, q2, w1, w2, p)
    return reaction(q1, q2, w1, w2, a1, a2, slope, p)


def reaction(q1, q2, w1, w2, a1, a2, slope, p: Params):
    """ground_reaction with the accelerations (a1, a2) given."""
    big, small = p.l + p.beta * (p.a + p.l), p.beta * p.b
    rx = big * (a1 * cos(q1) - w1**2 * sin(q1)) - small * (a2 * cos(q2) - w2**2 * sin(q2))
    ry = big * (-a1 * sin(q1) - w1**2 * cos(q1)) - small * (-a2 * sin(q2) - w2**2 * cos(q2)) \
        + (1 + 2 * p.beta) * p.g
    return _along_ramp(rx, ry, slope)


def strike_impulse(q1, q2, w1, w2, p: Params, slope):
    """(normal, tangential): the impulse at the new stance foot at a heel strike from state
    (q1, q2, w1, w2), per hip mass (N s / kg): the change of the walker's momentum."""
    after = heel_strike(q1, q2, w1, w2, p)
    px0, py0 = momentum(q1, q2, w1, w2, p)
    px1, py1 = momentum(*after, p)
    return _along_ramp(px1 - px0, py1 - py0, slope)


def _along_ramp(x, y, slope):
    """(normal, downhill) components of a vector on a ramp of `slope`: n = (sin, cos),
    t = (cos, -sin)."""
    return x * sin(slope) + y * cos(slope), x * cos(slope) - y * sin(slope)


def strike_guard(q1, q2, slope, rise_per_length):
    """Positive while the swing foot, once ahead of the stance leg, is above the ground; zero at
    the heel strike. A ramp (rise 0): 2 slope - q1 - q2 (the swing foot's height above the ramp
    is 2 l sin((q1 + q2 - 2 slope) / 2) sin((q2 - q1) / 2): this factor, without the root where
    the legs pass). Stairs (slope 0): cos q1 - cos q2 + rise / l, the swing foot's height above
    the tread one rise below, per leg length."""
    if isinstance(rise_per_length, float) and rise_per_length == 0.0:
        return 2 * slope - q1 - q2
    return cos(q1 - slope) - cos(q2 - slope) + rise_per_length * cos(slope)


def foot_height(q1, q2, slope, p: Params):
    """The swing foot's height above the ramp through the stance foot (m, along its normal)."""
    return p.l * (cos(q1 - slope) - cos(q2 - slope))


def step_length(q1, q2, p: Params):
    """Distance between the feet along the ground at a heel strike from (q1, q2) (m)."""
    return 2 * p.l * sin((q1 - q2) / 2)
