"""The rimless wheel in the build sheet's DXF (sheet/dxf.py): GROUND (the ramp's surface or the
stairs' profile, and a POINT at every foothold: foothold 0 and one a step), WHEEL (the wheel at
its start: a LINE a spoke from the hub's centre to its tip, a CIRCLE of the hub's radius of
gyration, or a mark 1/40 of the spacing across for a point mass), DIMENSIONS (the footholds'
spacing along the ramp, ALIGNED; or the tread and the rise) and NOTES (the step numbers, the
slope in degrees)."""

from __future__ import annotations

import math

from ...sheet.dxf import dimension_style
from ...sheet.dxf import point_mm as _p
from ...sheet.parts import MM
from .sheet import numbers, wheel_spokes


def draw_dxf(msp, sheet) -> float:
    """The ground and the wheel; returns the notes' text height (mm): 1/20 of the spacing."""
    g = numbers(sheet.spec)
    size = g["chord"] * MM / 20
    if g["stairs"]:
        _stairs(msp, sheet, g, size)
    else:
        _ramp(msp, sheet, g, size)
    _wheel(msp, sheet, g, size)
    return size


def _feet(msp, sheet, size):
    ground = {"layer": "GROUND"}
    msp.add_point((0.0, 0.0), dxfattribs=ground)
    for item in sheet.items:
        at = _p(item["foot_x_m"], item.get("foot_y_m", item.get("level_m", 0.0)))
        msp.add_point(at, dxfattribs=ground)
        msp.add_text(str(item["step"]), height=size, dxfattribs={"layer": "NOTES"}
                     ).set_placement((at[0], at[1] - 2 * size))


def _ramp(msp, sheet, g, size):
    beta, chord = g["slope"], g["chord"]
    down = (math.cos(beta), -math.sin(beta))
    ends = [(-0.5 * chord * down[0], -0.5 * chord * down[1]),
            ((sheet.count + 0.5) * chord * down[0], (sheet.count + 0.5) * chord * down[1])]
    msp.add_line(_p(*ends[0]), _p(*ends[1]), dxfattribs={"layer": "GROUND"})
    _feet(msp, sheet, size)
    first = sheet.items[0]
    msp.add_aligned_dim(p1=(0.0, 0.0), p2=_p(first["foot_x_m"], first["foot_y_m"]),
                        distance=-3 * size, override=dimension_style(size),
                        dxfattribs={"layer": "DIMENSIONS"}).render()
    msp.add_text(f"slope {math.degrees(beta):.4f} deg", height=size,
                 dxfattribs={"layer": "NOTES"}).set_placement((0.0, 3 * size))


def _stairs(msp, sheet, g, size):
    items, s0 = sheet.items, g["landing_offset"]
    profile = [(-s0 - 0.3 * g["tread"], g["rise"]), (-s0, g["rise"]), (-s0, 0.0),
               (items[0]["back_x_m"], 0.0)]
    for item in items:
        profile += [(item["back_x_m"], item["level_m"]), (item["nose_x_m"], item["level_m"])]
    last = items[-1]
    profile.append((last["nose_x_m"], last["level_m"] - last["rise_m"]))
    msp.add_lwpolyline([_p(*c) for c in profile], dxfattribs={"layer": "GROUND"})
    _feet(msp, sheet, size)
    style, attribs = dimension_style(size), {"layer": "DIMENSIONS"}
    first = items[0]
    msp.add_linear_dim(base=(0, first["level_m"] * MM - 4 * size),
                       p1=_p(first["back_x_m"], first["level_m"]),
                       p2=_p(first["nose_x_m"], first["level_m"]), angle=0, override=style,
                       dxfattribs=attribs).render()
    msp.add_linear_dim(base=(first["back_x_m"] * MM - 2 * size, 0),
                       p1=_p(first["back_x_m"], 0.0),
                       p2=_p(first["back_x_m"], first["level_m"]), angle=90, override=style,
                       dxfattribs=attribs).render()


def _wheel(msp, sheet, g, size):
    hub, tips = wheel_spokes(sheet.spec, g)
    for tip in tips:
        msp.add_line(hub, tip, dxfattribs={"layer": "WHEEL"})
    radius = sheet.spec.scene.wheel.gyration * MM
    msp.add_circle(hub, radius if radius > 0 else size / 2, dxfattribs={"layer": "WHEEL"})
