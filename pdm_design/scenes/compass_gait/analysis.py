"""The analysis of one compass-gait design: its period-1 gait, multipliers and margins
(analysis.result.Analysis, as the other scenes give).

Margins (>= 0: the condition holds), each measured on one step of the periodic gait simulated
from its fixed point (simulate.one_step, "precise"):
    stance_contact  the smallest normal force on the stance foot over the step, per weight
    no_slip         margin(friction, the largest friction the stance foot needs, in the stance
                    phase and at the heel strike's impulse)
    stability       margin(max_spectral_radius (1 by default), the spectral radius)
    hip_limit       margin(the walker's hip_limit, the largest angle between the legs over the
                    step): the heel strike comes before the swing leg reaches the hip's limit
                    (only with a hip_limit)
The swing foot's scuff below the ramp as the legs pass is ignored, as the field does; its depth
per leg length is reported (geometry "scuff_depth").

The periodic gait (`periodic`, the optimize JSON's): its post-strike fixed point, step length and
period, multipliers and spectral radius (periodic_of).
"""

from __future__ import annotations

import math

from ...accuracy import accuracy as accuracy_preset
from ...analysis.result import Analysis, margin
from . import stepmap
from .gait import find_gait
from .ground import ground_of, params_for
from .simulate import one_step

PERIODIC_KEYS = ("fixed_point", "step_length", "step_period", "multipliers", "spectral_radius")


def analyse_compass_gait(scene, design, stages: int | None = None,
                         max_spectral_radius: float = 1.0) -> Analysis:
    """stages: unused (every step of the periodic gait is alike); kept for the shared shape."""
    del stages
    params = params_for(scene, design)
    ground = ground_of(design, params)
    values = {k: getattr(design, k) for k in design.VARIABLES}
    try:
        gait = find_gait(scene, design)
    except stepmap.GaitNotFound as exc:
        return Analysis(kind="compass_gait", design=values, geometry={}, periodic={},
                        margins={}, problems=(f"no periodic gait: {exc}",))
    out = one_step(params, ground, gait.state, math.inf, accuracy_preset("precise"))
    stats = out.margins
    demand = max(stats["friction_max"], stats.get("strike_friction", 0.0))
    margins = {
        "stance_contact": float(stats["normal_min"]),
        "no_slip": margin(scene.friction, demand),
        "stability": margin(max_spectral_radius, gait.spectral_radius),
    }
    limit = scene.walker.hip_limit
    if limit is not None:
        margins["hip_limit"] = margin(limit, stats["leg_angle_max"])
    problems = []
    if not gait.stable:
        problems.append(f"the gait is unstable: spectral radius {gait.spectral_radius:.4g} "
                        "(a disturbance grows step by step)")
    return Analysis(
        kind="compass_gait", design=values, geometry={"scuff_depth": stats["scuff_depth"]},
        periodic=periodic_of(gait), margins=margins, problems=tuple(problems))


class FixedPoint(dict):
    """The post-strike state {stance, swing, stance_rate, swing_rate} (rad, rad/s): a dict (the
    JSON's object) that the text report shows in words."""

    def __str__(self) -> str:
        return ", ".join(f"{name} {value:.6g} {'rad/s' if name.endswith('_rate') else 'rad'}"
                         for name, value in self.items())


class Multipliers(list):
    """The multipliers as [re, im] pairs: a list (the JSON's) shown as complex numbers."""

    def __str__(self) -> str:
        return ", ".join(f"{re:.6g}{im:+.6g}i" for re, im in self)


def periodic_of(gait: stepmap.Gait) -> dict:
    """The optimize JSON's `periodic` (PERIODIC_KEYS): the post-strike fixed point {stance,
    swing, stance_rate, swing_rate} (rad, rad/s), step_length (m, along the ground),
    step_period (s), multipliers [[re, im], ...] (largest modulus first), spectral_radius."""
    json = gait.to_json()
    periodic = {key: json[key] for key in PERIODIC_KEYS}
    periodic["fixed_point"] = FixedPoint(periodic["fixed_point"])
    periodic["multipliers"] = Multipliers(periodic["multipliers"])
    return periodic
