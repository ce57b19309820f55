"""Plots of a design table: how the optimum and its tolerance move across the sweep.

x is the first swept parameter; each further combination of the other swept parameters is one
line. Points whose status is not a success are drawn as red crosses (the figure's legend says
so). Every panel of a figure has the same x range (the grid's). A column equal to one already
drawn at every point (tolerance, dx and dy of a square box) is not drawn again: the panel that
shows it names both. Lengths are drawn in millimetres. Figures are made with matplotlib's object
API (Figure + Agg canvas, no pyplot state) and returned as PNG and SVG bytes.
"""

from __future__ import annotations

import math

from ..report.render import render_figure
from .grid import SweepAxis, grid_points
from .tables import DESIGN, GEOMETRY, PERIODIC, TOLERANCE_AXES, number

MAX_PANELS = 6
MAX_LINES = 8
SUCCESS = ("optimal", "evaluated")
# (label, unit) of the shared columns; a scene's own over them (Scene.column_labels); a unit "m"
# is drawn in millimetres
_LABELS = {
    "objective": ("objective", ""), "tolerance": ("tolerance (smallest half-width)", "m"),
    "min_margin": ("smallest margin", ""), "contraction": ("contraction factor", ""),
    "drop_per_stage": ("drop per stage", "m"),
}
# swept keys (by last name) that are lengths in any scene: drawn in millimetres on the x axis,
# as is a key the scene's columns give in metres (Scene.column_labels) other than a requirement
# (a margin, whatever its name)
LENGTH_KEYS = {"width", "height", "thickness", "radius", "drop_height"}


def sweep_figures(kind: str, axes: tuple[SweepAxis, ...], rows: list[dict[str, str]]
                  ) -> dict[str, bytes]:
    """{file name: bytes} of the optimum and tolerance figures (PNG and SVG each)."""
    labels = labels_of(kind)
    swept = {a.path[1] for a in axes if a.path[0] == "design"}
    optimum = [c for c in (*DESIGN[kind], "objective", *GEOMETRY[kind], *PERIODIC[kind])
               if c not in swept and _varies(rows, c)][:MAX_PANELS]
    tolerance = ["tolerance", *(f"tolerance.{a}" for a in TOLERANCE_AXES[kind])]
    tolerance = [c for c in tolerance if _present(rows, c)] + ["min_margin"]
    out = {}
    for name, panels, empty in (
        ("optimum", _distinct(rows, optimum), "no design quantity changes across this sweep"),
        ("tolerance", _distinct(rows, tolerance), ""),
    ):
        figure = _figure(axes, rows, panels, empty, f"{name} across the sweep", labels)
        if name == "tolerance" and len(tolerance) == 1:
            figure.axes[0].set_title("smallest margin (tolerance not computed: the spec's "
                                     "objective does not ask for max_offset_tolerance)",
                                     fontsize=8)
        for fmt in ("png", "svg"):
            out[f"{name}.{fmt}"] = _render(figure, fmt)
    return out


def labels_of(kind: str) -> dict[str, tuple[str, str]]:
    """{column: (label, unit)} of a design table of a scene of `kind`: the shared ones with the
    scene's own over them (Scene.column_labels)."""
    from ..plugin import scene_kind

    return {**_LABELS, **scene_kind(kind).column_labels}


def _distinct(rows, columns) -> list[list[str]]:
    """The columns grouped by equal values at every row (each group one panel), in order."""
    groups: list[list[str]] = []
    for column in columns:
        values = [number(r.get(column, "")) for r in rows]
        for group in groups:
            if [number(r.get(group[0], "")) for r in rows] == values:
                group.append(column)
                break
        else:
            groups.append([column])
    return groups


def _label(columns, labels: dict) -> tuple[str, float]:
    """(the y label of a panel showing `columns`, the factor its values are drawn with)."""
    text, unit = labels.get(columns[0], (columns[0], ""))
    text = " = ".join([text, *(c.rsplit(".", 1)[-1] for c in columns[1:])])
    if unit == "m":
        return f"{text} (mm)", 1e3
    return (f"{text} ({unit})" if unit else text), 1.0


