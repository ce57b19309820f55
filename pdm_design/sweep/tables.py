"""Rows of a design table: the columns of each scene, one outcome as a row, CSV and Markdown.

Cells are text: numbers as `repr(float)` (exact: a row read back gives the same floats), empty
for a quantity that does not exist, `true`/`false` for booleans. The final CSV and Markdown are
made from these cells, whether a row was computed in this run or read back by `--resume`, so an
interrupted and resumed sweep writes the same files as an uninterrupted one.
"""

from __future__ import annotations

import csv
import io
import math

from ..plugin import scene_kind
from ..scenes.common import is_number


class _ByKind:
    """A scene's names of one group of table columns, looked up by kind (Scene attributes)."""

    def __init__(self, get):
        self._get = get

    def __getitem__(self, kind: str) -> tuple[str, ...]:
        return tuple(self._get(scene_kind(kind)))


DESIGN = _ByKind(lambda scene: scene.design_class().VARIABLES)
GEOMETRY = _ByKind(lambda scene: scene.table_geometry)
PERIODIC = _ByKind(lambda scene: scene.table_periodic)
TOLERANCE_AXES = _ByKind(lambda scene: scene.tolerance_axes)
ERROR = "error"
"""Status of a grid point whose solve raised: retried by --resume."""


def columns(kind: str, sweep_columns: tuple[str, ...]) -> tuple[str, ...]:
    """Every column of a design table of this scene kind, in order."""
    return (
        *sweep_columns, "status",
        *DESIGN[kind], *GEOMETRY[kind], *PERIODIC[kind],
        "objective", "tolerance", *(f"tolerance.{a}" for a in TOLERANCE_AXES[kind]),
        "min_margin", "min_margin_name", *(f"margin.{m}" for m in scene_kind(kind).margins),
        "verified", "verification", "solver_iterations", "reason",
    )


def cell(value) -> str:
    """One value as CSV text."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float) or hasattr(value, "__float__"):
        number = float(value)
        return repr(number) if math.isfinite(number) else ""
    return " ".join(str(value).split())  # one line, whatever the message


def outcome_cells(outcome, kind: str) -> dict[str, str]:
    """The cells of one solved grid point (a DesignOutcome), keyed by column (no sweep columns)."""
    analysis = outcome.analysis
    row: dict[str, object] = {"status": outcome.status.value}
    for name in DESIGN[kind]:
        row[name] = analysis.design.get(name)
    for name in GEOMETRY[kind]:
        row[name] = analysis.geometry.get(name)
    for name in PERIODIC[kind]:
        row[name] = analysis.periodic.get(name)
    objective = outcome.objective or {}
    row["objective"] = objective.get("value") if isinstance(objective, dict) else None
    tolerance = outcome.tolerance or {}
    sides = [float(v) for k, v in tolerance.items() if is_number(v) and k != "volume"]
    row["tolerance"] = min(sides) if sides else None
    for axis in TOLERANCE_AXES[kind]:
        value = tolerance.get(axis)
        row[f"tolerance.{axis}"] = value if is_number(value) else None
    margins = analysis.margins
    if margins:
        # Ties within rounding (a frictionless launch is flight 1's own nose condition) go to the
        # first in the scene's list, so the column does not flicker from row to row.
        least = min(margins.values())
        worst = next(n for n in (*scene_kind(kind).margins, *margins)
                     if n in margins and margins[n] <= least + 1e-12)
        row["min_margin"], row["min_margin_name"] = margins[worst], worst
    for name in scene_kind(kind).margins:
        row[f"margin.{name}"] = margins.get(name)
    verification = outcome.verification
    if verification is not None:
        row["verified"] = bool(verification.get("passed"))
        row["verification"] = verification.get("summary", "")
    solver = outcome.solver or {}
    iterations = solver.get("iterations") if isinstance(solver, dict) else None
    row["solver_iterations"] = iterations if is_number(iterations) else None
    row["reason"] = _reason(outcome)
    return {k: cell(v) for k, v in row.items()}


def error_cells(error: BaseException) -> dict[str, str]:
    """The cells of a grid point whose solve raised."""
    return {"status": ERROR, "reason": cell(f"{type(error).__name__}: {error}")}


def _reason(outcome) -> str:
    if not outcome.status.is_success:
        why = "; ".join(outcome.violations) if outcome.violations else outcome.status_message
        return why
    verification = outcome.verification
    if verification is not None and not verification.get("passed", False):
        return f"verification failed: {verification.get('summary', '')}"
    return ""



# --------------------------------------------------------------------------- CSV

def csv_line(values) -> str:
    """One CSV record (with its line end) for a sequence of cells."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(values)
    return buffer.getvalue()


