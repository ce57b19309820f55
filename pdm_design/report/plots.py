"""Figures of a simulation run (matplotlib is imported by the plotters, which write atomically)."""

from __future__ import annotations


def plot_simulation(spec, design, result, path, *, offsets=(), stages=None) -> None:
    """Draw a run like the paper's figures into a PNG at `path` (whole or not at all).
    offsets and stages must be those the run used (they place the mechanisms)."""
    title = f"{spec.name or spec.source}: {'completed' if result.outcome.completed else 'failed'}"
    from ..plugin import of

    of(spec).plot_run(spec, design, result, path, offsets=offsets, stages=stages, title=title)


def plot_path(result, path, *, title: str = "", dpi: int = 120) -> None:
    """A run of any scene: the object's path y(x) and its height y(t), from the recorded
    trajectory (keys time, x, y), into an image file at `path` (whole or not at all)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..io import atomic_path

    traj = result.trajectory
    if not traj or not traj.get("time"):
        raise ValueError("the run has no trajectory: simulate with record_trajectory=True")
    figure = Figure(figsize=(11, 4.5), layout="constrained")
    FigureCanvasAgg(figure)
    along, height = figure.subplots(1, 2)
    along.plot(traj["x"], traj["y"], lw=1.2)
    along.set(xlabel="x (m)", ylabel="y (m)", title="path")
    along.set_aspect("equal", adjustable="datalim")
    height.plot(traj["time"], traj["y"], lw=1.2)
    height.set(xlabel="time (s)", ylabel="y (m)", title="height")
    for ax in (along, height):
        ax.grid(alpha=0.3)
    if title:
        figure.suptitle(title)
    with atomic_path(path) as tmp:
        figure.savefig(tmp, dpi=dpi)
