"""The build sheet's drawing: the whole device in millimetres and degrees, every tolerance on its
part, the feed dimensioned, the link-length dimension along the link, and no two labels that
overlap (their extents measured by matplotlib's renderer)."""

import dataclasses
import math
from pathlib import Path

import pytest

from pdm_design.sheet import make_sheet
from pdm_design.sheet.drawing import draw
from pdm_design.sheet.labels import figure_texts, labels_on_lines, overlapping_texts
from pdm_design.sheet.parts import ToleranceEntry
from pdm_design.spec import load_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
MANIP = PROBLEMS / "paper_manipulators.toml"
STAIRS = PROBLEMS / "paper_stairs_frictionless.toml"
EXTRA = (ToleranceEntry("link length", "every link", 0.0005, "m", "margin landing"),
         ToleranceEntry("back stop angle", "back stop of every manipulator", 0.004, "rad",
                        "margin over_the_top"),
         ToleranceEntry("palm mass", "every palm", 0.002, "kg", "margin slip_carry"),
         ToleranceEntry("friction", "the material lot", 0.05, "", "margin slip_impact"))


def sheet_of(path, count, tol, extra=()):
    spec = load_spec(path)
    sheet = make_sheet(spec, "evaluated", tol, "given for this test", count)
    return dataclasses.replace(sheet, tolerances=extra)


def texts(figure):
    return [t.get_text() for t in figure_texts(figure)]


@pytest.mark.parametrize("path, count, tol", [
    (MANIP, 6, {"dx": 0.083, "dy": 0.083}),
    (MANIP, 30, {"dx": 0.01, "dy": 0.02}),
    (MANIP, 3, None),
    (STAIRS, 20, {"rise": 0.004, "tread": 0.005}),
    (STAIRS, 60, None),
    (STAIRS, 2, {"rise": 0.004, "tread": 0.005}),
])
def test_no_two_labels_overlap(path, count, tol):
    figure = draw(sheet_of(path, count, tol, EXTRA))
    assert overlapping_texts(figure) == []
    plain = draw(sheet_of(path, count, tol))  # labels of the spec's own parts: off the lines
    assert overlapping_texts(plain) == [] and labels_on_lines(plain, plain.sheet_labels) == []
    pages = [draw(sheet_of(path, count, tol), first, min(first + 5, count), notes=False)
             for first in range(1, count + 1, 6)][:3]
    for page in pages:
        assert overlapping_texts(page) == []
        assert labels_on_lines(page, page.sheet_labels) == []


def test_every_manipulator_is_drawn_in_millimetres_and_degrees():
    from matplotlib.patches import Rectangle

    sheet = sheet_of(MANIP, 30, {"dx": 0.01, "dy": 0.02})
    figure = draw(sheet)
    ax = figure.axes[0]
    palms = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_fill()]
    assert len(palms) == 30
    assert all(abs(p.get_width() - 1600.0) < 1e-9 for p in palms)  # mm
    assert "pdf, pages 2 to 6 (6 a page)" in " ".join(texts(figure)).replace("\n", " ")
    page = draw(sheet, 25, 30, notes=False)  # the PDF's last page of manipulators
    assert len([p for p in page.axes[0].patches if isinstance(p, Rectangle) and p.get_fill()]) == 6
    # 24 pitches on: l (sin a + sin b), -l (cos a - cos b) each; past verification.stages = 6,
    # so no tolerance on it
    assert "pivot 25 (36639.0, -7427.1) mm" in texts(page)
    words = " ".join(texts(draw(sheet_of(MANIP, 6, None))))
    assert "link l = 2000.0 mm" in words and "back stop -11.46 deg" in words
    assert "handover beta 34.38 deg" in words and "pitch x 1526.6 mm" in words
    assert " rad" not in words and ax.get_xlabel() == "x (mm)"


def test_every_tolerance_is_shown_on_its_part():
    figure = draw(sheet_of(MANIP, 6, {"dx": 0.083, "dy": 0.05}, EXTRA))
    words = "\n".join(texts(figure))
    assert "link l = 2000.0 mm, link length +-0.5 mm" in words
    assert "back stop -11.46 deg, back stop angle +-0.2292 deg" in words
    assert "palm mass +-2 g" in words
    assert "pivot x (box) +-83 mm; pivot y (box) +-50 mm" in words
    assert "friction +-0.05: the material lot" in words  # no part of its own: in the list


def test_the_feed_is_dimensioned_from_pivot_one():
    words = texts(draw(sheet_of(MANIP, 6, None)))
    assert "1250.0 mm" in words and "3050.0 mm" in words  # start (-1.25, 3.05) m
    assert any("velocity (3000.0, 0.0) mm/s" in w for w in words)
    stairs = texts(draw(sheet_of(STAIRS, 5, None)))
    assert "1000.0 mm above tread 1" in stairs  # h0 = 1 m
    assert any("launch 2000.0 mm/s" in w for w in stairs)


def test_the_link_length_dimension_runs_along_the_link():
    figure = draw(sheet_of(MANIP, 6, None))
    label = next(t for t in figure_texts(figure) if t.get_text().startswith("link l ="))
    alpha = 0.2
    # the link leans back by alpha from vertical: its direction is 90 + alpha degrees
    along = (90 + math.degrees(alpha)) % 180
    assert abs(label.get_rotation() % 180 - along) < 1e-6
    # the label's point is on a line parallel to the link (its offset is normal to it)
    hole = (-400.0, -50.0)  # the rear bracket hole: pivot (0, 0) - (s/2, T)
    top = (hole[0] - 2000 * math.sin(alpha), hole[1] + 2000 * math.cos(alpha))
    mid = ((hole[0] + top[0]) / 2, (hole[1] + top[1]) / 2)
    dx, dy = label.xy[0] - mid[0], label.xy[1] - mid[1]
    assert abs(dx * -math.sin(alpha) + dy * math.cos(alpha)) < 1e-6  # no part along the link
