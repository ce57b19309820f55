"""Closed-form analysis of a manipulators design: pitch, periodic handover, margins, approach."""

from __future__ import annotations

import math
from typing import NamedTuple

from ...analysis.result import Analysis, margin
from . import physics as phys
from .model import ManipulatorsDesign, ManipulatorsScene

APPROACH_STAGES = 6
# Margins that depend on the landing velocity (the others are the same at every stage).
_SPEED_DEPENDENT = ("over_the_top", "lift_off", "slip_impact", "tip_impact")
# With links or pivot friction the carry's contact force has a tangential part beyond gravity's,
# so the friction it needs and where it acts depend on the speed too.
_MECHANISM_SPEED_DEPENDENT = ("slip_carry", "tip_carry")


class CarryTerms(NamedTuple):
    """The carry of palm + links + stuck object (physics.manipulators.carry_terms): effective
    mass ratio, effective gravity, pivot friction per carried mass, the palm-plus-links mass felt
    along the swing (kg), and whether these are the paper's (massless links, no friction)."""

    q: float
    gravity: float
    friction: float
    felt_mass: float
    plain: bool
    damping: float = 0.0  # physics.damping_rate: 0, or the carry is integrated


# Relative error of the integrated (damped) carry in the analysis (physics.carry_steps): far
# below what verification demands of the simulator (measured 1e-13 against it).
ANALYSIS_RTOL = 1e-12


def carry_terms(scene, design) -> CarryTerms:
    mech = scene.mechanism()
    kw = dict(object_mass=scene.body.mass, gravity=scene.gravity,
              link_length=design.link_length, **mech)
    q, g_e, f = phys.carry_terms(design.mass_ratio, **kw)
    felt = phys.palm_terms(design.mass_ratio, **kw)[0]
    delta = phys.damping_rate(q, object_mass=scene.body.mass, link_length=design.link_length,
                              damping=scene.pivots.damping)
    return CarryTerms(q, g_e, f, felt, scene.plain_mechanism, delta)


def carry_v2(carry: CarryTerms, u, alpha, theta, link_length, lowest=False):
    """v(theta)^2 of a carry from -alpha at u: the closed form, or with pivot damping the
    integrated one (physics.integrated_carry_speed_squared; lowest: also the smallest v^2)."""
    kw = dict(gravity=carry.gravity, link_length=link_length, friction=carry.friction)
    if carry.damping == 0.0:
        v2 = float(phys.carry_speed_squared(u, alpha, theta, **kw))
        return (v2, None) if lowest else v2
    steps = phys.carry_steps(ANALYSIS_RTOL, abs(theta + alpha))
    out = phys.integrated_carry_speed_squared(u, alpha, theta, damping=carry.damping,
                                              steps=steps, lowest=lowest, **kw)
    return tuple(float(v) for v in out) if lowest else float(out)


def _damped_contraction(carry, a, b, l, s2):
    """d s'^2 / d s^2 of the integrated stage map at its fixed point s2 (central difference)."""
    k, h = float(phys.momentum_fraction(carry.q)), 1e-4

    def next_s2(x):
        return carry_v2(carry, k * math.sqrt(x) * math.cos(a + b), a, b, l)

    return (next_s2(s2 * (1 + h)) - next_s2(s2 * (1 - h))) / (2 * h * s2)


def _damped_handover_speed_squared(carry, a, b, l, start):
    """Fixed point of the integrated stage map s -> v(beta) after landing at k s cos(a + b)
    (pivot damping: no closed form), iterated from `start` (the map contracts); <= 0 when the
    carry stops."""
    k, s2 = float(phys.momentum_fraction(carry.q)), start
    for _ in range(500):
        v2 = carry_v2(carry, k * math.sqrt(max(s2, 0.0)) * math.cos(a + b), a, b, l)
        if v2 <= 0.0 or abs(v2 - s2) <= 1e-16 * v2:
            return v2
        s2 = v2
    return s2


def _mechanism_report(scene, design) -> dict:
    """The links and pivots as the analysis used them: each link's mass and inertia about its
    pivot, how many, and the pivots' friction torque and damping (all joints together)."""
    links, l = scene.links, design.link_length
    inertia = links.mass * l * l / 3.0 if links.inertia is None else links.inertia
    return {"link_mass": links.mass, "link_inertia": inertia, "link_count": links.count,
            "pivot_friction_torque": scene.pivots.friction_torque,
            "pivot_damping": scene.pivots.damping}


