"""Figures of a simulation run (matplotlib is imported by the plotters, which write atomically)."""

from __future__ import annotations


def plot_simulation(spec, design, result, path, *, offsets=(), stages=None) -> None:
    """Draw a run like the paper's figures into a PNG at `path` (whole or not at all).
    offsets and stages must be those the run used (they place the mechanisms)."""
    title = f"{spec.name or spec.source}: {'completed' if result.outcome.completed else 'failed'}"
    if spec.kind == "stairs":
        from ..scenes.stairs.sim.plot import plot_stairs_run

        plot_stairs_run(result, path, title=title)
    else:
        from ..scenes.manipulators.sim.plot import plot_manipulators

        plot_manipulators(result, spec.scene, design, path, offsets=offsets, stages=stages,
                          title=title)
