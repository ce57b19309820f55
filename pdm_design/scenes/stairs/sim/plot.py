"""Plots of a stairs run like the paper's Figs. 7-9: y(t), vx(t), omega(t), and the path over
the staircase. Needs a result simulated with record_trajectory=True."""

from __future__ import annotations

from pathlib import Path

from ....io import atomic_path


def plot_stairs_run(result, path, *, title: str | None = None, dpi: int = 120) -> Path:
    """Draw the recorded trajectory of a stairs run into a PNG at `path`; returns the path.

    Panels: height of the ball's lowest point y(t) (paper Fig. 7), horizontal speed vx(t)
    (Fig. 9), spin omega(t) (Fig. 8; counter-clockwise positive), and the path of the lowest
    point over the staircase as built (impacts marked, a failure marked with a cross).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    traj = result.trajectory
    if not traj or not traj.get("time"):
        raise ValueError("the run has no trajectory: simulate with record_trajectory=True")
    t, x, y = traj["time"], traj["x"], traj["y"]

    fig = Figure(figsize=(11, 8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    (ay, avx), (aom, apath) = axes
    ay.plot(t, y, lw=1.2)
    ay.set(xlabel="time (s)", ylabel="y of lowest point (m)", title="height (cf. paper Fig. 7)")
    avx.plot(t, traj["vx"], lw=1.2, color="tab:green")
    avx.set(xlabel="time (s)", ylabel="vx (m/s)", title="horizontal speed (cf. Fig. 9)")
    aom.plot(t, traj["omega"], lw=1.2, color="tab:purple")
    aom.set(xlabel="time (s)", ylabel="omega (rad/s, ccw +)", title="spin (cf. Fig. 8)")

    xs, ys = _staircase_outline(getattr(result, "staircase", []), min(x), max(x))
    if xs:
        apath.fill_between(xs, ys, min(ys) - 0.05 * (max(ys) - min(ys) + 1e-9), step=None,
                           color="0.85", lw=0)
        apath.plot(xs, ys, color="0.3", lw=1.0)
    apath.plot(x, y, lw=1.2, color="tab:blue")
    impacts = [e for e in result.events if e.kind == "impact"]
    apath.plot([e.before["x"] for e in impacts], [e.before["y"] for e in impacts], "o",
               ms=3, color="tab:orange", label="impacts")
    if result.outcome.failure is not None:
        f = result.outcome.failure
        apath.plot([f.before["x"]], [f.before["y"]], "x", ms=10, mew=2, color="tab:red",
                   label=f"{f.kind} (stage {f.stage})")
    apath.set(xlabel="x (m)", ylabel="y (m)", title="path of the lowest point")
    apath.set_aspect("equal", adjustable="datalim")
    apath.legend(loc="upper right", fontsize=8)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    path = Path(path)
    with atomic_path(path) as tmp:  # the file is whole or absent, never half written
        fig.savefig(tmp, dpi=dpi)
    return path


def _staircase_outline(steps, x_min, x_max):
    """Polyline of the tread surfaces and risers between x_min and x_max."""
    xs: list[float] = []
    ys: list[float] = []
    for s in steps:
        back = s["back"] if s["back"] != float("-inf") else x_min - 0.5
        if s["nose"] < x_min - 1.0 or back > x_max + 1.0:
            continue
        xs += [back, s["nose"]]
        ys += [s["level"], s["level"]]
    return xs, ys
