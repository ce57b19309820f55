"""The rimless wheel's build sheet, drawing, DXF, run plot and animation (scenes/rimless_wheel/
sheet.py, drawing.py, dxf.py, plot.py, animation.py), checked against closed forms: footholds a
chord 2 l sin(pi / n) apart down a ramp of slope beta, foothold k at k chord (cos beta,
-sin beta); spokes 360 / n degrees apart; on stairs of rise r and spoke chord c, a foothold
advance a = sqrt(c^2 - r^2) per step (docs/rimless_wheel.md, section 7), the tread a when left
out, tread k's back at k tread - s0 and its level -k r; and against the simulator's recorded
footholds (its own integration of the stance and impacts)."""

import dataclasses
import math
from pathlib import Path

import pytest

from pdm_design.plugin import scene_kind
from pdm_design.report.animation import animation
from pdm_design.sheet import make_sheet
from pdm_design.sheet.drawing import draw, drawing_files
from pdm_design.sheet.dxf import dxf_document
from pdm_design.sheet.labels import figure_texts, labels_on_lines, overlapping_texts
from pdm_design.sheet.parts import parts_list
from pdm_design.spec import load_spec
from pdm_design.verify import simulate_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
RAMP = PROBLEMS / "rimless_wheel_ramp.toml"  # 10 spokes of 0.5 m, slope 0.08 rad
STAIRS = PROBLEMS / "rimless_wheel_stairs.toml"  # 8 spokes of 1 m
N, LEG, SLOPE = 10, 0.5, 0.08
CHORD = 2 * LEG * math.sin(math.pi / N)  # 309.017 mm
S_N, S_LEG, RISE, S0 = 8, 1.0, 0.1, 0.4
S_CHORD = 2 * S_LEG * math.sin(math.pi / S_N)
ADVANCE = math.sqrt(S_CHORD**2 - RISE**2)


def ramp_spec():
    return load_spec(RAMP)


def stairs_spec(tread=None):
    spec = load_spec(STAIRS)
    design = {**spec.design, "rise": RISE, "landing_offset": S0}
    if tread is not None:
        design["tread"] = tread
    return dataclasses.replace(spec, design=design, objective={"max_min_margin": 1.0})


def sheet_of(spec, count=None, tol=None):
    return make_sheet(spec, "evaluated", tol, "given for this test",
                      count or spec.verification.stages)


# ------------------------------------------------------------------------- the sheet

def test_ramp_footholds_are_a_spoke_chord_apart_down_the_slope():
    sheet = sheet_of(ramp_spec(), 12, {"slope": 0.01})
    assert len(sheet.items) == 12
    for item in sheet.items:
        k = item["step"]
        assert item["spacing_m"] == pytest.approx(CHORD, rel=1e-14)
        assert item["along_ramp_m"] == pytest.approx(k * CHORD, rel=1e-14)
        assert item["foot_x_m"] == pytest.approx(k * CHORD * math.cos(SLOPE), rel=1e-14)
        assert item["foot_y_m"] == pytest.approx(-k * CHORD * math.sin(SLOPE), rel=1e-14)
        assert item["slope_rad"] == SLOPE and item["slope_tolerance_rad"] == 0.01
    rows = {name: (value, unit, tol) for name, value, unit, tol in sheet.summary}
    assert rows["slope"] == (SLOPE, "rad", 0.01)
    assert rows["angle between spokes"][0] == pytest.approx(2 * math.pi / N, rel=1e-15)
    assert rows["foothold spacing along the ramp (2 l sin(pi/n))"][0] == pytest.approx(CHORD)


def test_ramp_tolerance_covers_only_the_verified_steps():
    spec = ramp_spec()  # verification.stages = 50
    sheet = sheet_of(spec, 52, {"slope": 0.01})
    assert [i["slope_tolerance_rad"] for i in sheet.items[48:]] == [0.01, 0.01, None, None]


def test_parts_list_gives_hub_spokes_tips_and_ramp_in_mm_g_and_degrees():
    sheet = sheet_of(ramp_spec(), 6)
    parts = {p.name: p for p in parts_list(sheet)[0]}
    assert parts["hub"].quantity == 1
    assert "mass 2000 g" in parts["hub"].dimensions  # 2.0 kg
    assert "radius of gyration about its centre 100.00 mm" in parts["hub"].dimensions
    assert parts["spoke"].quantity == N
    assert "length 500.00 mm" in parts["spoke"].dimensions
    assert "mass 50 g" in parts["spoke"].dimensions  # 0.05 kg
    assert f"{360 / N:g} deg apart" in parts["spoke"].dimensions
    assert parts["spoke tip"].quantity == N and "at least 0.8" in parts["spoke tip"].dimensions
    assert f"slope {math.degrees(SLOPE):.2f} deg" in parts["ramp"].dimensions
    assert f"footholds {CHORD * 1e3:.2f} mm apart" in parts["ramp"].dimensions


