"""The DXF of a build sheet, read back with ezdxf: every pivot, hole and step corner where the
design puts it (computed here from alpha, beta, l and the pitch formulas, or from the periodic
bounce), in millimetres to 0.001 mm, on its layer."""

import io
import math
from pathlib import Path

import pytest

ezdxf = pytest.importorskip("ezdxf")

from pdm_design.sheet import sheet_for  # noqa: E402
from pdm_design.sheet.dxf import LAYERS, dxf_bytes, dxf_png  # noqa: E402

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
MANIP = PROBLEMS / "paper_manipulators.toml"
STAIRS = PROBLEMS / "paper_stairs_frictionless.toml"

EXACT = 1e-3  # mm


def read(sheet):
    return ezdxf.read(io.StringIO(dxf_bytes(sheet).decode("utf-8")))


def points(doc, layer, kind="POINT"):
    found = []
    for e in doc.modelspace().query(f'{kind}[layer=="{layer}"]'):
        where = e.dxf.location if kind == "POINT" else e.dxf.center
        found.append((where.x, where.y))
    return sorted(found)


def assert_same(found, expected):
    expected = sorted(expected)
    assert len(found) == len(expected)
    for (x, y), (u, v) in zip(found, expected):
        assert abs(x - u) < EXACT and abs(y - v) < EXACT, ((x, y), (u, v))


@pytest.fixture(scope="module")
def manip():
    sheet = sheet_for(MANIP, count=9, tolerance=False)
    return sheet, read(sheet)


def test_units_are_millimetres_and_every_layer_is_there(manip):
    _, doc = manip
    assert doc.header["$INSUNITS"] == 4 and doc.header["$MEASUREMENT"] == 1
    assert set(LAYERS) <= {layer.dxf.name for layer in doc.layers}


def test_every_pivot_and_hole_is_where_alpha_beta_and_l_put_it(manip):
    sheet, doc = manip
    a, b, l = 0.2, 0.6, 2000.0  # the paper's example, mm
    width, thick = 1600.0, 50.0  # paper_manipulators.toml's palm
    px, py = l * (math.sin(a) + math.sin(b)), l * (math.cos(a) - math.cos(b))
    pivots = [(k * px, -k * py) for k in range(9)]
    assert_same(points(doc, "PIVOTS"), pivots)
    s = width / 2  # the holes: half the palm's width apart
    brackets = [(x + side * s / 2, y - thick) for x, y in pivots for side in (-1, 1)]
    palms = [(x - l * math.sin(a) + side * s / 2, y + l * math.cos(a) - thick)
             for x, y in pivots for side in (-1, 1)]
    assert_same(points(doc, "PIVOTS", "CIRCLE"), brackets)
    assert_same(points(doc, "LINKS", "CIRCLE"), palms)


def test_every_link_is_l_long_and_at_the_back_stop(manip):
    _, doc = manip
    lines = list(doc.modelspace().query('LINE[layer=="LINKS"]'))
    assert len(lines) == 18
    for line in lines:
        dx, dy = line.dxf.end.x - line.dxf.start.x, line.dxf.end.y - line.dxf.start.y
        assert abs(math.hypot(dx, dy) - 2000.0) < EXACT
        assert abs(math.atan2(dx, dy) + 0.2) < 1e-9  # -alpha from vertical


def test_palms_stops_dimensions_and_notes_are_on_their_layers(manip):
    _, doc = manip
    msp = doc.modelspace()
    assert len(msp.query('LWPOLYLINE[layer=="PALMS"]')) == 9
    assert len(msp.query('LINE[layer=="STOPS"]')) == 18
    assert len(msp.query('DIMENSION[layer=="DIMENSIONS"]')) >= 4
    notes = " ".join(e.plain_text() for e in msp.query('MTEXT[layer=="NOTES"]'))
    assert "18 x link: hole spacing 2000.00 mm" in notes and "9 x palm" in notes


def test_every_step_corner_is_where_the_periodic_bounce_puts_it():
    sheet = sheet_for(STAIRS, count=12, tolerance=False)
    doc = read(sheet)
    g, h0, v0, eps = 9.81, 1.0, 2.0, 0.8
    rise = h0 * (1 - eps ** 2)
    tread = v0 * (1 + eps) * math.sqrt(2 * h0 / g)
    first_landing = v0 * math.sqrt(2 * h0 / g)
    back = first_landing - tread / 2  # the spec leaves the landing at the tread's middle
    corners = []
    for k in range(12):
        level = -k * rise
        corners += [((back + k * tread) * 1e3, level * 1e3),
                    ((back + (k + 1) * tread) * 1e3, level * 1e3)]
    assert_same(points(doc, "STEPS"), corners)


def test_the_dxf_renders_to_a_png():
    sheet = sheet_for(PROBLEMS / "paper_stairs_friction.toml", count=4, tolerance=False)
    assert dxf_png(sheet).startswith(b"\x89PNG")


def test_the_same_sheet_gives_the_same_bytes(manip):
    sheet, _ = manip
    assert dxf_bytes(sheet) == dxf_bytes(sheet)  # no dates or GUIDs of the moment
