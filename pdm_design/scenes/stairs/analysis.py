"""Closed-form analysis of a stairs design: periodic rise and tread, first impact, clearances."""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

from ...analysis.result import Analysis, margin
from . import physics as phys
from .model import StairsDesign, StairsScene


def analyse_stairs(scene: StairsScene, design: StairsDesign,
                   stages: int | None = None) -> Analysis:
    """stages: also follow the approach from the drop height for that many bounces (a given rise
    other than (1 - eps^2) h0 starts the ball off its periodic orbit): the clearance margins are
    then the smallest over the periodic flight and those bounces."""
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
            # the staircase the simulator builds follows the first impact's horizontal speed
            vx, spin = phys.sliding_impact(vx, spin, vy_first, eps, scene.friction,
                                           radius=ball.radius, mass=ball.mass,
                                           inertia=ball.inertia)
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
    if vx <= 0.0:  # no flight goes down the stairs: no tread, landing or clearance to judge
        problems.append(f"the ball moves at {vx:g} m/s along the stairs after the first impact: "
                        "it does not go down them")
    elif vy_periodic is not None and eps > 0.0:
        flight = float(phys.flight_time(g, vy_periodic**2 / (2.0 * g), eps))
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
        # the launch over the top landing (one rise above tread 1), whose nose is v0 t(h0) -
        # landing ahead of it; the optimizer's launch row and the simulator's step 0
        launch = phys.launch_clearances(v0, g, ball.radius, h0 - rise,
                                        v0 * vy_first / g - landing, rise)
        margins["first_nose_clearance"] = float(min(launch) / tread)
        nearest_riser = landing
        if landing >= tread:
            problems.append(f"landing_offset {landing:g} m is not on the tread (tread {tread:g} m)")
        clearance = nose_clearance(vx, eps * vy_periodic, g, ball.radius, tread, landing, rise)
        if stages and landing < tread:
            # the flights the ball flies: off its orbit (a rise other than (1 - eps^2) h0) it
            # settles at another landing point and never flies the periodic flight from
            # landing_offset, so that one is not judged (it failed sound designs)
            path = approach(g, eps, rise, vx, ball.radius, tread, landing, vy_first, stages)
            nearest_riser = path.nearest
            if math.isfinite(path.nose):  # a single bounce flies no flight after it
                clearance = path.nose
            if path.overshoot:
                problems.append(path.overshoot)
        geometry["nose_clearance"] = clearance
        margins["nose_clearance"] = float(clearance / tread)
        margins["riser_clearance"] = float((nearest_riser - phys.riser_reach(rise, ball.radius))
                                           / tread)

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
    if eps < 1.0 and rise > 0.0:
        return float(phys.periodic_vertical_speed(g, rise, eps))
    if eps < 1.0:
        problems.append(f"rise 0 with restitution {eps:g} < 1: every bounce loses height and no "
                        "step gives it back, so there is no periodic orbit")
        return None
    if rise == 0.0:
        return phys.impact_speed_vertical(g, h0)
    problems.append("restitution 1 with a rise > 0: every bounce gains energy, no periodic orbit")
    return None


@dataclass(frozen=True)
class Approach:
    """The first bounces from the drop height: the smallest nose clearance of their flights (m),
    the landing nearest the riser (m from the back of its tread), and, if a bounce lands beyond
    the nose of its tread (the ball skips a step), that in words."""

    nose: float
    nearest: float
    overshoot: str | None


def approach(g, eps, rise, vx, radius, tread, landing, v1, stages, *, explicit=200_000):
    """Bounce n lands L_n from the back of tread n at vertical speed v_n (L_1 = landing,
    v_1 = sqrt(2 g h0)); it leaves at eps v_n, flies T_n = (eps v_n + v_{n+1}) / g with
    v_{n+1}^2 = (eps v_n)^2 + 2 g rise, and L_{n+1} = L_n + vx T_n - tread. Once v_n has
    converged (geometrically, by eps^2 a bounce) L drifts by a constant step, and the bounces
    left are judged at the two ends of that straight run. Flights 1..stages-1 and landings
    1..stages, as the simulator's `stages` bounces."""
    v, L, n = v1, landing, 1
    nose, nearest = math.inf, math.inf

    def lands(n, L):
        if L >= tread:
            return (f"bounce {n} of the approach from the drop height lands {L:.4g} m from the "
                    f"back of its tread, beyond its nose (tread {tread:.4g} m): the ball skips "
                    "a step before it settles on the periodic orbit")
        return None

    while True:
        nearest = min(nearest, L)
        if (miss := lands(n, L)) or n >= stages:
            return Approach(nose, nearest, miss)
        up = eps * v
        nose = min(nose, nose_clearance(vx, up, g, radius, tread, L, rise))
        v_next = math.sqrt(up * up + 2.0 * g * rise)
        step = vx * (up + v_next) / g - tread
        converged = abs(v_next - v) <= 4 * sys.float_info.epsilon * v
        v, L, n = v_next, L + step, n + 1
        if converged or n > explicit:  # the rest drift by `step` a bounce: a straight run
            # to bounce `stages`, or to the first that lands beyond the nose or at the riser
            stop = stages
            if step > 0.0:
                stop = min(stop, n + max(math.ceil((tread - L) / step), 0))
            elif step < 0.0:
                stop = min(stop, n + max(math.ceil((L - radius) / -step), 0))
            last = L + (stop - n) * step
            nearest = min(nearest, L, last)
            if miss := lands(n, L) or lands(stop, last):
                return Approach(nose, nearest, miss)
            if stop - 1 >= n:  # flights n .. stop - 1, judged at their two ends
                up = eps * v
                nose = min(nose, nose_clearance(vx, up, g, radius, tread, L, rise),
                           nose_clearance(vx, up, g, radius, tread, L + (stop - 1 - n) * step,
                                          rise))
            return Approach(nose, nearest, None)


def nose_clearance(vx, vy_up, g, radius, tread, landing, rise):
    """Smallest gap (m) between the ball and the step it leaves, over one flight to the tread
    `rise` below.

    The ball leaves the tread `landing` from its back with velocity (vx > 0, vy_up); the nose is
    tread - landing ahead. The gap is the distance from the ball's centre path, up to its
    landing, to the nose corner less the radius (exact: `physics.stairs.corner_gaps`), and, where
    the centre passes over the nose, the height of its lowest point above the nose level
    (negative: it comes down before the nose, or it took off beyond it). The riser below the nose
    is never nearer than the corner to a ball that clears the corner.
    """
    return float(min(phys.flight_clearances(vx, vy_up, g, radius, tread - landing, rise)))