def test_a_slope_box_is_listed_on_the_ramp():
    sheet = sheet_of(ramp_spec(), 6, {"slope": 0.01})
    parts, other = parts_list(sheet)
    ramp = next(p for p in parts if p.name == "ramp")
    assert [e.quantity for e in ramp.tolerances] == ["slope (box)"]
    assert ramp.tolerances[0].shown() == f"+-{math.degrees(0.01):.4g} deg" and other == ()


def test_stairs_rise_and_tread_from_the_spoke_chord():
    sheet = sheet_of(stairs_spec(), 25, {"rise": 0.004, "tread": 0.005})
    for item in sheet.items:
        k = item["step"]
        assert item["rise_m"] == RISE
        assert item["tread_m"] == pytest.approx(ADVANCE, rel=1e-14)  # left out: one pitch
        assert item["level_m"] == pytest.approx(-k * RISE, rel=1e-14)
        assert item["back_x_m"] == pytest.approx(k * ADVANCE - S0, rel=1e-14)
        assert item["nose_x_m"] == pytest.approx((k + 1) * ADVANCE - S0, rel=1e-14)
        assert item["foot_x_m"] == pytest.approx(k * ADVANCE, rel=1e-14)
        assert item["landing_from_back_m"] == pytest.approx(S0, abs=1e-12)
        within = k <= 20  # verification.stages
        assert item["rise_tolerance_m"] == (0.004 if within else None)
        assert item["tread_tolerance_m"] == (0.005 if within else None)
    step = next(p for p in parts_list(sheet)[0] if p.name == "step")
    assert step.quantity == 25
    assert f"rise 100.00 mm, tread {ADVANCE * 1e3:.2f} mm" in step.dimensions
    assert [e.quantity for e in step.tolerances] == ["rise (box)", "tread (box)"]


def test_stairs_footholds_match_the_simulators_landings():
    """A tread 5 mm shorter than the pitch: each foothold lands a further 5 mm from its
    tread's back; the simulator's recorded footholds and landings say the same."""
    spec = stairs_spec(tread=ADVANCE - 0.005)
    sheet = sheet_of(spec, 8)
    run = simulate_spec(spec, spec.design_at(), stages=8)
    assert run.outcome.completed
    for item, record in zip(sheet.items, run.stages, strict=True):
        k = item["step"]
        assert item["landing_from_back_m"] == pytest.approx(S0 + 0.005 * k, abs=1e-12)
        assert record["landing_x"] == pytest.approx(item["landing_from_back_m"], abs=1e-9)
        assert record["foot_x"] == pytest.approx(item["foot_x_m"], abs=1e-9)
        assert record["foot_y"] == pytest.approx(item["level_m"], abs=1e-9)


# ------------------------------------------------------------------------- the DXF

def flat(pairs):
    return [float(v) for pair in pairs for v in pair]


def _entities(doc, kind, layer):
    return [e for e in doc.modelspace().query(kind) if e.dxf.layer == layer]


@pytest.mark.parametrize("spec, n, leg", [(ramp_spec(), N, LEG), (stairs_spec(), S_N, S_LEG)])
def test_dxf_wheel_has_a_line_a_spoke_at_the_pitch(spec, n, leg):
    doc = dxf_document(sheet_of(spec, 5))
    lines = _entities(doc, "LINE", "WHEEL")
    assert len(lines) == n
    hub = lines[0].dxf.start
    angles = []
    for line in lines:
        assert tuple(line.dxf.start) == pytest.approx(tuple(hub), abs=1e-9)
        d = line.dxf.end - line.dxf.start
        assert math.hypot(d.x, d.y) == pytest.approx(leg * 1e3, rel=1e-12)
        angles.append(math.atan2(d.y, d.x))
    steps = sorted((a - angles[0]) % (2 * math.pi) for a in angles)
    assert steps == pytest.approx([2 * math.pi * j / n for j in range(n)], abs=1e-12)
    assert tuple(lines[0].dxf.end)[:2] == pytest.approx((0.0, 0.0), abs=1e-9)  # on foothold 0