def csv_text(header: tuple[str, ...], rows: list[dict[str, str]]) -> str:
    return csv_line(header) + "".join(csv_line([r.get(c, "") for c in header]) for r in rows)


def read_csv(text: str) -> tuple[list[str], list[dict[str, str]]]:
    """Header and rows of a table's CSV. A last line without its line end (a write cut short)
    is not a row."""
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
    records = list(csv.reader(io.StringIO(text)))
    if not records:
        return [], []
    header, body = records[0], records[1:]
    return header, [dict(zip(header, r)) for r in body if len(r) == len(header)]


# --------------------------------------------------------------------------- Markdown

def number(text: str) -> float | None:
    """A cell's number, or None."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def _shown(text: str) -> str:
    value = number(text)
    if value is None:
        return (text or "-").replace("|", "\\|")
    return f"{value:.6g}"


def _markdown_table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(_shown(c) for c in row) + " |" for row in rows]
    return lines


def markdown(kind: str, title: str, description: list[str], sweep_columns: tuple[str, ...],
             rows: list[dict[str, str]]) -> str:
    """The design table in Markdown: the varying quantities per point, the ones that do not vary
    listed once, the margins, and why each failing point fails."""
    counts: dict[str, int] = {}
    for row in rows:
        counts[row.get("status", "")] = counts.get(row.get("status", ""), 0) + 1
    lines = [f"# {title}", "", *description, "",
             f"{len(rows)} points: " + ", ".join(f"{n} {s}" for s, n in sorted(counts.items())),
             ""]
    main = [*DESIGN[kind], *GEOMETRY[kind], *PERIODIC[kind], "objective", "tolerance",
            *(f"tolerance.{a}" for a in TOLERANCE_AXES[kind]), "min_margin",
            "min_margin_name", "verified"]
    swept = {c.split(".", 1)[1] for c in sweep_columns if c.startswith("design.")}
    present = [c for c in main if c not in swept and any(r.get(c, "") != "" for r in rows)]
    constant = [c for c in present if len(rows) > 1 and len({r.get(c, "") for r in rows}) == 1]
    varying = [c for c in present if c not in constant]
    if constant:
        lines += ["Same at every point: " + ", ".join(
            f"{c} = {_shown(rows[0].get(c, ''))}" for c in constant) + ".", ""]
    header = [*sweep_columns, "status", *varying]
    lines += _markdown_table(header, [[r.get(c, "") for c in header] for r in rows])
    margin_columns = [f"margin.{m}" for m in scene_kind(kind).margins
                      if any(r.get(f"margin.{m}", "") != "" for r in rows)]
    if margin_columns:
        lines += ["", "## Margins", "",
                  "Normalised slack of each condition (>= 0 holds; see docs/json-schema.md).", ""]
        header = [*sweep_columns, *margin_columns]
        lines += _markdown_table([*sweep_columns, *(c.split(".", 1)[1] for c in margin_columns)],
                                 [[r.get(c, "") for c in header] for r in rows])
    failing = [r for r in rows if r.get("reason")]
    if failing:
        lines += ["", "## Why points fail", ""]
        for r in failing:
            where = ", ".join(f"{c} = {_shown(r.get(c, ''))}" for c in sweep_columns)
            lines.append(f"- {where} ({r.get('status', '')}): {r['reason']}")
    return "\n".join(lines) + "\n"
