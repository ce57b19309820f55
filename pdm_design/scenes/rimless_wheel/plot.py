"""Plots of a rimless wheel run: the stance angle and the angular speed against time, the hub's
path over the ground as built, and the speed against the angle (the orbit closes on itself).
Needs a result simulated with record_trajectory=True."""

from __future__ import annotations

from pathlib import Path

from ...io import atomic_path


def plot_wheel_run(spec, result, path, *, title: str | None = None, dpi: int = 120) -> Path:
    """Draw the recorded trajectory of a rimless wheel run into a PNG at `path`; returns it.

    Panels: the stance spoke's angle from the vertical phi(t) (forward positive; it jumps back
    by 360/n degrees at each impact), the angular speed omega(t) (rolling forward positive), the
    hub's path with the footholds (impacts marked, a failure marked with a cross), and omega
    against phi.
    """
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    traj = result.trajectory
    if not traj or not traj.get("time"):
        raise ValueError("the run has no trajectory: simulate with record_trajectory=True")
    t, phi, omega = (np.asarray(traj[k], float) for k in ("time", "phi", "omega"))
    fig = Figure(figsize=(11, 8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    (aphi, aom), (apath, aphase) = axes
    aphi.plot(t, np.degrees(phi), lw=1.2)
    aphi.set(xlabel="time (s)", ylabel="stance angle phi (deg)",
             title="the stance spoke from the vertical")
    aom.plot(t, omega, lw=1.2, color="tab:purple")
    aom.set(xlabel="time (s)", ylabel="omega (rad/s, forward +)", title="angular speed")
    _path(apath, spec, result, traj)
    cut = np.flatnonzero(np.diff(phi) < 0.0) + 1  # the impacts: one line a stance
    aphase.plot(np.insert(np.degrees(phi), cut, np.nan), np.insert(omega, cut, np.nan), lw=0.8,
                color="tab:purple")
    aphase.set(xlabel="stance angle phi (deg)", ylabel="omega (rad/s)",
               title="speed against angle, a line a stance")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    path = Path(path)
    with atomic_path(path) as tmp:  # the file is whole or absent, never half written
        fig.savefig(tmp, dpi=dpi)
    return path


def _path(ax, spec, result, traj):
    from .animation import ground_outline

    ax.plot(*zip(*ground_outline(spec, result)), color="0.3", lw=1.0, label="ground")
    feet = [(0.0, 0.0)] + [(s["foot_x"], s["foot_y"]) for s in result.stages]
    ax.plot(*zip(*feet), "o", color="0.3", ms=2.5, label="footholds")
    ax.plot(traj["x"], traj["y"], lw=1.2, color="tab:blue", label="hub")
    impacts = [e for e in result.events if e.kind == "impact"]
    ax.plot([e.before["x"] for e in impacts], [e.before["y"] for e in impacts], "o", ms=3,
            color="tab:orange", label="hub at impacts")
    if result.outcome.failure is not None:
        f = result.outcome.failure
        ax.plot([f.before["x"]], [f.before["y"]], "x", ms=10, mew=2, color="tab:red",
                label=f"{f.kind} (stage {f.stage})")
    ax.set(xlabel="x (m, downhill)", ylabel="y (m)", title="the hub's path")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="upper right", fontsize=8)