def test_dxf_ramp_points_and_spacing_dimension():
    doc = dxf_document(sheet_of(ramp_spec(), 7))
    points = [tuple(p.dxf.location)[:2] for p in _entities(doc, "POINT", "GROUND")]
    assert flat(points) == pytest.approx(flat((k * CHORD * 1e3 * math.cos(SLOPE),
                                               -k * CHORD * 1e3 * math.sin(SLOPE))
                                              for k in range(8)), abs=1e-9)
    dims = _entities(doc, "DIMENSION", "DIMENSIONS")
    assert [d.get_measurement() for d in dims] == pytest.approx([CHORD * 1e3], rel=1e-12)
    assert {layer.dxf.name for layer in doc.layers} >= {"GROUND", "WHEEL", "DIMENSIONS",
                                                         "NOTES"}


def test_dxf_stairs_profile_and_dimensions():
    doc = dxf_document(sheet_of(stairs_spec(), 4))
    profile = _entities(doc, "LWPOLYLINE", "GROUND")
    assert len(profile) == 1
    corners = [tuple(p)[:2] for p in profile[0].get_points("xy")]
    for k in range(1, 5):  # every tread's back and nose on its level
        level = -k * RISE * 1e3
        assert any(abs(x - (k * ADVANCE - S0) * 1e3) < 1e-9 and abs(y - level) < 1e-9
                   for x, y in corners)
        assert any(abs(x - ((k + 1) * ADVANCE - S0) * 1e3) < 1e-9 and abs(y - level) < 1e-9
                   for x, y in corners)
    measured = sorted(d.get_measurement() for d in _entities(doc, "DIMENSION", "DIMENSIONS"))
    assert measured == pytest.approx(sorted([ADVANCE * 1e3, RISE * 1e3]), rel=1e-12)
    points = [tuple(p.dxf.location)[:2] for p in _entities(doc, "POINT", "GROUND")]
    assert flat(points) == pytest.approx(flat((k * ADVANCE * 1e3, -k * RISE * 1e3)
                                              for k in range(5)), abs=1e-9)


# ------------------------------------------------------------------------- the drawing

@pytest.mark.parametrize("spec, count, tol", [
    (ramp_spec(), 6, {"slope": 0.01}), (ramp_spec(), 14, {"slope": 0.01}),
    (ramp_spec(), 50, None), (stairs_spec(), 5, {"rise": 0.004, "tread": 0.005}),
    (stairs_spec(), 14, {"rise": 0.004, "tread": 0.005}), (stairs_spec(), 20, None)])
def test_drawing_labels_are_apart_off_the_lines_and_inside_the_figure(spec, count, tol):
    sheet = sheet_of(spec, count, tol)
    pages = [draw(sheet, first, min(first + 5, count), notes=False)
             for first in range(1, count + 1, 6)][:3]
    for page in pages:  # the PDF's pages, each dimensioned
        assert overlapping_texts(page) == []
        assert labels_on_lines(page, page.sheet_labels) == []
    figure = draw(sheet)
    assert overlapping_texts(figure) == []
    assert labels_on_lines(figure, figure.sheet_labels) == []
    renderer = figure.canvas.get_renderer()
    page = figure.bbox
    for text in figure_texts(figure):
        box = text.get_window_extent(renderer)
        assert (page.x0 - 1 <= box.x0 and box.x1 <= page.x1 + 1 and page.y0 - 1 <= box.y0
                and box.y1 <= page.y1 + 1), text.get_text()


def test_drawing_dimensions_the_ground_in_mm_and_degrees():
    shown = [t.get_text() for t in figure_texts(draw(sheet_of(ramp_spec(), 6,
                                                              {"slope": 0.01})))]
    assert f"{CHORD * 1e3:.2f} mm" in shown
    assert f"slope {math.degrees(SLOPE):.3f} deg +-{math.degrees(0.01):.3g} deg" in shown
    assert any(f"{N} spokes of 500.00 mm, 36 deg apart" in s for s in shown)
    shown = [t.get_text() for t in figure_texts(draw(sheet_of(stairs_spec(), 5,
                                                              {"rise": 0.004, "tread": 0.005})))]
    assert f"tread {ADVANCE * 1e3:.2f} mm +-5 mm" in shown
    assert "rise 100.00 mm +-4 mm" in shown
    assert f"{S0 * 1e3:.2f} mm to foothold 0" in shown


