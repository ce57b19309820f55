"""Tolerances of a build, per part or per lot, and what they do to the yield.

model     the typed tolerances (Tolerance, Tolerances, QUANTITIES)
outcome   BuildOutcome: what a batch of builds did, whatever the scene
draw      random builds, each reproducible from (seed, index, stages)
manipulators, stairs
          run_builds(scene, design, deviations, stages) -> BuildOutcome: many builds at once;
          simulate_build: one build in the event simulator
yield_    the Monte Carlo yield, its confidence interval, the simulator's confirmation and the
          sensitivity
sensitivity
          variance-based (Sobol') indices of the tolerances, and their bar chart
command   `pdm-design yield` (text, JSON, figures, `check`'s min_yield) and `simulate --build`"""

from __future__ import annotations

from .model import Tolerance, Tolerances
from .outcome import BuildOutcome


def run_builds(scene, design, deviations: dict, stages: int) -> BuildOutcome:
    """The closed-form outcome of many builds of one design, for the scene's kind."""
    if scene.kind == "manipulators":
        from ..scenes.manipulators.tolerances import run_builds as run
    else:
        from ..scenes.stairs.tolerances import run_builds as run
    return run(scene, design, deviations, stages)


__all__ = ["BuildOutcome", "Tolerance", "Tolerances", "run_builds"]
