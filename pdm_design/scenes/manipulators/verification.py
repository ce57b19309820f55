"""A row of manipulators judged by the simulator: the closed forms' handover speeds against a
nominal run, and one build of the explicit-offset box (every pivot's offsets)."""

from __future__ import annotations

import numpy as np

from ...plugin_tolerances import relative_agreement


def closed_form_agreement(spec, analysis, result) -> dict | None:
    """The largest relative difference between the simulated and the closed-form handover
    speeds, stage by stage."""
    predicted = handover_speeds(spec, analysis, len(result.stages))
    simulated = [s["handover_speed"] for s in result.stages if s["handover_speed"] is not None]
    return relative_agreement("the handover speeds", predicted, simulated)


def left_closed_forms(result) -> str:
    """After a lift-off the object flies (the run is judged by its outcome); the closed forms,
    which keep it on its palm, describe neither that flight nor the stages after it."""
    lifted = next((e for e in result.events if e.kind == "lift_off"), None)
    if lifted is None:
        return ""
    return f"; the object lifted off palm {lifted.stage} and flew on (closed forms not compared)"


def disagreement_note(spec) -> str:
    """What the closed forms leave out that the simulator models: a palm's restitution."""
    if spec.scene.palm.restitution > 0.0:
        return (f" (the closed forms assume a plastic landing; the palm's restitution "
                f"{spec.scene.palm.restitution:g} makes the object hop on the palm before it "
                "rests, and the run drifts from them: simulate more stages to see where it goes)")
    return ""


def handover_speeds(spec, analysis, stages):
    """Closed-form handover speeds of the first `stages` stages (extends the analysis' list
    by the paper's device's stage map; on real links or pivots, whose map that is not, the
    analysis' own list is compared alone)."""
    from . import physics as phys

    speeds = list(analysis.approach.get("handover_speeds", []))
    if (not speeds or analysis.periodic.get("handover_speed") is None
            or not spec.scene.plain_mechanism):
        return speeds
    d = analysis.design
    while len(speeds) < stages:
        speeds.append(float(phys.next_handover_speed(
            speeds[-1], d["alpha"], d["beta"], d["mass_ratio"], gravity=spec.scene.gravity,
            link_length=d["link_length"])))
    return speeds


def simulate_box_build(scene_object, spec, design, errors, deviations: dict, accuracy):
    """One build of the box: every pivot's (dx, dy) offsets and, of an allocated box, each
    other quantity a number for the lot or a list of one per manipulator (BoxAxes.per_part:
    the yield's per-part build, tolerances.simulate_build)."""
    stages = spec.verification.stages
    if not deviations:
        from .model import ManipulatorOffset

        offsets = tuple(ManipulatorOffset(manipulator=k + 1, dx=a, dy=b)
                        for k, (a, b) in enumerate(errors))
        return scene_object.simulate(spec, design, stages=stages, accuracy=accuracy,
                                     errors=offsets)
    from .tolerances import simulate_build

    per_part = scene_object.box_axes.per_part
    built = {"pivot_x": np.array([[e[0] for e in errors]]),
             "pivot_y": np.array([[e[1] for e in errors]])}
    for q, dev in deviations.items():  # a list: every part its own value
        built[q] = (np.broadcast_to(np.asarray(dev, float), (stages,))[None, :].copy()
                    if q in per_part else np.array([dev]))
    return simulate_build(spec.scene, design, built, stages, accuracy=accuracy,
                          allow_skips=spec.verification.allow_skips)
