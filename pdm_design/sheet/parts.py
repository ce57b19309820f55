"""The device as a workshop builds it, in millimetres and degrees: every item it places, the parts
list, and the tolerances by part. The drawing, the DXF and the report page all take their
numbers from here (the sheet's CSV and the JSON stay SI).

What a scene places and builds, and its parts, are the scene's (Scene.sheet_rows,
Scene.parts: scenes/<kind>/sheet.py).

Tolerances are a list of ToleranceEntry (quantity, applies_to, value, unit, limited_by): the
sheet's own (its placement box, Scene.box_tolerances) and any a tolerance analysis adds; each is
shown on the part whose words (Scene.part_words) its applies_to mentions, or under "other
tolerances".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..units import workshop

MM = 1e3
BOX_WORDS = ("worst-case box the optimizer computed (every build with all its errors inside it "
             "works)")
_RUNS: dict[int, tuple] = {}  # id(sheet) -> (sheet, its nominal run or None)


@dataclass(frozen=True)
class ToleranceEntry:
    """One tolerance: +-value (unit SI: m, rad, kg, or '' for a ratio) of `quantity`, on the
    part(s) `applies_to` names; `limited_by` says what sets it (a margin, a solver)."""

    quantity: str
    applies_to: str
    value: float
    unit: str
    limited_by: str = ""

    def shown(self) -> str:
        """+-value in workshop units (mm, degrees), e.g. '+-83.1 mm'."""
        value, unit = workshop_value(self.value, self.unit)
        return f"+-{_number(value)} {unit}".rstrip()


@dataclass(frozen=True)
class Part:
    """A line of the parts list: name, how many, dimensions in words (mm, degrees), and the
    tolerances that apply to it."""

    name: str
    quantity: int
    dimensions: str
    tolerances: tuple[ToleranceEntry, ...] = ()


def workshop_value(value: float, unit: str) -> tuple[float, str]:
    """(value, unit) in workshop units (units.workshop: m -> mm, rad -> degrees, m/s -> mm/s,
    kg -> g, N m -> N mm; others as given)."""
    return workshop(value, unit)


def workshop_column(column: str, value=None) -> tuple[str, object]:
    """(the heading, the value) of a CSV column in workshop units: 'pivot_x_m' is shown as
    'pivot_x (mm)' in mm, 'back_stop_rad' as 'back_stop (deg)'; other columns as they are."""
    for suffix, unit in (("_m", "m"), ("_rad", "rad")):
        if column.endswith(suffix):
            name = column[: -len(suffix)]
            shown, words = workshop_value(value, unit) if isinstance(value, float) else (
                value, workshop_value(0.0, unit)[1])
            return f"{name} ({words})", shown
    return column, value


def _number(value: float) -> str:
    return f"{value:.4g}" if abs(value) < 1e4 else f"{value:.0f}"


def mm(value: float) -> str:
    """A length in m shown in mm to 0.01 mm (the CSV and the DXF keep every digit)."""
    return f"{value * MM:.2f}"


def deg(value: float) -> str:
    """An angle in rad shown in degrees to 0.01 degree."""
    return f"{math.degrees(value):.2f}"


# --------------------------------------------------------------------------- tolerances

def tolerance_entries(sheet) -> tuple[ToleranceEntry, ...]:
    """The sheet's tolerances: its own (its placement box, Scene.box_tolerances), then the
    extra ones it was given (BuildSheet.tolerances)."""
    from ..plugin import of

    own = ()
    if sheet.tolerance and not getattr(sheet, "statistical", False):  # statistical: among
        # the others
        own = of(sheet.spec).box_tolerances(sheet, f"{BOX_WORDS}: {sheet.tolerance_note}")
    return (*own, *getattr(sheet, "tolerances", ()))


def part_of(entry: ToleranceEntry, words: dict[str, tuple[str, ...]]) -> str | None:
    """The parts-list name an entry belongs to (by the words of its applies_to, Scene.
    part_words), or None."""
    applies = entry.applies_to.lower()
    for part, keys in words.items():
        if any(k in applies for k in keys):
            return part
    return None


# --------------------------------------------------------------------------- geometry

def nominal_run(sheet):
    """The simulator's run of the sheet's design over its items, with the trajectory (None
    when the simulator refuses it: the drawing does without the path). Kept for the last sheet
    asked: its drawing's pages all draw the same path."""
    cached = _RUNS.get(id(sheet))
    if cached is not None and cached[0] is sheet:
        return cached[1]
    try:
        from ..verify import simulate_spec

        run = simulate_spec(sheet.spec, sheet.spec.design_at(), stages=sheet.count,
                            record_trajectory=True)
    except Exception:  # e.g. more stages than the simulator keeps records for
        run = None
    _RUNS.clear()
    _RUNS[id(sheet)] = (sheet, run)
    return run


# --------------------------------------------------------------------------- parts list

def parts_list(sheet) -> tuple[tuple[Part, ...], tuple[ToleranceEntry, ...]]:
    """(the parts, the tolerances that name none of them)."""
    from ..plugin import of

    scene = of(sheet.spec)
    entries = tolerance_entries(sheet)
    by_part: dict[str | None, list[ToleranceEntry]] = {}
    for entry in entries:
        by_part.setdefault(part_of(entry, scene.part_words), []).append(entry)
    parts = scene.parts(sheet)
    named = {p.name for p in parts}
    out = tuple(Part(p.name, p.quantity, p.dimensions, tuple(by_part.get(p.name, ())))
                for p in parts)
    other = tuple(e for key, group in by_part.items() if key not in named for e in group)
    return out, other
