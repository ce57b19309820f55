"""Closed-form analysis of a rimless wheel design: the period-one orbit, the approach to it from
the start speed, the margins (docs/rimless_wheel.md, sections 5 and 6)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...analysis.result import Analysis, margin
from . import physics as phys
from .model import RimlessWheelDesign, RimlessWheelScene, check_ground

# Angles of the stance at which the no-flight and no-slip margins are taken (both ends in).
ARC_POINTS = 33
# Stances of the approach followed one by one (beyond, E_k is within 1e-15 of the orbit's
# or the contraction is judged through the orbit).
APPROACH_LIMIT = 100_000


@dataclass(frozen=True)
class WheelNumbers:
    """One design's numbers: spokes n, half pitch alpha, leg l, k^2, eta, 1 - eta^2, stance
    rate, gravity, friction; the step's chord angle beta and the ground's normal angle."""

    n: int
    alpha: float
    leg: float
    k2: float
    eta: float
    loss: float
    rate: float
    gravity: float
    friction: float
    beta: float
    ground: float

    @property
    def chord(self) -> float:
        return float(phys.chord(self.leg, self.alpha))


def resolve(scene: RimlessWheelScene,
            design: RimlessWheelDesign) -> tuple[WheelNumbers, dict, list]:
    """The design's numbers, its stairs geometry (rise, tread, landing_offset, drift) and the
    problems found resolving them."""
    problems = check_ground(scene, design)
    n, leg = int(design.spokes), design.leg_length
    w = scene.wheel
    alpha = phys.half_pitch(n)
    k2 = float(phys.gyration_squared(w.mass, w.gyration, w.spoke_mass, n, leg))
    eta = float(phys.impact_ratio(k2, leg, alpha))
    loss = float(phys.energy_loss(k2, leg, alpha))
    rate = float(phys.stance_rate(scene.gravity, k2, leg))
    geometry: dict[str, float | None] = {}
    if scene.ground == "ramp":
        beta = ground = float(design.slope or 0.0)
    else:
        ground, beta = 0.0, 0.0
        rise, c = design.rise or 0.0, float(phys.chord(leg, alpha))
        if rise >= c:
            problems.append(f"rise {rise:g} m is not below the distance between two spoke tips "
                            f"({c:.6g} m): a spoke cannot reach the next tread")
        else:
            beta = float(phys.stairs_chord_angle(rise, leg, alpha))
        advance = float(phys.stairs_advance(rise, leg, alpha))
        tread = advance if design.tread is None else design.tread
        reach = float(phys.nose_reach(leg, alpha, beta))
        low = max(tread - reach, 0.0)
        landing = 0.5 * (low + tread) if design.landing_offset is None else design.landing_offset
        geometry.update(rise=rise, tread=tread, landing_offset=landing, nose_reach=reach,
                        drift_per_step=advance - tread)
    wheel = WheelNumbers(n, alpha, leg, k2, eta, loss, rate, scene.gravity, scene.friction, beta,
                         ground)
    return wheel, geometry, problems


def stance_margins(wh: WheelNumbers, energy, phi0, phi1):
    """(over_the_top, no_flight, no_slip) of stances of energy `energy` (a number or an array)
    from phi0 to phi1: the smallest over ARC_POINTS angles (both ends in)."""
    energy = np.asarray(energy, dtype=float)
    start2 = phys.speed_squared(energy, phi0, wh.rate)
    demand = float(phys.over_the_top_demand(phi0 + wh.alpha, wh.alpha, wh.rate))
    top = _margins(start2, demand)
    flight = slip = np.inf
    for _, (fc, fd), (sc, sd) in phys.stance_conditions(
            energy, phi0, phi1, wh.ground, wh.leg, wh.gravity, wh.k2, wh.rate, wh.friction,
            ARC_POINTS):
        flight = np.minimum(flight, _margins(fc, fd))
        slip = np.minimum(slip, _margins(sc, sd))
    return top, flight, slip


def _margins(capacity, demand):
    """analysis.result.margin, elementwise: (capacity - demand) / max(capacity, demand); where
    both are <= 0, 0 if equal else -1; at least -1 (a negative capacity, friction's on a
    negative normal force, fails whole)."""
    capacity, demand = np.broadcast_arrays(np.asarray(capacity, float), np.asarray(demand, float))
    scale = np.maximum(capacity, demand)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(scale > 0.0, (capacity - demand) / np.where(scale > 0.0, scale, 1.0),
                       np.where(capacity == demand, 0.0, -1.0))
    out = np.maximum(out, -1.0)
    return out if out.shape else float(out)


def analyse_rimless_wheel(scene: RimlessWheelScene, design: RimlessWheelDesign,
                          stages: int | None = None) -> Analysis:
    """The orbit, the margins over the approach from the start speed (`stages` steps, default
    until it has converged) and on the orbit, and the problems."""
    wh, geometry, problems = resolve(scene, design)
    margins: dict[str, float] = {}
    periodic: dict[str, float | None] = {"post_impact_speed": None}
    if wh.eta <= 0.0:
        problems.append(f"{wh.n} spokes with this mass distribution: an impact keeps a fraction "
                        f"eta = {wh.eta:.4g} <= 0 of the speed, the wheel stops or rolls back at "
                        "every impact")
    if wh.beta <= 0.0 and not problems:
        problems.append("the ground does not go down (chord slope <= 0): every impact loses "
                        "energy that no step gives back, the wheel slows and stops")
    phi0, phi1 = wh.beta - wh.alpha, wh.beta + wh.alpha
    margins["impact_friction"] = _impact_friction(wh, problems)
    start_energy = float(phys.stance_energy(scene.initial.speed, phi0, wh.rate))
    energies = [start_energy]
    if wh.beta > 0.0 and wh.eta > 0.0:
        orbit = float(phys.periodic_energy(wh.beta, wh.alpha, wh.eta, wh.rate, wh.loss))
        w2 = float(phys.speed_squared(orbit, phi0, wh.rate))
        rolls = orbit > 0.0 or phi0 >= 0.0  # the orbit's stance vaults its spoke
        if not rolls:
            problems.append("no rolling orbit: the speed every step would settle on is too slow "
                            "to vault the stance spoke, so the wheel slows to a stop (a steeper "
                            "ground, or more spokes, gives the step more energy than it loses)")
        period = float(phys.step_time(orbit, phi0, phi1, wh.rate, 64)) if rolls else None
        periodic.update(
            post_impact_speed=math.sqrt(w2), pre_impact_speed=math.sqrt(w2) / wh.eta,
            energy=orbit, contraction=wh.eta**2, step_period=period,
            ground_speed=wh.chord / period if period else None,
            height_per_step=wh.chord * math.sin(wh.beta))
        count = stages if stages else APPROACH_LIMIT
        energies = _approach(start_energy, orbit, wh.eta**2, count)
    top, flight, slip = stance_margins(wh, np.asarray(energies), phi0, phi1)
    margins["over_the_top"] = float(np.min(top))
    margins["no_flight"] = float(np.min(flight))
    margins["no_slip"] = float(np.min(slip))
    if scene.ground == "stairs" and wh.beta > 0.0:
        _stairs_margins(wh, geometry, stages or 1, margins, problems)
    design_values = {"spokes": float(wh.n), "leg_length": wh.leg,
                     "slope": design.slope if scene.ground == "ramp" else None,
                     "rise": geometry.get("rise"), "tread": geometry.get("tread"),
                     "landing_offset": geometry.get("landing_offset")}
    geometry.update(half_pitch=wh.alpha, chord=wh.chord, chord_angle=wh.beta,
                    impact_ratio=wh.eta, gyration_squared=wh.k2, stance_rate=wh.rate)
    return Analysis(kind="rimless_wheel", design=design_values, geometry=geometry,
                    periodic=periodic, margins=margins,
                    approach={"start_energy": start_energy, "stances_judged": len(energies)},
                    problems=tuple(problems))


def _approach(start, orbit, multiplier, count):
    """The stance energies E_0 .. E_{count-1}: E_k = E* + q^k (E_0 - E*), q = eta^2; once
    q^k (E_0 - E*) is below rounding, the rest equal the orbit's (one entry stands for them)."""
    k = np.arange(count, dtype=float)
    with np.errstate(under="ignore"):
        gap = (start - orbit) * multiplier**k
    settled = np.abs(gap) <= 1e-15 * max(abs(orbit), 1e-300)
    last = int(np.argmax(settled)) if settled.any() else count - 1
    return orbit + gap[: last + 1]


