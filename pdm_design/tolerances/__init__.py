"""Tolerances of a build, per part or per lot, and what they do to the yield.

outcome   BuildOutcome: what a batch of builds did, whatever the scene
draw      random builds, each reproducible from (seed, index, stages)
run_builds
          the scene's closed-form outcome of many builds at once (Scene.run_builds)
yield_    the Monte Carlo yield, its confidence interval, the simulator's confirmation and the
          sensitivity
sensitivity
          variance-based (Sobol') indices of the tolerances, and their bar chart

The typed tolerances (Tolerance, Tolerances) are pdm_design.tolerance_model's; the command
`pdm-design yield` is pdm_design.commands.yield_."""

from __future__ import annotations

from ..tolerance_model import Tolerance, Tolerances
from .outcome import BuildOutcome


def run_builds(scene, design, deviations: dict, stages: int) -> BuildOutcome:
    """The closed-form outcome of many builds of one design (the scene's Scene.run_builds)."""
    from ..plugin import of

    return of(scene).run_builds(scene, design, deviations, stages)


__all__ = ["BuildOutcome", "Tolerance", "Tolerances", "run_builds"]
