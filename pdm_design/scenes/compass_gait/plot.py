"""Plots of a compass-gait run (`simulate --plot`): the legs' angles and rates against time, and
the hip's path over the ground with each stance foot and heel strike. Needs a result simulated
with record_trajectory=True."""

from __future__ import annotations

import math
from pathlib import Path

from ...io import atomic_path


def plot_compass_gait_run(result, path, *, title: str | None = None, dpi: int = 120) -> Path:
    """Draw the recorded trajectory into an image at `path` (whole or not at all)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    traj = result.trajectory
    if not traj or not traj.get("time"):
        raise ValueError("the run has no trajectory: simulate with record_trajectory=True")
    t = traj["time"]
    fig = Figure(figsize=(11, 8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    (angles, rates), (phase, where) = axes
    for name, color in (("stance", "tab:blue"), ("swing", "tab:orange")):
        angles.plot(t, [math.degrees(v) for v in traj[name]], ".", ms=1.2, color=color,
                    label=f"{name} leg")
        rates.plot(t, traj[f"{name}_rate"], ".", ms=1.2, color=color, label=f"{name} leg")
        phase.plot([math.degrees(v) for v in traj[name]], traj[f"{name}_rate"], ".", ms=1.0,
                   color=color, label=f"{name} leg")
    strikes = [e.time for e in result.events if e.kind == "heel_strike"]
    for ax in (angles, rates):
        for s in strikes:
            ax.axvline(s, color="0.8", lw=0.5, zorder=0)
    angles.set(xlabel="time (s)", ylabel="angle from vertical (deg)",
               title="leg angles (grey: heel strikes)")
    rates.set(xlabel="time (s)", ylabel="rate (rad/s)", title="leg rates")
    phase.set(xlabel="angle (deg)", ylabel="rate (rad/s)", title="phase portrait")
    where.plot(traj["x"], traj["y"], lw=1.2, color="tab:blue", label="hip")
    feet = [(r["foot_x"], r["foot_y"]) for r in result.stages]
    where.plot([0.0] + [f[0] for f in feet], [0.0] + [f[1] for f in feet], "o-", ms=3,
               lw=0.6, color="0.35", label="stance feet (the ground)")
    failure = result.outcome.failure
    if failure is not None:
        where.plot([traj["x"][-1]], [traj["y"][-1]], "x", ms=10, mew=2, color="tab:red",
                   label=f"{failure.kind} (step {failure.stage})")
    where.set(xlabel="x downhill (m)", ylabel="y (m)", title="the hip's path")
    where.set_aspect("equal", adjustable="datalim")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    if title:
        fig.suptitle(title)
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi)
    return path
