"""Builds of one design for `pdm-design yield`: every bob's mass and every ramp's drop off by its
own error (the `[tolerances]` quantities bob_mass and drop, each part its own), all builds at
once on the closed-form stage map s_next = r_k^2 s + 2 g h_k (physics.py)."""

from __future__ import annotations

import numpy as np

from pdm_design.tolerance_model import EACH_OR_LOT, quantity

QUANTITIES = {q.name: q for q in (
    quantity("bob_mass", "kg", EACH_OR_LOT, "a bob's mass"),
    quantity("drop", "m", EACH_OR_LOT, "a ramp's drop"),
)}


def per_stage(design, deviations: dict, builds: int, stages: int) -> tuple:
    """(bob masses, drops): (builds, stages) arrays of the design plus each build's errors."""
    def of(name, nominal):
        value = np.asarray(deviations.get(name, np.zeros((builds, stages))), dtype=float)
        value = value[:, None] if value.ndim == 1 else value
        return nominal + np.broadcast_to(value, (builds, stages))

    return of("bob_mass", design.bob_mass), of("drop", design.drop)


def run_builds(scene, design, deviations: dict, stages: int):
    """pdm_design.tolerances.outcome.BuildOutcome of the builds: stages passed, the failure
    (stalled, looped, invalid_part), the smallest margin over the run."""
    from pdm_design.tolerances.outcome import BuildOutcome

    builds = len(next(iter(deviations.values())))
    masses, drops = per_stage(design, deviations, builds, stages)
    m, e, g = scene.puck.mass, scene.puck.restitution, scene.gravity
    s = np.full(builds, scene.initial.speed ** 2)
    passed = np.full(builds, stages)
    failure = np.full(builds, "", dtype=object)
    smallest = np.full(builds, np.inf)
    for k in range(stages):
        M, alive = masses[:, k], passed == stages
        forward = (m - e * M) / m
        loop = 1.0 - ((1 + e) * m / (m + M)) ** 2 * s / (4 * g * design.rod_length)
        bad = np.where(M <= 0, "invalid_part", np.where(loop <= 0, "looped",
                                                        np.where(forward <= 0, "stalled", "")))
        smallest = np.where(alive, np.minimum(smallest, np.minimum(forward, loop)), smallest)
        ends = alive & (bad != "")
        passed[ends], failure[ends] = k, bad[ends]
        r = (m - e * M) / (m + M)
        s = r * r * s + 2 * g * drops[:, k]
    return BuildOutcome(passed, failure, smallest, np.ones(builds, dtype=bool))