def _impact_friction(wh: WheelNumbers, problems: list[str]) -> float:
    normal, _ = phys.impact_impulses(wh.eta, wh.alpha, wh.beta, wh.ground)
    if normal <= 0.0:
        problems.append("the impact's impulse would pull the new spoke into the ground: the "
                        "wheel leaves the ground at impact")
        return -1.0
    demand = float(phys.impact_friction_demand(wh.eta, wh.alpha, wh.beta, wh.ground))
    return margin(wh.friction, demand)


def _stairs_margins(wh: WheelNumbers, geo: dict, stages: int, margins: dict,
                    problems: list) -> None:
    """landing (each foothold before its tread's nose: 1 - s / tread) and nose_clearance (the
    landing spoke passes over the nose: 1 - a / nose_reach, a the nose's distance ahead of the
    foothold) over `stages` steps, whose footholds drift by drift_per_step each."""
    tread, s0, drift = geo["tread"], geo["landing_offset"], geo["drift_per_step"]
    if s0 >= tread:
        problems.append(f"landing_offset {s0:g} m is not on the tread (tread {tread:g} m)")
    ends = (s0, s0 + (stages - 1) * drift)  # footholds the steps leave from
    reach = geo["nose_reach"]
    margins["landing"] = min(margin(tread, s + drift) for s in ends)
    margins["nose_clearance"] = min(margin(reach, tread - s) for s in ends)
