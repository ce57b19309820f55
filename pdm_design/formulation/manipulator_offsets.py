"""The manipulators' conditions as explicit functions of every pivot's offset (no worst case).

d = (dx_1..dx_N, dy_1..dy_{N+1}): pivot K moved by (dx_K, dy_K) (y up) from its nominal place;
the object lands on palms 1..N and palm N hands it over to palm N+1 (whose dx does not matter).
Stage by stage, with the closed forms of `physics.manipulators`:
    first landing  Q = sqrt(vy0^2 + 2 g (H - dy_1)),  u_1 = m/(m+M) (vx0 cos a - Q sin a),
                   o_1 = C0 + vx0 (vy0 + Q) / g - dx_1
    handover K->K+1 at cos th = cos b + (dy_{K+1} - dy_K) / l,
                   speed v^2 = u_K^2 + 2 g l (cos a - cos th)
    landing on K+1 u_{K+1} = m/(m+M) v cos(a + th),
                   o_{K+1} = o_K + l (sin th - sin b) - (dx_{K+1} - dx_K)
Used to linearise the safe set of offsets (solve/tolerance.py, cvxpy) and to check a robust box by
sampling offsets inside it.
"""

from __future__ import annotations

import casadi as ca

from ..physics import manipulators as phys
from .common import MARGIN, VALIDITY, ConditionInfo, Scenario
from .manipulators import impact_rows


def scenario(spec, model, m) -> Scenario:
    N = spec.verification.stages
    dx = ca.SX.sym("dx", N)
    dy = ca.SX.sym("dy", N + 1)
    a, b, l, g, q = m.a, m.b, m.l, m.g, m.q
    body, palm = spec.scene.body, spec.scene.palm
    mu, W, w, h = palm.friction, palm.width, body.width, body.height
    rows: list[tuple] = []  # (keys, where, slack, scale, kind)

    def add(key, where, slack, scale=1.0, kind=MARGIN):
        rows.append(((key,), where, slack, scale, kind))

    def impact(prefix, stage, px, py, o):
        impact_rows(add, spec.scene, f"{prefix}slip_impact", f"{prefix}tip_impact",
                    f"palm {stage}", px, py, [o], [o])

    add("start_height", "palm 1", m.H - dy[0], l, VALIDITY)
    Q = m.fall_speed(dy[0])
    u = m.first_speed(Q)
    add("forward_landing", "palm 1", u, m.k * ca.sqrt(m.vx0**2 + Q**2), VALIDITY)
    o = m.C0 + m.vx0 * m.flight_time(dy[0]) - dx[0]
    px, py = phys.landing_impulse(m.vx0, -Q, a, q)
    impact("first_", 1, px, py, o)
    fp_back = phys.carry_force_point(-a, h)  # ahead of the centre
    parked = _parked_clearance(spec, m)
    for K in range(1, N + 1):
        first = "first_" if K == 1 else ""
        where = f"palm {K}"
        add("landing", f"{where}, ahead", W / 2 - o - w / 2, W / 2)
        add("landing", f"{where}, behind", W / 2 + o - w / 2, W / 2)
        if m.steps:  # pivot damping: the integrated carry's slowest point
            add(f"{first}over_the_top", where, m.carry_v2(u, b, lowest=True)[1], u**2)
        else:
            add(f"{first}over_the_top", where, u**2 - m.top_needed, u**2)
        if m.plain:
            held = phys.lift_off_capacity(a, gravity=g, link_length=l)
            demand = phys.friction_demand(a)
        else:  # links or pivots: the contact force depends on the speed (docs/physics.md 2.1)
            held, demand, fp_back = m.contact(-a, u**2)
            fp_back = fp_back * h
        add(f"{first}lift_off", f"{where}, back stop", held - u**2, held)
        add("slip_carry", f"{where}, back stop", mu - demand, mu)
        add("tip_carry", f"{where}, back stop, object's front edge", w / 2 - fp_back, w / 2)
        add("tip_carry", f"{where}, back stop, palm's front edge", W / 2 - o - fp_back, W / 2 - o)
        delta = dy[K] - dy[K - 1]
        cth = ca.cos(b) + delta / l
        th = ca.acos(cth)
        add("palm_clearance", f"palm {K + 1}", m.pitch_y - delta, l)
        for n in range(1, min(K - 1, m.parked) + 1):  # palm K - n, parked at its front stop
            # pivot K - n from pivot K: n pitches back and up, plus the two offsets' difference
            add("parked_palms", f"{where}, palm {K - n} parked", parked(
                th, n * m.pitch_x - (dx[K - n - 1] - dx[K - 1]),
                n * m.pitch_y + (dy[K - n - 1] - dy[K - 1]), o, a, l), l)
        if palm.front_stop < ca.pi / 2:
            add("front_stop", where, palm.front_stop - th, palm.front_stop)
        v2 = m.carry_v2(u, th)
        if m.plain:
            held = g * l * cth  # lift_off_capacity(th), without cos(acos(.))
            demand = phys.friction_demand(th)
            fp_front = -phys.carry_force_point(th, h)  # behind the centre
        else:
            held, demand, fp_front = m.contact(th, v2)
            fp_front = -fp_front * h
        add(f"{first}lift_off", f"{where}, handover", held - v2, held)
        add("slip_carry", f"{where}, handover", mu - demand, mu)
        add("tip_carry", f"{where}, handover, object's rear edge", w / 2 - fp_front, w / 2)
        add("tip_carry", f"{where}, handover, palm's rear edge", W / 2 + o - fp_front, W / 2 + o)
        if K == N:
            break
        v = ca.sqrt(v2)
        u = phys.landing_speed(v * ca.cos(th), -v * ca.sin(th), a, q)
        add("forward_landing", f"palm {K + 1}", u / v, m.k, VALIDITY)
        o = o + l * (ca.sin(th) - ca.sin(b)) - (dx[K] - dx[K - 1])
        px, py = phys.landing_impulse(ca.cos(th), -ca.sin(th), a, q)
        impact("", K + 1, px, py, o)

    x = ca.vertcat(*model.design_symbols.values(), *(s for _, s, _, _ in model.aux))
    d = ca.vertcat(dx, dy)
    fn = ca.Function("offsets", [x, d], [ca.vertcat(*[r[2] for r in rows]),
                                         ca.vertcat(*[r[3] for r in rows])])
    names = tuple(f"dx{K}" for K in range(1, N + 1)) + tuple(f"dy{K}" for K in range(1, N + 2))
    infos = tuple(ConditionInfo(i, r[0][0], r[0], r[1], r[4], False) for i, r in enumerate(rows))
    return Scenario(fn, names, {"dx": tuple(range(N)), "dy": tuple(range(N, 2 * N + 1))}, infos)


def _parked_clearance(spec, m):
    """physics.parked_palm_clearance of one parked palm as a CasADi Function of (theta_end,
    pitch_x, pitch_y, offset, alpha, link_length): built once and called at every stage and
    palm back, it is copied in C++; built there from the formula, a row of 100 stages took 1.4
    s (up to 16 parked palms a stage)."""
    th, px, py, o, a, l = (ca.SX.sym(name) for name in ("th", "px", "py", "o", "a", "l"))
    body, palm = spec.scene.body, spec.scene.palm
    gap = phys.parked_palm_clearance(1, alpha=a, theta_end=th, link_length=l,
                                     front_stop=palm.front_stop, pitch_x=px, pitch_y=py,
                                     offset_lo=o, offset_hi=o, reach=(body.width + palm.width) / 2,
                                     depth=palm.thickness + body.height)
    return ca.Function("parked_palm_clearance", [th, px, py, o, a, l], [gap])
