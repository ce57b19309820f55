"""The staircase's build sheet (sheet/build.py): every step's rise and tread with their
tolerance, and where each step's back, nose and tread surface are (frame: the ball is launched at
x = 0; nominal tread 1 is at y = 0); the parts list. Step k's tread is the level y_k from its back
(the riser) x to its nose x."""

from __future__ import annotations

import dataclasses
import math

from ...sheet.generic import BoxShift, SheetWords
from ...sheet.parts import MM, Part, mm

PART_WORDS = {"step": ("step", "rise", "tread"), "feed": ("feed", "launch", "start")}
WORDS = SheetWords(item="step", units="millimetres",
                   legend="dashed: the ball's centre (simulated); circles: the ball at each "
                          "impact")


def sheet_rows(spec, analysis, tol, count):
    from .sim import stairs_geometry

    geo = stairs_geometry(spec.scene, spec.design_at())
    tr, tt = (tol["rise"], tol["tread"]) if tol else (None, None)
    covered = spec.verification.stages
    items = []
    for k in range(1, count + 1):
        items.append({
            "step": k, "rise_m": geo.rise_height(k), "tread_m": geo.tread_length(k),
            "rise_tolerance_m": tr if k <= covered else None,
            "tread_tolerance_m": tt if k <= covered else None,
            "back_x_m": geo.back_x(k), "nose_x_m": geo.nose_x(k), "level_m": geo.level(k),
            "landing_from_back_m": geo.landing_offset,
        })
    d = analysis.design
    summary = [
        ("steps", count, "", None),
        ("rise (every step)", geo.rise, "m", tr),
        ("tread (every step)", geo.tread, "m", tt),
        ("landing point from the back of each tread", geo.landing_offset, "m", None),
        ("launch height above tread 1", geo.launch_height, "m", None),
        ("launch speed (horizontal)", d["launch_speed"], "m/s", None),
        ("back of tread 1 (launch at x = 0)", geo.x_back_1, "m", None),
        ("restitution", d["restitution"], "", None),
        ("ball radius", spec.scene.ball.radius, "m", None),
        ("impact speed (periodic)", analysis.periodic.get("impact_speed"), "m/s", None),
    ]
    return summary, items


def box_shift(spec) -> BoxShift | None:
    """The spec with a given tread left to the periodic flight, and |tread - that tread|.

    The NLP holds a given tread to the periodic flight's (optimizer.md, section 9), which an
    optimizer's answer meets only to its tolerance (6e-8 m off found no box). Built with tread
    T + d, every step is the periodic design's with a tread error d, so the periodic design's
    box, its tread half-width less |d|, holds for it."""
    if spec.design.get("tread") is None:
        return None
    from .analysis import analyse_stairs

    periodic = analyse_stairs(spec.scene, spec.design_at(), spec.verification.stages).periodic
    drift = periodic.get("drift_per_bounce")
    if drift is None:
        return None
    design = {name: value for name, value in spec.design.items() if name != "tread"}
    return BoxShift(dataclasses.replace(spec, design=design), "tread", abs(float(drift)),
                    "the periodic flight's")


def parts(sheet) -> list[Part]:
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


def table_rows(sheet) -> list[str]:
    """Fixed-width rows of the step table, mm."""
    rows = [f"{'k':>4} {'rise':>10} {'tread':>10} {'back x':>12} {'nose x':>12} {'level':>12} "
            f"{'tol rise':>9} {'tol tread':>9}"]
    for item in sheet.items:
        rows.append(f"{item['step']:>4} {item['rise_m'] * MM:>10.3f} "
                    f"{item['tread_m'] * MM:>10.3f} {item['back_x_m'] * MM:>12.3f} "
                    f"{item['nose_x_m'] * MM:>12.3f} {item['level_m'] * MM:>12.3f} "
                    f"{_tol(item['rise_tolerance_m']):>9} {_tol(item['tread_tolerance_m']):>9}")
    return rows


def _tol(value) -> str:
    return "-" if value is None or not math.isfinite(value) else f"+-{value * MM:.3g}"
