"""The device as a DXF drawing for CAD and laser cutting (ezdxf, imported here only), and the
same drawing rendered to PNG (ezdxf's drawing add-on on matplotlib) for a look.

Millimetres ($INSUNITS 4), the frame of the build sheet (x along the row, y up), one layer per
kind of thing: PIVOTS (a POINT at every design pivot and a circle at every bracket hole), LINKS
(each link as a line between its holes, a circle at every palm hole), PALMS (each palm at its
back stop), STOPS (the back- and front-stop directions of every manipulator), STEPS (the
staircase's profile and a POINT at every tread's back and nose), DIMENSIONS (pitch, link length,
rise, tread, the feed, the tolerance boxes), NOTES (numbers, angles in degrees, the parts list
and the tolerances). Coordinates are written at full double precision. Circles at holes mark
their centres (HOLE_MARK mm across): bore each to suit its bearing.
"""

from __future__ import annotations

import io
import math
import re

from .parts import MM, deg, hole_spacing, link_holes, mm, parts_list, pivots

LAYERS = {"PIVOTS": 7, "LINKS": 5, "PALMS": 8, "STOPS": 1, "STEPS": 7, "DIMENSIONS": 94,
          "NOTES": 7}  # AutoCAD colour indices (7: black on white, white on black)
HOLE_MARK = 10.0   # mm, diameter of the circle drawn at a hole centre


def dxf_document(sheet):
    """An ezdxf document of the sheet's device (every manipulator or step)."""
    import ezdxf
    from ezdxf import units

    doc = ezdxf.new("R2010", setup=True)
    doc.units = units.MM
    doc.header["$MEASUREMENT"] = 1
    for name, color in LAYERS.items():
        doc.layers.add(name, color=color)
    msp = doc.modelspace()
    size = _text_height(sheet)
    if sheet.kind == "manipulators":
        _manipulators(msp, sheet, size)
    else:
        _stairs(msp, sheet, size)
    _notes(msp, sheet, size)
    return doc


def dxf_bytes(sheet) -> bytes:
    """The DXF file; the same bytes for the same sheet (fixed dates and GUIDs, as ezdxf writes
    them for its own tests: a drawing that did not change gives no diff)."""
    import ezdxf

    stream = io.StringIO()
    document = dxf_document(sheet)
    fixed = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        document.write(stream)
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = fixed
    # ezdxf's "created by" and "written by" markers carry the time: the fixed date instead
    text = re.sub(r"^(ezdxf )?(\d+\.\d+\.\d+\S* @ )\d{4}-\d\d-\d\dT[\d:.+-]+$",
                  r"\1\g<2>2000-01-01T00:00:00+00:00", stream.getvalue(), flags=re.M)
    return text.encode("utf-8")


def dxf_png(sheet, *, dpi: int = 110) -> bytes:
    """The DXF drawing rendered to PNG by ezdxf's drawing add-on (matplotlib backend)."""
    from ezdxf.addons.drawing import Frontend, RenderContext
    from ezdxf.addons.drawing.config import BackgroundPolicy, ColorPolicy, Configuration
    from ezdxf.addons.drawing.matplotlib import MatplotlibBackend
    from matplotlib.figure import Figure

    from ..report.render import render_figure

    doc = dxf_document(sheet)
    figure = Figure(figsize=(14, 8))
    ax = figure.add_axes((0, 0, 1, 1))
    config = Configuration(background_policy=BackgroundPolicy.WHITE,
                           color_policy=ColorPolicy.COLOR)
    Frontend(RenderContext(doc), MatplotlibBackend(ax), config=config).draw_layout(
        doc.modelspace(), finalize=True)
    ax.set_facecolor("white")
    figure.set_facecolor("white")
    return render_figure(figure, "png", dpi=dpi)


def _text_height(sheet) -> float:
    if sheet.kind == "manipulators":
        return sheet.design["link_length"] * MM / 30
    return max(sheet.items[0]["tread_m"], sheet.items[0]["rise_m"]) * MM / 20


def _dimension_style(size: float) -> dict:
    """Dimension overrides: the measured length in mm as drawn (dimlfac 1: ezdxf's own style
    scales by 100), to 0.001 mm."""
    return {"dimtxt": size, "dimasz": size, "dimdec": 3, "dimexe": size / 2,
            "dimexo": size / 2, "dimlfac": 1.0, "dimgap": size / 4}


def _p(x: float, y: float) -> tuple[float, float]:
    return x * MM, y * MM


# --------------------------------------------------------------------------- manipulators

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
    style = _dimension_style(size)
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


# --------------------------------------------------------------------------- stairs

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
    style = _dimension_style(size)
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


# --------------------------------------------------------------------------- notes

def _notes(msp, sheet, size):
    parts, other = parts_list(sheet)
    lines = [f"{sheet.spec.name or sheet.spec.source}: {sheet.kind}, millimetres and degrees",
             "PARTS"]
    for part in parts:
        tol = "; ".join(f"{e.quantity} {e.shown()}" for e in part.tolerances)
        lines.append(f"{part.quantity} x {part.name}: {part.dimensions}"
                     + (f"; tolerance {tol}" if tol else ""))
    if other:
        lines.append("OTHER TOLERANCES: " + "; ".join(f"{e.quantity} ({e.applies_to}) "
                                                        f"{e.shown()}" for e in other))
    if sheet.failures:
        lines.insert(0, "DOES NOT WORK - DO NOT BUILD: " + sheet.failures[0])
    xs = [e.dxf.location.x for e in msp.query("POINT")]
    ys = [e.dxf.location.y for e in msp.query("POINT")]
    msp.add_mtext("\\P".join(lines), dxfattribs={"layer": "NOTES", "char_height": 0.7 * size}
                  ).set_location((min(xs), min(ys) - 8 * size))
