"""What a scene's build sheet is made of (the data a scene gives through pdm_design.plugin.Scene)
and the sheet of a scene that gives nothing but its core: its design values, one item a stage,
the simulated path drawn, no parts."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .parts import MM, ToleranceEntry, nominal_run


@dataclass(frozen=True)
class SheetWords:
    """item: what one item's coordinates are of ("pivot": "every pivot's coordinates"); legend:
    the drawing's legend; units: the drawing's units in words ("millimetres, degrees")."""

    item: str
    legend: str
    units: str


@dataclass(frozen=True)
class BoxShift:
    """The robust box of a fixed design solved for `spec` instead (a design value the NLP holds
    to a periodic orbit left free there), its `axis` half-width less `offset` (m), the design's
    offset from `reference` (words: "the periodic flight's")."""

    spec: object
    axis: str
    offset: float
    reference: str


def sheet_rows(scene, spec, analysis, tol, count):
    """(summary, items): the design values; one item a stage, numbered."""
    noun = scene.stage_noun
    summary = [(noun[1], count, "", None)]
    summary += [(name, float(value), "", None) for name, value in analysis.design.items()
                if isinstance(value, (int, float)) and not isinstance(value, bool)]
    return summary, [{noun[0]: k} for k in range(1, count + 1)]


def box_tolerances(scene, sheet, why: str) -> tuple[ToleranceEntry, ...]:
    """One "AXIS (box)" entry an axis of the sheet's box (m), on the stages it covers."""
    where = f"{scene.stage_noun[0]} 1 to {sheet.tolerance_covers}"
    return tuple(ToleranceEntry(f"{axis} (box)", where, sheet.tolerance[axis], "m", why)
                 for axis in scene.tolerance_axes if axis in sheet.tolerance)


def table_rows(sheet) -> list[str]:
    """Every item's columns, lengths in mm (3 decimals), angles in radians."""
    header = list(sheet.items[0])
    shown = [c[:-2] if c.endswith("_m") else c for c in header]
    rows = [" ".join(f"{c:>12}" for c in shown)]
    for item in sheet.items:
        rows.append(" ".join(f"{_cell(c, item[c]):>12}" for c in header))
    return rows


def _cell(column: str, value) -> str:
    if isinstance(value, float):
        if not math.isfinite(value):
            return "-"
        return f"{value * MM:.3f}" if column.endswith("_m") else f"{value:.6g}"
    return "-" if value is None else str(value)


def _path(sheet) -> list[tuple[float, float]]:
    run = nominal_run(sheet)
    if run is None or not run.trajectory.get("x"):
        return []
    return [(x * MM, y * MM) for x, y in zip(run.trajectory["x"], run.trajectory["y"])]


def _starts(sheet) -> dict[int, tuple[float, float]]:
    """{stage: the place its stage record gives (x, y), mm} from the nominal run."""
    run = nominal_run(sheet)
    out = {}
    for k, record in enumerate(() if run is None else run.stages, 1):
        x, y = record.get("x"), record.get("y")
        if isinstance(x, (int, float)) and isinstance(y, (int, float)):
            out[k] = (x * MM, y * MM)
    return out


def draw_path(ax, labels, sheet, items) -> None:
    """The simulated path (dotted) and each drawn stage's recorded place (x, y), numbered."""
    path = _path(sheet)
    if path:
        ax.plot(*zip(*path), color="tab:green", lw=0.9, ls=":")
    starts = _starts(sheet)
    noun = next(iter(items[0]), None) if items else None  # the stage number's column
    for item in items:
        k = item.get(noun)
        if k in starts:
            ax.plot([starts[k][0]], [starts[k][1]], marker="o", color="black", markersize=3)
            labels.add(ax, str(k), starts[k], (8, 7), optional=True)


def draw_dxf(msp, sheet) -> float:
    """The simulated path as a polyline on DIMENSIONS and a POINT at each stage's recorded
    place; the text height: 1/40 of the path's extent."""
    path = _path(sheet)
    starts = _starts(sheet)
    for x, y in starts.values():
        msp.add_point((x, y), dxfattribs={"layer": "DIMENSIONS"})
    if len(path) > 1:
        msp.add_lwpolyline(path, dxfattribs={"layer": "DIMENSIONS"})
    if not starts:
        msp.add_point(path[0] if path else (0.0, 0.0), dxfattribs={"layer": "DIMENSIONS"})
    xs = [p[0] for p in path] or [0.0]
    ys = [p[1] for p in path] or [0.0]
    return max(max(xs) - min(xs), max(ys) - min(ys), 1.0) / 40
