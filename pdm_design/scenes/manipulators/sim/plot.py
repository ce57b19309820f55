"""Figures of a manipulators run, like the paper's Figs. 10-15: the object's vy(t), vx(t), y(t)
and its path in the x-y plane with the mechanisms (pivots, links, palms) drawn at the events."""

from __future__ import annotations

from ....io import atomic_path
from .geometry import build_row, palm_outline

SNAPSHOT_KINDS = ("landing", "handover", "complete")


def plot_manipulators(result, scene, design, path, *, offsets=(), stages=None, title=None):
    """Write a 2 x 2 figure of `result` (simulated with record_trajectory=True) to `path` (PNG).

    scene, design, offsets and stages (the row's length; default: the manipulators the run
    reached) must be those of the run: they place the mechanisms."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    traj = result.trajectory
    if not traj or not traj.get("time"):
        raise ValueError("the result has no trajectory: simulate with record_trajectory=True")
    if stages is None:
        stages = max(len(result.stages), max((e.stage for e in result.events), default=1),
                     max((int(o.manipulator) for o in offsets), default=1))
    row = build_row(scene, design, stages, offsets)

    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
    t = traj["time"]
    for ax, key, label in ((axes[0, 0], "vy", "$v_y$ (m/s)"), (axes[0, 1], "vx", "$v_x$ (m/s)"),
                           (axes[1, 0], "y", "$y$ (m)")):
        ax.plot(t, traj[key], lw=1.2)
        ax.set_xlabel("t (s)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        for e in result.events:
            if e.kind in SNAPSHOT_KINDS or e.failure:
                ax.axvline(e.time, color="0.8", lw=0.6, zorder=0)
    axes[0, 0].set_title("object velocity, vertical")
    axes[0, 1].set_title("object velocity, along the row")
    axes[1, 0].set_title("object height (bottom centre)")

    ax = axes[1, 1]
    _draw_mechanisms(ax, row, result)
    ax.plot(traj["x"], traj["y"], color="C3", lw=1.4, label="object (bottom centre)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("path and mechanisms at the events")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)

    outcome = result.outcome
    status = "completed" if outcome.completed else (
        f"failed: {outcome.failure.kind} on manipulator {outcome.failure.stage}")
    fig.suptitle(title or f"manipulators run: {outcome.stages_passed} manipulators passed, "
                 f"{status}")
    fig.tight_layout()
    try:
        with atomic_path(path) as tmp:  # the file is whole or absent, never half written
            fig.savefig(tmp, dpi=120)
    finally:
        plt.close(fig)
    return path


def _draw_mechanisms(ax, row, result):
    """Every palm at rest on its back stop (light), and the palm carrying or receiving the object
    at each landing, handover, completion and failure, with the object there."""
    for k, (px, py) in enumerate(row.pivots):
        ax.plot(px, py, "k^", ms=6)
        ax.annotate(str(k + 1), (px, py), textcoords="offset points", xytext=(4, -10),
                    fontsize=7)
        _draw_palm(ax, row, k, -row.back_stops[k], color="0.8")
    w, h = row.body_width, row.body_height
    for e in result.events:
        if not (e.kind in SNAPSHOT_KINDS or e.failure):
            continue
        color = "C3" if e.failure else "C0"
        if e.kind in ("landing", "handover"):
            state, k = e.after, int(e.after.get("palm", e.stage)) - 1
        else:
            state, k = e.before, e.stage - 1
        if "x" not in state:
            continue
        if "theta" in state and 0 <= k < len(row):
            _draw_palm(ax, row, k, state["theta"], color=color)
        ww, hh = (h, w) if int(e.before.get("face", 0)) % 2 else (w, h)  # lying on its side
        ax.add_patch(_rect(state["x"] - ww / 2, state["y"], ww, hh,
                           "C3" if e.failure else "C1"))


def _draw_palm(ax, row, k, theta, color):
    """Palm k at angle theta with the two parallel links of its parallelogram."""
    px, py = row.pivots[k]
    cx, cy = row.palm_top(k, theta)
    gap = 0.25 * row.palm_width
    for dx in (-gap, gap):
        ax.plot([px + dx, cx + dx], [py, cy - row.palm_thickness], color=color, lw=1.0)
    outline = palm_outline(row, k, theta)
    ax.fill(outline[:, 0], outline[:, 1], color=color, alpha=0.7, lw=0)


def _rect(x, y, w, h, color):
    from matplotlib.patches import Rectangle

    return Rectangle((x, y), w, h, facecolor=color, edgecolor="k", lw=0.6, alpha=0.7)