def analyse_manipulators(scene: ManipulatorsScene, design: ManipulatorsDesign,
                         stages: int | None = None) -> Analysis:
    """stages: manipulators in the row (default APPROACH_STAGES); palms parked behind the
    carrying one are checked as far back as the row has them."""
    l = design.link_length
    a, b = design.alpha, design.beta
    body, palm = scene.body, scene.palm
    carry = carry_terms(scene, design)
    q, g_e, f = carry.q, carry.gravity, carry.friction
    problems: list[str] = []
    margins: dict[str, float] = {}

    pitch_x, pitch_y = phys.pitch(a, b, l)
    geometry = {"pitch_x": float(pitch_x), "pitch_y": float(pitch_y),
                "palm_mass": body.mass / design.mass_ratio}
    geometry.update(_mechanism_report(scene, design))
    if palm.front_stop <= b:
        problems.append(f"the front stop at {palm.front_stop:g} rad stops the palm before the "
                        f"handover angle beta = {b:g} rad")
    links = scene.links
    if links.inertia is not None and links.inertia < links.mass * l * l / 4.0:
        problems.append(f"links.inertia = {links.inertia:g} kg m^2 is below mass (l/2)^2 = "
                        f"{links.mass * l * l / 4.0:g} kg m^2: no rigid link of length l = {l:g} m "
                        "with its centre of mass at mid-length has it")

    # First approach: ballistic flight onto the first palm resting at -alpha.
    first = _first_landing(scene, design, problems)
    offset = first["landing_offset"] if first else 0.0
    geometry["landing_offset"] = offset if first else None
    if first:  # an object that never lands on palm 1 has no landing to judge
        margins["landing"] = margin(palm.width / 2, abs(offset) + body.width / 2)

    # Periodic orbit: fixed point of the handover-speed map.
    s2 = phys.handover_speed_squared(a, b, q, gravity=g_e, link_length=l, friction=f)
    if carry.damping and s2 > 0.0:
        s2 = _damped_handover_speed_squared(carry, a, b, l, s2)
    periodic: dict[str, float | None] = {
        "handover_speed": None, "landing_speed": None,
        "contraction": float(phys.contraction(a, b, q)), "drop_per_stage": None,
        "effective_mass": carry.felt_mass,
    }
    if carry.damping and s2 > 0.0:  # the integrated map's slope at its fixed point
        periodic["contraction"] = _damped_contraction(carry, a, b, l, s2)
    if s2 <= 0.0 and (f > 0.0 or carry.damping > 0.0) and b > a:
        problems.append("the pivot friction and damping take more energy out of a carry than "
                        "its drop gives: there is no periodic handover speed")
    elif s2 <= 0.0:
        problems.append(f"beta = {b:g} rad is not beyond alpha = {a:g} rad: the carry gains no "
                        "height, so there is no periodic handover speed")
    else:
        s = math.sqrt(s2)
        u = float(phys.landing_speed(s * math.cos(b), -s * math.sin(b), a, q))
        if u > 0.0:
            periodic.update(handover_speed=s, landing_speed=u, drop_per_stage=float(pitch_y))
        else:  # s*^2 = D / (1 - c) solves the map's algebra, but no object is carried on it
            problems.append(f"alpha + beta = {a + b:g} rad is not below pi/2: a handover drives "
                            "the next palm back onto its stop, so there is no periodic handover")
        # the margins at s* say how far such a design is from working; a row of one has no
        # later landing, only palm 1's carry (its speed-dependent margins are the first_ ones)
        later = _stage_margins(scene, design, (s * math.cos(b), -s * math.sin(b)), offset)
        margins.update({k: v for k, v in later.items()
                        if stages != 1 or k not in _SPEED_DEPENDENT})

    parked = parked_palms_margin(scene, design, offset, stages or APPROACH_STAGES)
    if parked is not None:
        margins["parked_palms"] = parked

    approach: dict[str, object] = {}
    if first:
        first_margins = _stage_margins(scene, design, first["velocity"], offset)
        margins.update({f"first_{k}": first_margins[k] for k in _SPEED_DEPENDENT})
        approach = {
            "landing_point": first["point"],
            "landing_velocity": first["velocity"],
            "handover_speeds": _predicted_handover_speeds(scene, design, first["velocity"]),
        }
    return Analysis(
        kind="manipulators",
        design={name: float(getattr(design, name)) for name in design.VARIABLES},
        geometry=geometry,
        periodic=periodic,
        margins=margins,
        approach=approach,
        problems=tuple(problems),
    )


