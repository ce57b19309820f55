"""The compass gait in the build sheet's DXF (sheet/dxf.py): GROUND (the ramp's or the stairs'
profile and a POINT at every step's stance foot), WALKER (the legs, the hip and the legs' centres
of mass at the post-strike state on step 1's foot), and on DIMENSIONS the step and the leg."""

from __future__ import annotations

from ...sheet.dxf import dimension_style
from ...sheet.parts import MM, deg, mm
from .drawing import ground_outline
from .sheet import pose, walker_of


def draw_dxf(msp, sheet) -> float:
    """Every step's foot and the walker; returns the notes' text height: 1/20 of the leg."""
    walker, design = walker_of(sheet.spec), sheet.spec.design_at()
    l = walker.leg_length * MM
    size = l / 20
    body = pose(sheet.periodic["fixed_point"], walker.leg_length)
    hip = (body.hip[0] * MM, body.hip[1] * MM)
    trailing = (body.trailing[0] * MM, body.trailing[1] * MM)
    adv = (body.advance[0] * MM, body.advance[1] * MM)
    feet = [(i["foot_x_m"] * MM, i["foot_y_m"] * MM) for i in sheet.items]
    left, right = min(0.0, trailing[0]) - 0.3 * l, feet[-1][0] + adv[0] + 0.3 * l
    msp.add_lwpolyline(ground_outline(design, feet[0], adv, left, right, l), close=True,
                       dxfattribs={"layer": "GROUND"})
    for item, foot in zip(sheet.items, feet):
        msp.add_point(foot, dxfattribs={"layer": "GROUND"})
        msp.add_text(str(item["step"]), height=size, dxfattribs={"layer": "NOTES"}
                     ).set_placement((foot[0] + size / 2, foot[1] + size / 2))
    walk = {"layer": "WALKER"}
    msp.add_line((0.0, 0.0), hip, dxfattribs=walk)
    msp.add_line(trailing, hip, dxfattribs=walk)
    msp.add_circle(hip, size / 2, dxfattribs=walk)
    b = walker.leg_com * MM
    for end in ((0.0, 0.0), trailing):
        msp.add_circle((hip[0] + (end[0] - hip[0]) * b / l, hip[1] + (end[1] - hip[1]) * b / l),
                       size / 4, dxfattribs=walk)
    style = dimension_style(size)
    attribs = {"layer": "DIMENSIONS"}
    msp.add_aligned_dim(p1=(0.0, 0.0), p2=hip, distance=-2 * size, override=style,
                        dxfattribs=attribs).render()
    if len(feet) > 1:
        msp.add_aligned_dim(p1=feet[0], p2=feet[1], distance=-3 * size, override=style,
                            dxfattribs=attribs).render()
    ground = (f"ramp slope {deg(float(design.slope))} deg" if design.slope is not None else
              f"stairs rise {mm(float(design.rise))} mm, tread {mm(float(design.tread))} mm")
    masses = ("the simplest walker" if walker.model == "simplest" else
              f"hip {walker.hip_mass * 1e3:.1f} g; legs {walker.leg_mass * 1e3:.1f} g, centre "
              f"of mass {mm(walker.leg_com)} mm from the hip")
    msp.add_text(f"walker: legs {mm(walker.leg_length)} mm; {masses}; {ground}",
                 height=0.7 * size,
                 dxfattribs={"layer": "NOTES"}).set_placement((left, hip[1] + 3 * size))
    return size