def test_drawing_files_are_written():
    files = drawing_files(sheet_of(ramp_spec(), 8))
    assert files["sheet.png"][:8] == b"\x89PNG\r\n\x1a\n"
    assert files["sheet.pdf"][:5] == b"%PDF-" and b"<svg" in files["sheet.svg"]


# ------------------------------------------------------------------------- plot, animation

def test_plot_run_writes_a_png(tmp_path):
    spec = ramp_spec()
    run = simulate_spec(spec, spec.design_at(), stages=4, record_trajectory=True)
    scene_kind("rimless_wheel").plot_run(spec, spec.design_at(), run, tmp_path / "run.png")
    assert (tmp_path / "run.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("spec, n, leg", [(ramp_spec(), N, LEG), (stairs_spec(), S_N, S_LEG)])
def test_animation_wheel_stands_on_the_recorded_footholds(spec, n, leg):
    """At every frame, the stance spoke drawn (the hub at the frame's x, y, turned by the
    frame's angle) ends on the foothold the simulator recorded for that stance; the footholds
    are the closed form's."""
    run = simulate_spec(spec, spec.design_at(), stages=12, record_trajectory=True)
    data = animation(spec, run).data
    assert data["spokes"] == n and data["leg"] == pytest.approx(leg * 1e3)
    pitch = 2 * math.pi / n
    impacts = [e.time for e in run.events if e.kind == "impact"]
    assert len(impacts) == 12
    for i, t in enumerate(data["t"]):
        m = data["stance"][i]
        assert m == sum(1 for ti in impacts if ti <= t)
        phi = data["turn"][i] - pitch * m
        assert -pitch <= phi <= pitch
        tip = (data["x"][i] - leg * 1e3 * math.sin(phi),
               data["y"][i] - leg * 1e3 * math.cos(phi))
        assert list(tip) == pytest.approx(data["feet"][m], abs=0.1)  # mm
    if spec.scene.ground == "ramp":
        expected = [(k * CHORD * math.cos(SLOPE), -k * CHORD * math.sin(SLOPE))
                    for k in range(13)]
    else:
        expected = [(k * ADVANCE, -k * RISE) for k in range(13)]
    assert flat(data["feet"]) == pytest.approx(flat((x * 1e3, y * 1e3) for x, y in expected),
                                               abs=1e-3)
    turns = data["turn"]
    assert all(b >= a for a, b in zip(turns, turns[1:]))  # it rolls forward, continuously
    assert max(b - a for a, b in zip(turns, turns[1:])) < 0.5 * pitch


def test_scene_parameters_give_the_wheel_as_built():
    wheel = scene_kind("rimless_wheel").scene_parameters(ramp_spec().scene)
    assert wheel == {"wheel": {"mass": 2.0, "gyration": 0.1, "spoke_mass": 0.05}}  # the spec's
    defaults = scene_kind("rimless_wheel").scene_parameters(load_spec(STAIRS).scene)
    assert defaults == {"wheel": {"mass": 1.0, "gyration": 0.0, "spoke_mass": 0.0}}


def test_allocated_tolerances_land_on_their_parts():
    """Tolerances of an optimize answer: the slope on the ramp; leg length, hub mass, rise
    and tread on the spokes, the hub and the steps."""
    from pdm_design.sheet.build import allocated_entries

    def given(*rows):
        return allocated_entries([{"quantity": q, "applies_to": "each", "value": v,
                                   "unit": u, "allocated": False} for q, v, u in rows])

    sheet = dataclasses.replace(sheet_of(ramp_spec(), 4), tolerances=given(("slope", 0.02,
                                                                            "rad")))
    ramp = next(p for p in parts_list(sheet)[0] if p.name == "ramp")
    assert [(e.quantity, e.value) for e in ramp.tolerances] == [("slope", 0.02)]
    sheet = dataclasses.replace(sheet_of(stairs_spec(), 4), tolerances=given(
        ("leg_length", 0.001, "m"), ("mass", 0.01, "kg"), ("rise", 0.002, "m"),
        ("tread", 0.003, "m")))
    parts, other = parts_list(sheet)
    on = {p.name: [e.quantity for e in p.tolerances] for p in parts}
    assert on["spoke"] == ["leg length"] and on["hub"] == ["mass"]
    assert on["step"] == ["rise", "tread"] and other == ()