def parked_palms_margin(scene, design, offset, stages) -> float | None:
    """Smallest slack (physics.parked_palm_clearance), in link lengths and clipped to [-1, 1],
    of the carried object against the palms parked at their front stops behind its palm (None:
    a row of one has none).

    Every landing is at `offset` (nominal geometry) and every carry ends at beta, so the slack
    to the palm n places back is the same at every stage after the n-th. The palm just released
    is taken as parked from the handover on: conservative when it reaches its stop after the
    object has passed (the simulator follows the timing)."""
    l, fs = design.link_length, scene.palm.front_stop
    pitch_x, pitch_y = (float(p) for p in phys.pitch(design.alpha, design.beta, l))
    body, palm = scene.body, scene.palm
    worst = None
    for n in range(1, stages):
        clearance = float(phys.parked_palm_clearance(
            n, alpha=design.alpha, theta_end=design.beta, link_length=l, front_stop=fs,
            pitch_x=pitch_x, pitch_y=pitch_y, offset_lo=offset, offset_hi=offset,
            reach=(body.width + palm.width) / 2, depth=palm.thickness + body.height))
        worst = clearance if worst is None else min(worst, clearance)
        # every palm further back is behind the object from the start of the carry
        if l * math.sin(fs) - n * pitch_x + (body.width + palm.width) / 2 - offset \
                <= -l * math.sin(design.alpha):
            break
    return None if worst is None else max(-1.0, min(1.0, worst / l))


def _first_landing(scene, design, problems):
    """Where and how fast the object first meets palm 1's top surface (None if it cannot)."""
    g, l = scene.gravity, design.link_length
    (x0, y0), (vx, vy) = scene.initial.position, scene.initial.velocity
    px, py = phys.palm_centre(design.first_pivot_x, design.first_pivot_y, -design.alpha, l)
    drop = y0 - float(py)
    if drop < 0.0:
        problems.append(f"the object starts {-drop:.4g} m below the first palm's top surface")
        return None
    t = (vy + math.sqrt(vy**2 + 2.0 * g * drop)) / g
    x = x0 + vx * t
    return {"point": (x, float(py)), "velocity": (vx, vy - g * t), "landing_offset": x - float(px)}


def _stage_margins(scene, design, velocity, offset) -> dict[str, float]:
    """Margins of one stage: landing with `velocity` at `offset` from the palm centre, then the
    carry to beta (with links or pivot friction, the carry's lift-off, slip and tipping are
    judged at its two ends and over the whole carry, whole_carry_margins: each margin is the
    ends' where the whole carry's rows hold, else the least of those rows, < 0)."""
    g, l = scene.gravity, design.link_length
    a, b = design.alpha, design.beta
    carry = carry_terms(scene, design)
    q, g_e, f = carry.q, carry.gravity, carry.friction
    body, palm = scene.body, scene.palm
    vx, vy = velocity
    u = float(phys.landing_speed(vx, vy, a, q))
    px, py = (float(p) for p in phys.landing_impulse(vx, vy, a, q))
    v_beta2, lowest = carry_v2(carry, u, a, b, l, lowest=True)
    if lowest is None:
        top = float(phys.top_speed_squared_needed(a, gravity=g_e, link_length=l, friction=f))
    else:  # damped: the squared speed the carry loses down to its slowest point
        top = u * u - lowest
    support = _support(body.width, palm.width, offset)
    half_h = body.height / 2
    ends = ((-a, u * u), (b, v_beta2))
    along = [None if carry.plain else float(phys.carry_along(
        th, gravity=g, carry_gravity=g_e, friction=f, link_length=l)) for th, _ in ends]
    ratio = [None if A is None else float(phys.carry_force_ratio(
        th, v2, gravity=g, link_length=l, along=A)) for (th, v2), A in zip(ends, along)]
    demand = (float(phys.friction_demand(max(a, b))) if carry.plain
              else max(float(phys.friction_demand(th, r)) for (th, _), r in zip(ends, ratio)))

    out = {
        "over_the_top": margin(u**2 if u > 0 else 0.0, top),
        "lift_off": min(margin(float(phys.lift_off_capacity(th, gravity=g, link_length=l,
                                                            along=A)), v2)
                        for (th, v2), A in zip(ends, along)),
        "slip_carry": margin(palm.friction, demand),
        "tip_carry": min(
            _tip_margin(support, float(phys.carry_force_point(-a, body.height, ratio[0]))),
            _tip_margin(support, float(phys.carry_force_point(b, body.height, ratio[1]))),
        ),
    }
    if not carry.plain and carry.damping == 0.0 and u > 0.0:
        # the ends' margin where the whole carry's rows hold (proven), else their least
        for key, value in whole_carry_margins(scene, carry, u, a, b, l, support).items():
            out[key] = out[key] if value >= 0.0 else min(out[key], value)
    if py > 0.0:
        out["slip_impact"] = margin(palm.friction * py, abs(px))
        out["tip_impact"] = _tip_margin(support, -half_h * px / py)
    else:  # the palm would have to pull the object down: it is not landing on the palm
        out["slip_impact"] = out["tip_impact"] = -1.0
    return out


