"""Many builds of one compass-gait design at once (the yield): every step's ground off by its
own error (its slope; on stairs its rise too) and the start state by one, every build walked
on the vectorised step map (`fastmap.walk`, within 1e-7 of the event simulator). A build passes
when it makes every step; each failure is named as the simulator names it.
"""

from __future__ import annotations

import numpy as np

from . import fastmap
from .ground import params_for
from .quantities import START


def starts_of(scene, deviations: dict, builds: int) -> np.ndarray:
    """(builds, 4) post-strike start states: the scene's initial state plus each build's start
    deviations (lots, (builds,) arrays)."""
    x = np.tile(np.asarray(scene.initial.state(), dtype=float), (builds, 1))
    for j, name in enumerate(START):
        if name in deviations:
            x[:, j] += np.asarray(deviations[name], dtype=float).reshape(builds)
    return x


def per_step(deviations: dict, name: str, shape) -> np.ndarray:
    """A quantity's (builds, stages) deviations: each step's own, or a lot's on every step."""
    value = np.asarray(deviations.get(name, np.zeros(shape)), dtype=float)
    return np.broadcast_to(value[:, None] if value.ndim == 1 else value, shape)


def walk_builds(scene, design, deviations: dict, stages: int) -> fastmap.Walk:
    """Every build of `deviations` ({quantity: array}, SI) walked for `stages` steps."""
    params = params_for(scene, design)
    builds = len(next(iter(deviations.values())))
    shape = (builds, stages)
    starts = starts_of(scene, deviations, builds)
    slope = per_step(deviations, "slope", shape)
    if design.slope is not None:
        return fastmap.walk(params, starts, design.slope, stages, scene.friction, slope)
    rise = per_step(deviations, "rise", shape) / params.l
    return fastmap.walk(params, starts, 0.0, stages, scene.friction, slope,
                        rise=float(design.rise) / params.l, rise_errors=rise)


def build_outcome(scene, design, deviations: dict, stages: int):
    """The yield engine's map (Scene.run_builds). The map gives no margins: min_margin is 0 for
    a build that made every step and -1 for one that did not. A walker still in its step after
    the step map's longest step (fastmap.MAX_STEP_TIME) leaves the map: the event simulator
    names its fall."""
    from ...tolerances.outcome import BuildOutcome

    run = walk_builds(scene, design, deviations, stages)
    passed = np.minimum(run.steps, stages)
    names = np.array(["", *fastmap.FALLS], dtype=object)
    failure = np.where(passed >= stages, "", names[run.fall + 1]).astype(object)
    closed = run.fall != fastmap.FALLS.index("too_long")
    return BuildOutcome(passed, failure, np.where(passed >= stages, 0.0, -1.0), closed)


def simulate_build(scene, design, deviations: dict, stages: int, *, accuracy="default",
                   record_trajectory=False, allow_skips=False):
    """The event simulator on one build (deviations: 1-row arrays, as build_outcome's)."""
    from .simulate import simulate_compass_gait

    shape = (1, stages)
    return simulate_compass_gait(scene, design, stages=stages, accuracy=accuracy,
                                 step_errors=per_step(deviations, "slope", shape)[0].tolist(),
                                 rise_errors=per_step(deviations, "rise", shape)[0].tolist(),
                                 start=starts_of(scene, deviations, 1)[0],
                                 record_trajectory=record_trajectory)