def _x_axis(axis, labels: dict) -> tuple[str, float]:
    name = axis.path[-1]
    metres = axis.path[0] != "requirements" and labels.get(name, (name, ""))[1] == "m"
    if name in LENGTH_KEYS or metres:
        return f"{axis.column} (mm)", 1e3
    return axis.column, 1.0


def _present(rows, column) -> bool:
    return any(number(r.get(column, "")) is not None for r in rows)


def _varies(rows, column) -> bool:
    values = {number(r.get(column, "")) for r in rows} - {None}
    return len(values) > 1


def _series(axes, rows, column):
    """[(label, xs, ys, ok flags)] with one entry per combination of the other axes."""
    points = grid_points(axes)
    groups: dict[tuple[int, ...], list[int]] = {}
    for i, point in enumerate(points):
        groups.setdefault(point.index[1:], []).append(i)
    keys = sorted(groups)
    if len(keys) > MAX_LINES:  # evenly spaced subset of the lines
        step = (len(keys) - 1) / (MAX_LINES - 1)
        keys = [keys[round(j * step)] for j in range(MAX_LINES)]
    out = []
    for key in keys:
        members = groups[key]
        label = ", ".join(f"{a.column} = {a.values[i]:g}" for a, i in zip(axes[1:], key))
        xs = [points[i].values[0] for i in members]
        ys = [number(rows[i].get(column, "")) for i in members]
        ok = [rows[i].get("status") in SUCCESS for i in members]
        out.append((label, xs, [math.nan if y is None else y for y in ys], ok))
    return out


def _figure(axes, rows, panels, empty, title, labels=None):
    """panels: groups of columns equal at every point, one panel each; labels: {column: (label,
    unit)} (default: the shared ones)."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    count = max(1, len(panels))
    cols = 1 if count == 1 else 2
    nrows = math.ceil(count / cols)
    figure = Figure(figsize=(5.0 * cols, 2.8 * nrows + 0.9), layout="constrained")
    figure.suptitle(title)
    grid = figure.subplots(nrows, cols, squeeze=False)
    flat = [a for row in grid for a in row]
    for extra in flat[count:]:
        extra.set_visible(False)
    xlabel, xscale = _x_axis(axes[0], labels or _LABELS)
    if not panels:
        flat[0].text(0.5, 0.5, empty, ha="center", va="center", transform=flat[0].transAxes)
        flat[0].set_xlabel(xlabel)
        return figure
    lo, hi = min(axes[0].values) * xscale, max(axes[0].values) * xscale
    pad = 0.04 * (hi - lo) or 0.5 * max(abs(lo), 1e-12)
    failed = False
    for ax, columns in zip(flat, panels):
        ylabel, yscale = _label(columns, labels or _LABELS)
        for label, xs, ys, ok in _series(axes, rows, columns[0]):
            xs = [x * xscale for x in xs]
            ys = [y * yscale for y in ys]
            ax.plot(xs, ys, marker="o", markersize=3, label=label or None)
            bad = [(x, y) for x, y, good in zip(xs, ys, ok) if not good and not math.isnan(y)]
            if bad:
                failed = True
                ax.plot(*zip(*bad), linestyle="none", marker="x", color="tab:red",
                        markersize=6)
        ax.set_xlim(lo - pad, hi + pad)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.grid(True, alpha=0.3)
        if len(axes) > 1:
            ax.legend(fontsize=6)
    if failed:
        marker = Line2D([], [], linestyle="none", marker="x", color="tab:red", markersize=6)
        figure.legend([marker], ["not a success (infeasible or failed: see the table's "
                                 "status and reason)"], loc="outside lower center", fontsize=7)
    return figure


def _render(figure, fmt: str) -> bytes:
    return render_figure(figure, fmt, dpi=110)
