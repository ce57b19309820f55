"""The manipulators in the build sheet's DXF (sheet/dxf.py): PIVOTS (a POINT at every design
pivot and a circle at every bracket hole), LINKS (each link as a line between its holes, a circle
at every palm hole), PALMS (each palm at its back stop), STOPS (the back- and front-stop
directions of every manipulator), and on DIMENSIONS the pitch, the link length, the feed and the
tolerance boxes."""

from __future__ import annotations

import math

from ...sheet.dxf import HOLE_MARK, dimension_style
from ...sheet.dxf import point_mm as _p
from ...sheet.parts import MM, deg, mm
from .sheet import hole_spacing, link_holes, pivots


def draw_dxf(msp, sheet) -> float:
    """Every manipulator; returns the notes' text height (mm): 1/30 of the link length."""
    size = sheet.design["link_length"] * MM / 30
    _manipulators(msp, sheet, size)
    return size


def _manipulators(msp, sheet, size):
    d, scene = sheet.design, sheet.spec.scene
    a, l, fs = d["alpha"], d["link_length"], scene.palm.front_stop
    width, thick = scene.palm.width, scene.palm.thickness
    s = hole_spacing(sheet)
    tol = sheet.tolerance
    for k, x, y in pivots(sheet):
        msp.add_point(_p(x, y), dxfattribs={"layer": "PIVOTS"})
        holes = link_holes((x, y), -a, l, s, thick)
        for bracket, palm in holes:
            msp.add_circle(_p(*bracket), HOLE_MARK / 2, dxfattribs={"layer": "PIVOTS"})
            msp.add_circle(_p(*palm), HOLE_MARK / 2, dxfattribs={"layer": "LINKS"})
            msp.add_line(_p(*bracket), _p(*palm), dxfattribs={"layer": "LINKS"})
        cx, cy = x + l * math.sin(-a), y + l * math.cos(-a)
        corners = [(cx - width / 2, cy - thick), (cx + width / 2, cy - thick),
                   (cx + width / 2, cy), (cx - width / 2, cy)]
        msp.add_lwpolyline([_p(*c) for c in corners], close=True, dxfattribs={"layer": "PALMS"})
        for angle in (-a, fs):
            end = (x + 0.35 * l * math.sin(angle), y + 0.35 * l * math.cos(angle))
            msp.add_line(_p(x, y), _p(*end), dxfattribs={"layer": "STOPS"})
        msp.add_text(str(k), height=size, dxfattribs={"layer": "NOTES"}).set_placement(
            (x * MM + size / 2, y * MM - 2 * size))
        if tol and k <= sheet.tolerance_covers:
            dx, dy = tol["dx"], tol["dy"]
            box = [(x - dx, y - dy), (x + dx, y - dy), (x + dx, y + dy), (x - dx, y + dy)]
            msp.add_lwpolyline([_p(*c) for c in box], close=True,
                               dxfattribs={"layer": "DIMENSIONS"})
    _manipulator_dimensions(msp, sheet, size)


def _manipulator_dimensions(msp, sheet, size):
    d = sheet.design
    a, l = d["alpha"], d["link_length"]
    style = dimension_style(size)
    attribs = {"layer": "DIMENSIONS"}
    items = sheet.items
    x1, y1 = items[0]["pivot_x_m"], items[0]["pivot_y_m"]
    holes = link_holes((x1, y1), -a, l, hole_spacing(sheet), sheet.spec.scene.palm.thickness)
    bracket, palm = holes[0]
    msp.add_aligned_dim(p1=_p(*bracket), p2=_p(*palm), distance=-3 * size, override=style,
                        dxfattribs=attribs).render()
    if len(items) > 1:
        x2, y2 = items[1]["pivot_x_m"], items[1]["pivot_y_m"]
        below = min(y1, y2) * MM - 0.3 * l * MM
        msp.add_linear_dim(base=(x1 * MM, below), p1=_p(x1, y1), p2=_p(x2, y2), angle=0,
                           override=style, dxfattribs=attribs).render()
        msp.add_linear_dim(base=(x2 * MM + 0.2 * l * MM, y1 * MM), p1=_p(x1, y1),
                           p2=_p(x2, y2), angle=90, override=style, dxfattribs=attribs).render()
    fs = sheet.spec.scene.palm.front_stop
    for angle, words in ((-a, "back stop"), (d["beta"], "handover"), (fs, "front stop")):
        at = (x1 + 0.4 * l * math.sin(angle), y1 + 0.4 * l * math.cos(angle))
        msp.add_text(f"{words} {deg(angle)} deg", height=0.6 * size,
                     dxfattribs={"layer": "NOTES"}).set_placement(_p(*at))
    start, speed = sheet.spec.scene.initial.position, sheet.spec.scene.initial.velocity
    msp.add_point(_p(*start), dxfattribs={"layer": "DIMENSIONS"})
    msp.add_linear_dim(base=(x1 * MM, start[1] * MM + 2 * size), p1=_p(*start), p2=_p(x1, y1),
                       angle=0, override=style, dxfattribs=attribs).render()
    msp.add_linear_dim(base=(start[0] * MM - 2 * size, y1 * MM), p1=_p(*start), p2=_p(x1, y1),
                       angle=90, override=style, dxfattribs=attribs).render()
    msp.add_text(f"feed: start ({mm(start[0])}, {mm(start[1])}) mm at ({mm(speed[0])}, "
                 f"{mm(speed[1])}) mm/s", height=0.7 * size,
                 dxfattribs={"layer": "NOTES"}).set_placement((start[0] * MM,
                                                              start[1] * MM + 4 * size))
