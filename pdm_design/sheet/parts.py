"""The device as a workshop builds it, in millimetres and degrees: every pivot and hole, the parts
list, and the tolerances by part. The drawing, the DXF and the report page all take their
numbers from here (the sheet's CSV and the JSON stay SI).

Manipulators. A parallelogram of two links of length l (hole centre to hole centre). The
design's pivot (x_k, y_k) is the centre of the circle the palm's top-surface centre moves on:
palm top centre = pivot + l (sin theta, cos theta), theta the links' angle from vertical,
positive towards +x (the back stop at -alpha, the handover at beta). The links' holes lie
HOLE_SPACING_FRACTION of the palm's width apart, symmetric about the centre line: on the
bracket at (x_k -+ s/2, y_k - T), on the palm's underside at (palm top centre -+ s/2, - T), T the
palm's thickness; so each link is exactly l long and parallel to the other.

Stairs. Step k's tread is the level y_k from its back (the riser) x to its nose x; the ball is
launched at x = 0 (sheet/build.py).

Tolerances are a list of ToleranceEntry (quantity, applies_to, value, unit, limited_by): the
sheet's own (the pivot placement box, or the steps' rise and tread) and any a tolerance analysis
adds (link length, back stop, palm mass, friction, ...); each is shown on the part whose name its
applies_to mentions, or under "other tolerances".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..units import workshop

MM = 1e3
HOLE_SPACING_FRACTION = 0.5   # link holes on the palm: half the palm's width apart
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


# part names, and the words of a ToleranceEntry.applies_to that put it on that part
PART_WORDS = {
    "pivot bracket": ("pivot", "bracket"), "link": ("link",), "palm": ("palm",),
    "back stop": ("back stop", "back_stop", "alpha"), "front stop": ("front stop", "front_stop"),
    "step": ("step", "rise", "tread"), "feed": ("feed", "launch", "start"),
}


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
    """The sheet's tolerances: its own (pivot box or step rise and tread), then the extra ones
    it was given (BuildSheet.tolerances)."""
    own = []
    tol = sheet.tolerance
    if tol and not getattr(sheet, "statistical", False):  # statistical: among the others
        covers = sheet.tolerance_covers
        why = f"{BOX_WORDS}: {sheet.tolerance_note}"
        if sheet.kind == "manipulators":
            where = f"pivot bracket of manipulators 1 to {covers}"
            own = [ToleranceEntry("pivot x (box)", where, tol["dx"], "m", why),
                   ToleranceEntry("pivot y (box)", where, tol["dy"], "m", why)]
        else:
            where = f"step 1 to {covers}"
            own = [ToleranceEntry("rise (box)", where, tol["rise"], "m", why),
                   ToleranceEntry("tread (box)", where, tol["tread"], "m", why)]
    return (*own, *getattr(sheet, "tolerances", ()))


def part_of(entry: ToleranceEntry) -> str | None:
    """The parts-list name an entry belongs to (by the words of its applies_to), or None."""
    words = entry.applies_to.lower()
    for part, keys in PART_WORDS.items():
        if any(k in words for k in keys):
            return part
    return None


# --------------------------------------------------------------------------- geometry

def hole_spacing(sheet) -> float:
    """Distance between a palm's two link holes (m)."""
    return HOLE_SPACING_FRACTION * sheet.spec.scene.palm.width


def link_holes(pivot: tuple[float, float], theta: float, link: float, spacing: float,
               thickness: float) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """[(bracket hole, palm hole)] of the two links at angle theta (m)."""
    x, y = pivot
    cx, cy = x + link * math.sin(theta), y + link * math.cos(theta)
    return [((x + side * spacing / 2, y - thickness), (cx + side * spacing / 2, cy - thickness))
            for side in (-1.0, 1.0)]


def pivots(sheet) -> list[tuple[int, float, float]]:
    """[(k, x, y)] of every manipulator's pivot (m)."""
    return [(item["manipulator"], item["pivot_x_m"], item["pivot_y_m"]) for item in sheet.items]


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
    entries = tolerance_entries(sheet)
    by_part: dict[str | None, list[ToleranceEntry]] = {}
    for entry in entries:
        by_part.setdefault(part_of(entry), []).append(entry)
    maker = _manipulator_parts if sheet.kind == "manipulators" else _stairs_parts
    parts = maker(sheet)
    named = {p.name for p in parts}
    out = tuple(Part(p.name, p.quantity, p.dimensions, tuple(by_part.get(p.name, ())))
                for p in parts)
    other = tuple(e for key, group in by_part.items() if key not in named for e in group)
    return out, other


def _manipulator_parts(sheet) -> list[Part]:
    d, scene, n = sheet.design, sheet.spec.scene, sheet.count
    a, l = d["alpha"], d["link_length"]
    palm, fs = scene.palm, scene.palm.front_stop
    px, py = sheet.geometry["pitch_x"], sheet.geometry["pitch_y"]
    x0, y0 = d["first_pivot_x"], d["first_pivot_y"]
    s, t = hole_spacing(sheet), palm.thickness
    palm_mass = scene.body.mass / d["mass_ratio"]
    rest_x, rest_y = l * math.sin(-a), l * math.cos(-a)
    front_x, front_y = l * math.sin(fs), l * math.cos(fs)
    return [
        Part("pivot bracket", n, f"pivot k at x = {mm(x0)} + (k - 1) x {mm(px)} mm, y = "
             f"{mm(y0)} - (k - 1) x {mm(py)} mm; two holes at x -+ {mm(s / 2)}, y - {mm(t)} mm"),
        Part("link", 2 * n, f"hole spacing {mm(l)} mm (centre to centre)"),
        Part("palm", n, f"{mm(palm.width)} x {mm(palm.thickness)} mm, mass "
             f"{palm_mass:.4g} kg; two holes {mm(s)} mm apart on its underside, centred"),
        Part("back stop", n, f"links at {deg(-a)} deg from vertical; palm top centre at "
             f"({mm(rest_x)}, {mm(rest_y)}) mm from the pivot"),
        Part("front stop", n, f"links at {deg(fs)} deg from vertical; palm top centre at "
             f"({mm(front_x)}, {mm(front_y)}) mm from the pivot"),
    ]


def _stairs_parts(sheet) -> list[Part]:
    first = sheet.items[0]
    same = all(abs(i["rise_m"] - first["rise_m"]) < 1e-12 and
               abs(i["tread_m"] - first["tread_m"]) < 1e-12 for i in sheet.items)
    size = (f"rise {mm(first['rise_m'])} mm, tread {mm(first['tread_m'])} mm" if same else
            "rise and tread of each step in the CSV")
    launch = sheet.design["launch_speed"]
    return [
        Part("step", sheet.count, size + f"; tread 1 back at x = {mm(first['back_x_m'])} mm"),
        Part("feed", 1, f"ball launched horizontally at {mm(launch)} mm/s from x = 0, "
             f"{mm(sheet.spec.scene.initial.drop_height)} mm above tread 1"),
    ]
