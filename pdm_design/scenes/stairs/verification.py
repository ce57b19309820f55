"""A staircase judged by the simulator: the closed forms' impact speeds against a nominal run,
and one build of the explicit-offset box (every step's rise and tread errors)."""

from __future__ import annotations

import math

from ...plugin_tolerances import relative_agreement


def closed_form_agreement(spec, analysis, result) -> dict | None:
    """The largest relative difference between the simulated and the closed-form impact
    speeds, stage by stage."""
    predicted = impact_speeds(spec, analysis, len(result.stages))
    simulated = [s["impact_speed"] for s in result.stages]
    return relative_agreement("the impact speeds", predicted, simulated)


def impact_speeds(spec, analysis, stages):
    """Closed-form speed before each impact, transient included: the first fall is h0 at the
    launch speed; then v_y'^2 = eps^2 v_y^2 + 2 g rise at the speed after the first impact."""
    vx_after = analysis.periodic.get("horizontal_speed")
    rise = analysis.geometry.get("rise")
    if vx_after is None or rise is None:
        return []
    g, eps = spec.scene.gravity, analysis.design["restitution"]
    vy2 = 2.0 * g * spec.scene.initial.drop_height
    speeds = [math.sqrt(analysis.design["launch_speed"] ** 2 + vy2)]
    while len(speeds) < stages:
        vy2 = eps**2 * vy2 + 2.0 * g * rise
        speeds.append(math.sqrt(vx_after**2 + vy2))
    return speeds


def simulate_box_build(scene_object, spec, design, errors, deviations: dict, accuracy):
    """One build of the box: every step's (rise, tread) errors, and a number for each lot
    quantity of an allocated box (restitution, friction, launch_speed, launch_x)."""
    stages = spec.verification.stages
    if not deviations:
        from ..common import StepError

        step_errors = tuple(StepError(step=k + 1, rise=a, tread=b)
                            for k, (a, b) in enumerate(errors))
        return scene_object.simulate(spec, design, stages=stages, accuracy=accuracy,
                                     errors=step_errors)
    from .tolerances import simulate_build

    built = {"rise": [e[0] for e in errors], "tread": [e[1] for e in errors], **deviations}
    return simulate_build(spec.scene, design, built, stages, accuracy=accuracy)
