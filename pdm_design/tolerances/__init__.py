"""Tolerances of a build, per part or per lot, and what they do to the yield.

model     the typed tolerances (Tolerance, Tolerances, QUANTITIES, BuildOutcome)
draw      random builds, each reproducible from (seed, index, stages)
manipulators, stairs
          run_builds(scene, design, deviations, stages) -> BuildOutcome: many builds at once
yield_    the Monte Carlo yield, its confidence interval and the simulator's confirmation
sensitivity
          variance-based (Sobol) indices of the tolerances (where present)
"""

from __future__ import annotations

from .model import QUANTITIES, Tolerance, Tolerances
from .outcome import BuildOutcome


def run_builds(scene, design, deviations: dict, stages: int) -> BuildOutcome:
    """The closed-form outcome of many builds of one design, for the scene's kind."""
    if scene.kind == "manipulators":
        from .manipulators import run_builds as run
    else:
        from .stairs import run_builds as run  # the stairs module may be absent: ImportError
    return run(scene, design, deviations, stages)


__all__ = ["QUANTITIES", "BuildOutcome", "Tolerance", "Tolerances", "run_builds"]