def whole_carry_margins(scene, carry: CarryTerms, u, a, b, l, support, cells=None) -> dict:
    """The least over the whole carry from -a at u to b (real links or pivots, no damping) of
    its lift-off, slip and tip rows, each over its scale and clipped to [-1, 1]: the NLP's rows
    over the carry's cells with the curvature bound (physics.carry_contact_nodes; docs/physics.md
    section 2.1, "Over the whole carry"), a lower bound of each row, exact at the cells' ends.
    Rows (per object mass): lift-off N / g, slip (mu N -+ F) / (mu g), tip (d N +- (h/2) F) /
    (d g) for the supported base's front and rear ends d (`support`)."""
    g, mu, half_h = scene.gravity, scene.palm.friction, scene.body.height / 2
    nodes, bend = phys.carry_contact_nodes(
        u, a, start=a, end=b, fastest_u2=u * u, gravity=g, carry_gravity=carry.gravity,
        friction=carry.friction, link_length=l, cells=cells or phys.CARRY_CELLS)

    def least(c1, c2, scale):
        value = float(phys.carry_row_least(nodes, c1, c2, bend))
        return max(-1.0, min(1.0, value / scale)) if scale > 0.0 else -1.0

    low, high = support
    return {"lift_off": least(1.0, 0.0, g),
            "slip_carry": min(least(mu, -1.0, mu * g), least(mu, 1.0, mu * g)),
            "tip_carry": min(least(high, half_h, high * g), least(-low, -half_h, -low * g))}


def _support(object_width, palm_width, offset):
    """Interval of the object's base (relative to its centre) that rests on the palm."""
    return (max(-object_width / 2, -palm_width / 2 - offset),
            min(object_width / 2, palm_width / 2 - offset))


def _tip_margin(support, force_point):
    """Slack of the contact force's point of application within the supported base."""
    low, high = support
    if force_point >= 0.0:
        return margin(max(high, 0.0), force_point)
    return margin(max(-low, 0.0), -force_point)


def _predicted_handover_speeds(scene, design, velocity, stages=APPROACH_STAGES):
    """Handover speeds of the first stages by the closed-form map (nominal geometry), up to the
    first carry that cannot pass the top (sim.manipulators.handover_map is nan there too)."""
    l = design.link_length
    a, b = design.alpha, design.beta
    carry = carry_terms(scene, design)
    q, g_e, f = carry.q, carry.gravity, carry.friction
    top = float(phys.top_speed_squared_needed(a, gravity=g_e, link_length=l, friction=f))
    u = float(phys.landing_speed(*velocity, a, q))
    speeds = []
    while len(speeds) < stages and u > 0.0 and (carry.damping or u * u >= top):
        v2, lowest = carry_v2(carry, u, a, b, l, lowest=True)
        if v2 <= 0.0 or (lowest is not None and lowest <= 0.0):  # the palm stops short
            break
        speeds.append(math.sqrt(v2))
        u = float(phys.momentum_fraction(q)) * speeds[-1] * math.cos(a + b)
    return speeds
