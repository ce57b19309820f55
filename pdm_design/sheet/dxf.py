"""The device as a DXF drawing for CAD and laser cutting (ezdxf, imported here only), and the
same drawing rendered to PNG (ezdxf's drawing add-on on matplotlib) for a look.

Millimetres ($INSUNITS 4), the frame of the build sheet (x along the row, y up), one layer per
kind of thing: the scene's own (Scene.dxf_layers, drawn by Scene.draw_dxf:
scenes/<kind>/dxf.py), DIMENSIONS (dimensions, the feed, the tolerance boxes) and NOTES (numbers,
angles in degrees, the parts list and the tolerances). Coordinates are written at full double
precision. Circles at holes mark their centres (HOLE_MARK mm across): bore each to suit its
bearing.
"""

from __future__ import annotations

import io
import re

from ..plugin import of
from .parts import MM, parts_list

LAYERS = {"DIMENSIONS": 94, "NOTES": 7}  # AutoCAD colour indices (7: black on white, white on
# black); a scene's own layers come first (Scene.dxf_layers)
HOLE_MARK = 10.0   # mm, diameter of the circle drawn at a hole centre


def dxf_document(sheet):
    """An ezdxf document of the sheet's device (every stage's item)."""
    import ezdxf
    from ezdxf import units

    doc = ezdxf.new("R2010", setup=True)
    doc.units = units.MM
    doc.header["$MEASUREMENT"] = 1
    scene = of(sheet.spec)
    for name, color in {**scene.dxf_layers, **LAYERS}.items():
        doc.layers.add(name, color=color)
    msp = doc.modelspace()
    size = scene.draw_dxf(msp, sheet)
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


def dimension_style(size: float) -> dict:
    """Dimension overrides: the measured length in mm as drawn (dimlfac 1: ezdxf's own style
    scales by 100), to 0.001 mm."""
    return {"dimtxt": size, "dimasz": size, "dimdec": 3, "dimexe": size / 2,
            "dimexo": size / 2, "dimlfac": 1.0, "dimgap": size / 4}


def point_mm(x: float, y: float) -> tuple[float, float]:
    """A point in m as drawn, mm."""
    return x * MM, y * MM


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
