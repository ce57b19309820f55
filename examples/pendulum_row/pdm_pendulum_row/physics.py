"""The closed forms, written once for floats, numpy arrays and CasADi symbols.

A puck of mass m slides without friction down a straight ramp that drops h, runs smoothly onto
the level and hits a bob of mass M hanging at rest on a rigid rod of length l. The impact is
head-on and instantaneous; momentum is conserved and Newton's restitution e relates the speeds
apart and together:

    m v = m v' + M V,   V - v' = e v   =>   v' = r v,  r = (m - e M) / (m + M),
                                            V = (1 + e) m v / (m + M).

The bob swings away; the puck goes on down the next ramp and reaches the next bob with
v_next^2 = v'^2 + 2 g h (energy, frictionless). In s = v^2 the stage map is affine,
s_next = r^2 s + 2 g h, so the periodic speed is v*^2 = 2 g h / (1 - r^2) and every stage takes
r^2 of the distance left to it (the contraction). From s_1 = v0^2 the approach is
s_k = s* + r^(2(k-1)) (s_1 - s*): monotone, so the largest s of a run is max(s_1, s*).

Conditions: the puck goes on forward (v' > 0: m > e M, margin 1 - e M / m) and no bob swings
over its pivot (V^2 < 4 g l on a rigid rod, at the largest s: the first impact and the periodic).
The time down a ramp of slope a is (v_next - v') / (g sin a).
"""

from __future__ import annotations

from pdm_design.physics import ops


def ratio(m, M, e):
    """The puck's speed after an impact over its speed before, r."""
    return (m - e * M) / (m + M)


def bob_gain(m, M, e):
    """The bob's speed after an impact over the puck's before, (1 + e) m / (m + M)."""
    return (1.0 + e) * m / (m + M)


def periodic_speed2(m, M, e, h, g):
    """v*^2: the squared speed at every bob on the periodic orbit."""
    r = ratio(m, M, e)
    return 2.0 * g * h / (1.0 - r * r)


def next_speed(v, m, M, e, h, g):
    """The speed at the next bob from the speed v at this one."""
    r = ratio(m, M, e)
    return ops.sqrt(r * r * v * v + 2.0 * g * h)


def ramp_time(v_after, v_next, g, angle):
    """The time down one ramp, from the speed leaving a bob to the speed at the next."""
    return (v_next - v_after) / (g * ops.sin(angle))
