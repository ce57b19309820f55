"""The staircase in the build sheet's DXF (sheet/dxf.py): STEPS (the staircase's profile and a
POINT at every tread's back and nose), and on DIMENSIONS the tread, the rise and the launch."""

from __future__ import annotations

from ...sheet.dxf import dimension_style
from ...sheet.dxf import point_mm as _p
from ...sheet.parts import MM, mm


def draw_dxf(msp, sheet) -> float:
    """Every step; returns the notes' text height (mm): 1/20 of step 1's tread or rise."""
    size = max(sheet.items[0]["tread_m"], sheet.items[0]["rise_m"]) * MM / 20
    _stairs(msp, sheet, size)
    return size


def _stairs(msp, sheet, size):
    items = sheet.items
    first, last = items[0], items[-1]
    top = first["level_m"] + first["rise_m"]
    profile = [(min(0.0, first["back_x_m"]) - 0.3 * first["tread_m"], top),
               (first["back_x_m"], top)]
    for item in items:
        profile += [(item["back_x_m"], item["level_m"]), (item["nose_x_m"], item["level_m"])]
        msp.add_point(_p(item["back_x_m"], item["level_m"]), dxfattribs={"layer": "STEPS"})
        msp.add_point(_p(item["nose_x_m"], item["level_m"]), dxfattribs={"layer": "STEPS"})
        msp.add_text(str(item["step"]), height=size, dxfattribs={"layer": "NOTES"}
                     ).set_placement((item["back_x_m"] * MM + size / 2,
                                      item["level_m"] * MM + size / 2))
    profile.append((last["nose_x_m"], last["level_m"] - last["rise_m"]))
    msp.add_lwpolyline([_p(*c) for c in profile], dxfattribs={"layer": "STEPS"})
    style = dimension_style(size)
    attribs = {"layer": "DIMENSIONS"}
    msp.add_linear_dim(base=(0, (first["level_m"] - first["rise_m"]) * MM - 2 * size),
                       p1=_p(first["back_x_m"], first["level_m"]),
                       p2=_p(first["nose_x_m"], first["level_m"]), angle=0, override=style,
                       dxfattribs=attribs).render()
    if len(items) > 1:
        second = items[1]
        msp.add_linear_dim(base=(second["nose_x_m"] * MM + 2 * size, 0),
                           p1=_p(first["nose_x_m"], first["level_m"]),
                           p2=_p(second["nose_x_m"], second["level_m"]), angle=90,
                           override=style, dxfattribs=attribs).render()
    h0 = sheet.spec.scene.initial.drop_height
    r = sheet.spec.scene.ball.radius
    msp.add_point(_p(0.0, h0), dxfattribs={"layer": "DIMENSIONS"})
    msp.add_circle(_p(0.0, h0 + r), max(r * MM, 1.0), dxfattribs={"layer": "NOTES"})
    msp.add_linear_dim(base=(-2 * size, 0), p1=_p(0.0, h0), p2=_p(0.0, first["level_m"]),
                       angle=90, override=style, dxfattribs=attribs).render()
    msp.add_text(f"feed: launch {mm(sheet.design['launch_speed'])} mm/s at x = 0, "
                 f"{mm(h0)} mm above tread 1", height=0.7 * size,
                 dxfattribs={"layer": "NOTES"}).set_placement((0.0, h0 * MM + 2 * r * MM + size))
