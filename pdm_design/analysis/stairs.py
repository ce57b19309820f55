"""Closed-form analysis of a stairs design: periodic rise and tread, first impact, clearances."""

from __future__ import annotations

import math

import numpy as np

from ..physics import stairs as phys
from ..scenes import StairsDesign, StairsScene
from .result import Analysis, margin

_CLEARANCE_SAMPLES = 2049


def analyse_stairs(scene: StairsScene, design: StairsDesign) -> Analysis:
    g, h0 = scene.gravity, scene.initial.drop_height
    eps, v0 = design.restitution, design.launch_speed
    ball = scene.ball
    problems: list[str] = []
    margins: dict[str, float] = {}

    vy_first = phys.impact_speed_vertical(g, h0)
    vx, spin = v0, scene.initial.spin
    if not scene.frictionless:
        demand = phys.rolling_impulse_ratio(
            vx, spin, vy_first, eps, radius=ball.radius, mass=ball.mass, inertia=ball.inertia
        )
        margins["first_impact_friction"] = margin(scene.friction, demand)
        if demand > scene.friction:
            problems.append(
                f"friction {scene.friction:g} cannot stop the ball slipping at the first impact: "
                f"rolling without slip needs friction >= {demand:.4g} (the paper's eq. 13 assumes "
                "it can); the ball leaves sliding and the tread is not periodic"
            )
        else:
            vx, spin = phys.rolling_impact(
                vx, spin, radius=ball.radius, mass=ball.mass, inertia=ball.inertia
            )

    if eps == 0.0:
        problems.append("restitution 0: the ball does not bounce, it slides along each tread "
                        "(outside the model)")
    rise = phys.periodic_rise(h0, eps) if design.rise is None else design.rise
    vy_periodic = _periodic_vertical_speed(g, h0, eps, rise, design.rise is None, problems)

    geometry: dict[str, float | None] = {"rise": rise, "tread": design.tread}
    periodic: dict[str, float | None] = {"impact_speed": None}
    if vy_periodic is not None and eps > 0.0:
        flight = (1.0 + eps) * vy_periodic / g
        orbit_tread = vx * flight
        tread = orbit_tread if design.tread is None else design.tread
        geometry["tread"] = tread
        periodic.update(
            impact_speed=math.hypot(vx, vy_periodic),
            vertical_impact_speed=vy_periodic,
            horizontal_speed=vx,
            spin=None if scene.frictionless else spin,
            flight_time=flight,
            drift_per_bounce=orbit_tread - tread,
        )
        landing = tread / 2 if design.landing_offset is None else design.landing_offset
        geometry["landing_offset"] = landing
        clearance = nose_clearance(vx, eps * vy_periodic, g, ball.radius, tread, rise, landing)
        geometry["nose_clearance"] = clearance
        margins["nose_clearance"] = clearance / tread
        margins["riser_clearance"] = (landing - ball.radius) / tread
        if landing >= tread:
            problems.append(f"landing_offset {landing:g} m is not on the tread (tread {tread:g} m)")

    design_values = {
        "restitution": eps, "launch_speed": v0, "rise": rise, "tread": geometry["tread"],
        "landing_offset": geometry.get("landing_offset"),
    }
    return Analysis(
        kind="stairs",
        design=design_values,
        geometry=geometry,
        periodic=periodic,
        margins=margins,
        approach={"first_vertical_impact_speed": vy_first},
        problems=tuple(problems),
    )


def _periodic_vertical_speed(g, h0, eps, rise, derived, problems):
    """Vertical impact speed of the periodic orbit: v*^2 (1 - eps^2) = 2 g rise."""
    if derived:
        return phys.impact_speed_vertical(g, h0)
    if eps < 1.0:
        return math.sqrt(2.0 * g * rise / (1.0 - eps**2))
    if rise == 0.0:
        return phys.impact_speed_vertical(g, h0)
    problems.append("restitution 1 with a rise > 0: every bounce gains energy, no periodic orbit")
    return None


def nose_clearance(vx, vy_up, g, radius, tread, rise, landing):
    """Smallest gap (m) between the ball and the step it leaves, over one periodic flight.

    The ball leaves the tread at the contact point (0, 0) with velocity (vx, vy_up); the step's
    nose is at (tread - landing, 0) and its riser drops from there by `rise`. The gap is the
    distance from the ball's centre to the nose-and-riser segment less the radius, and, while the
    ball comes down still over the tread, the height of its lowest point above the tread
    (negative: it lands twice on one step).
    """
    flight = 2.0 * vy_up / g + _fall_time(vy_up, g, rise)
    t = np.linspace(0.0, flight, _CLEARANCE_SAMPLES)
    cx = vx * t
    cy = radius + vy_up * t - 0.5 * g * t**2
    nose_x = tread - landing
    below = np.clip(cy, -rise, 0.0)  # nearest point of the segment x = nose_x, y in [-rise, 0]
    gap_segment = np.hypot(cx - nose_x, cy - below) - radius
    descending_over_tread = (cx <= nose_x) & (t > vy_up / g)
    gap_tread = np.where(descending_over_tread, cy - radius, np.inf)
    return float(min(gap_segment.min(), gap_tread.min()))


def _fall_time(vy_up, g, rise):
    """Time from the apex-symmetric return to take-off height down by `rise`."""
    return (-vy_up + math.sqrt(vy_up**2 + 2.0 * g * rise)) / g
