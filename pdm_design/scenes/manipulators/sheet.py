"""The manipulators' build sheet (sheet/build.py): the coordinates of every pivot (frame of the
spec: origin at the first manipulator's nominal pivot when first_pivot_x = first_pivot_y = 0, x
along the row, y up), the back-stop, handover and front-stop angles, link length, palm mass and
size, the box (+-dx, +-dy) each pivot may be placed within, and the parts list.

A parallelogram of two links of length l (hole centre to hole centre). The design's pivot
(x_k, y_k) is the centre of the circle the palm's top-surface centre moves on: palm top centre =
pivot + l (sin theta, cos theta), theta the links' angle from vertical, positive towards +x (the
back stop at -alpha, the handover at beta). The links' holes lie HOLE_SPACING_FRACTION of the
palm's width apart, symmetric about the centre line: on the bracket at (x_k -+ s/2, y_k - T), on
the palm's underside at (palm top centre -+ s/2, - T), T the palm's thickness; so each link is
exactly l long and parallel to the other.
"""

from __future__ import annotations

import math

from ...sheet.generic import SheetWords
from ...sheet.parts import MM, Part, ToleranceEntry, deg, mm
from . import physics as phys

HOLE_SPACING_FRACTION = 0.5   # link holes on the palm: half the palm's width apart
# part names, and the words of a ToleranceEntry.applies_to that put it on that part
PART_WORDS = {
    "pivot bracket": ("pivot", "bracket"), "link": ("link",), "palm": ("palm",),
    "back stop": ("back stop", "back_stop", "alpha"), "front stop": ("front stop", "front_stop"),
    "feed": ("feed", "launch", "start"),
}
WORDS = SheetWords(
    item="pivot", units="millimetres, degrees",
    legend="solid: links and palms at the back stop; dashed: at the handover angle; red boxes: "
           "pivot tolerance (to scale); stars: handover points; dotted: the object's path "
           "(simulated)")


def sheet_rows(spec, analysis, tol, count):
    d, scene = analysis.design, spec.scene
    a, b, l = d["alpha"], d["beta"], d["link_length"]
    px, py = analysis.geometry["pitch_x"], analysis.geometry["pitch_y"]  # py: downward
    x0, y0 = d["first_pivot_x"], d["first_pivot_y"]
    palm_mass = scene.body.mass / d["mass_ratio"]
    tx, ty = (tol["dx"], tol["dy"]) if tol else (None, None)
    covered = spec.verification.stages
    items = []
    for k in range(1, count + 1):
        x, y = x0 + (k - 1) * px, y0 - (k - 1) * py
        back_x, back_y = (float(v) for v in phys.palm_centre(x, y, -a, l))
        hand_x, hand_y = (float(v) for v in phys.palm_centre(x, y, b, l))
        items.append({
            "manipulator": k, "pivot_x_m": x, "pivot_y_m": y,
            "pivot_x_tolerance_m": tx if k <= covered else None,
            "pivot_y_tolerance_m": ty if k <= covered else None,
            "back_stop_rad": -a, "handover_rad": b, "front_stop_rad": scene.palm.front_stop,
            "link_length_m": l, "palm_mass_kg": palm_mass,
            "palm_at_back_stop_x_m": back_x, "palm_at_back_stop_y_m": back_y,
            "handover_x_m": hand_x, "handover_y_m": hand_y,
        })
    summary = [
        ("manipulators", count, "", None),
        ("pitch x (pivot to pivot, along the row)", px, "m", None),
        ("pitch y (pivot to pivot, downward)", py, "m", None),
        ("pivot k x = first pivot x + (k - 1) pitch x", x0, "m", tx),
        ("pivot k y = first pivot y - (k - 1) pitch y", y0, "m", ty),
        ("link length l", l, "m", None),
        ("back stop -alpha (clockwise from vertical)", -a, "rad", None),
        ("handover angle beta", b, "rad", None),
        ("front stop", scene.palm.front_stop, "rad", None),
        ("palm mass M = m / mass_ratio", palm_mass, "kg", None),
        ("palm width x thickness", f"{scene.palm.width * 1e3:g} x "
         f"{scene.palm.thickness * 1e3:g}", "mm", None),
        ("object mass, width x height", f"{scene.body.mass:g} kg, {scene.body.width * 1e3:g} x "
         f"{scene.body.height * 1e3:g}", "mm", None),
        ("handover speed (periodic)", analysis.periodic.get("handover_speed"), "m/s", None),
    ]
    return summary, items


def box_tolerances(sheet, why):
    where = f"pivot bracket of manipulators 1 to {sheet.tolerance_covers}"
    tol = sheet.tolerance
    return (ToleranceEntry("pivot x (box)", where, tol["dx"], "m", why),
            ToleranceEntry("pivot y (box)", where, tol["dy"], "m", why))


def parts(sheet) -> list[Part]:
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


def table_rows(sheet) -> list[str]:
    """Fixed-width rows of the pivot (bracket holes) table, mm."""
    s, t = hole_spacing(sheet) * MM, sheet.spec.scene.palm.thickness * MM
    rows = [f"{'k':>4} {'pivot x':>12} {'pivot y':>12} {'hole 1 x':>12} {'hole 2 x':>12} "
            f"{'holes y':>12} {'tol x':>8} {'tol y':>8}"]
    for item in sheet.items:
        x, y = item["pivot_x_m"] * MM, item["pivot_y_m"] * MM
        tx, ty = item["pivot_x_tolerance_m"], item["pivot_y_tolerance_m"]
        rows.append(f"{item['manipulator']:>4} {x:>12.3f} {y:>12.3f} {x - s / 2:>12.3f} "
                    f"{x + s / 2:>12.3f} {y - t:>12.3f} {_tol(tx):>8} {_tol(ty):>8}")
    return rows


def _tol(value) -> str:
    return "-" if value is None or not math.isfinite(value) else f"+-{value * MM:.3g}"


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
