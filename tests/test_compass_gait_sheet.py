"""The compass gait's sheets, drawings and reports: the optimize JSON's periodic gait (against
gait.fixed_point and one step of the event simulator from it), the build sheet's numbers against
the spec in mm, g and degrees, the drawing's labels inside the figure, the DXF's dimensions, and
the animation's feet (each stance foot one step length down the ramp from the last: the feet at
a heel strike are 2 l sin((q1 - q2) / 2) apart along the direction (cos s, -sin s), as the guard
q1 + q2 = 2 s gives)."""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from pdm_design.accuracy import accuracy
from pdm_design.api import design
from pdm_design.report.animation import animation, animation_html
from pdm_design.report.document import optimize_document
from pdm_design.scenes.compass_gait import gait
from pdm_design.scenes.compass_gait.ground import ground_of, params_for
from pdm_design.scenes.compass_gait.scene import CompassGaitInitial
from pdm_design.scenes.compass_gait.simulate import one_step, simulate_compass_gait
from pdm_design.sheet import make_sheet
from pdm_design.sheet.drawing import draw
from pdm_design.sheet.dxf import dxf_document
from pdm_design.sheet.labels import overlapping_texts
from pdm_design.sheet.parts import parts_list
from pdm_design.spec import load_spec
from pdm_design.units import workshop

RAMP = Path(__file__).resolve().parents[1] / "problems" / "compass_gait_ramp.toml"
SLOPE = 0.0523599  # the spec's slope (3 degrees)
STATE = ("stance", "swing", "stance_rate", "swing_rate")


@pytest.fixture(scope="module")
def spec():
    return load_spec(RAMP)


@pytest.fixture(scope="module")
def document(spec):
    outcome = design(spec, verify=False)
    return json.loads(json.dumps(optimize_document(outcome)))  # as the JSON file carries it


@pytest.fixture(scope="module")
def expected(spec):
    return gait.fixed_point(spec.scene, spec.design_at())


@pytest.fixture(scope="module")
def sheet(spec):
    return make_sheet(spec, "evaluated", None, "given for this test", 5)


def test_the_json_carries_the_periodic_gait(document, expected):
    periodic = document["periodic"]
    assert list(periodic) == ["fixed_point", "step_length", "step_period", "multipliers",
                              "spectral_radius"]
    assert list(periodic["fixed_point"]) == list(STATE)
    for name in STATE:
        assert periodic["fixed_point"][name] == pytest.approx(expected["fixed_point"][name],
                                                              abs=1e-9)
    for name in ("step_length", "step_period", "spectral_radius"):
        assert periodic[name] == pytest.approx(expected[name], rel=1e-9)
    assert len(periodic["multipliers"]) == 3 and all(len(m) == 2
                                                     for m in periodic["multipliers"])
    moduli = [math.hypot(re, im) for re, im in periodic["multipliers"]]
    assert max(moduli) == pytest.approx(periodic["spectral_radius"], rel=1e-12)
    assert periodic["spectral_radius"] == pytest.approx(0.58, abs=0.005)  # the spec's note


def test_the_json_fixed_point_returns_under_the_event_simulator(spec, document):
    """One step of the simulator (DOP853, another integrator than the step map's) from the
    JSON's fixed point comes back to it after its step period, its feet step_length apart."""
    periodic = document["periodic"]
    x0 = [periodic["fixed_point"][n] for n in STATE]
    params = params_for(spec.scene, spec.design_at())
    out = one_step(params, ground_of(spec.design_at(), params), x0, math.inf,
                   accuracy("precise"))
    assert out.kind == "step"
    assert np.allclose(out.after, x0, atol=1e-6)
    assert out.time == pytest.approx(periodic["step_period"], abs=1e-6)
    q1, q2 = out.end[0], out.end[1]
    apart = math.hypot(math.sin(q1) - math.sin(q2), math.cos(q1) - math.cos(q2))
    assert apart * 1.0 == pytest.approx(periodic["step_length"], abs=1e-6)  # l = 1 m


def test_the_json_has_null_periodic_keys_without_a_gait(spec):
    steep = dataclasses.replace(spec, design={**spec.design, "slope": 0.6})
    periodic = optimize_document(design(steep, verify=False))["periodic"]
    assert periodic == dict.fromkeys(("fixed_point", "step_length", "step_period",
                                      "multipliers", "spectral_radius"))


def test_the_sheet_gives_the_spec_in_workshop_units(sheet):
    rows = {name: workshop(value, unit) for name, value, unit, _ in sheet.summary
            if isinstance(value, float)}
    assert rows["hip mass"] == pytest.approx((10_000.0, "g"))
    assert rows["leg mass (each leg)"] == pytest.approx((5_000.0, "g"))
    assert rows["leg length (each leg)"] == pytest.approx((1_000.0, "mm"))
    assert rows["leg centre of mass from the hip"] == pytest.approx((500.0, "mm"))
    assert rows["ramp slope"][0] == pytest.approx(3.0, abs=1e-5)
    parts, _ = parts_list(sheet)
    words = {p.name: (p.quantity, p.dimensions) for p in parts}
    assert words["hip"] == (1, "mass 10000.0 g, at the legs' common pivot")
    assert words["leg"] == (2, "length 1000.00 mm, mass 5000.0 g, centre of mass 500.00 mm "
                               "from the hip")
    assert words["ramp"][1].startswith("slope 3.00 deg")


def test_the_sheet_places_each_foot_one_step_down_the_ramp(sheet, expected):
    length = expected["step_length"]
    assert f"the periodic step {1e3 * length:.2f} mm along it" in dict(
        (p.name, p.dimensions) for p in parts_list(sheet)[0])["ramp"]
    for k, item in enumerate(sheet.items):
        assert item["foot_x_m"] == pytest.approx(k * length * math.cos(SLOPE), abs=1e-9)
        assert item["foot_y_m"] == pytest.approx(-k * length * math.sin(SLOPE), abs=1e-9)
        assert item["from_foot_1_m"] == pytest.approx(k * length, abs=1e-12)


def test_the_leg_inertia_is_listed_in_g_mm2(spec):
    walker = dataclasses.replace(spec.scene.walker, leg_inertia=0.2)
    heavy = dataclasses.replace(spec, scene=dataclasses.replace(spec.scene, walker=walker))
    parts, _ = parts_list(make_sheet(heavy, "evaluated", None, "given for this test", 3))
    leg = {p.name: p.dimensions for p in parts}["leg"]
    assert leg.endswith("inertia 2e+08 g mm^2 about its centre of mass")  # 0.2 kg m^2


def test_the_drawing_is_dimensioned_and_its_labels_are_inside_it(sheet, expected):
    figure = draw(sheet)
    texts = [note.get_text() for note, _ in figure.sheet_labels.made]
    fixed = expected["fixed_point"]
    assert f"step {1e3 * expected['step_length']:.1f} mm" in texts
    assert "leg 1000.0 mm" in texts and "c.o.m. 500.0 mm" in texts
    assert "hip 10000 g" in texts and "slope 3.00 deg" in texts
    assert (f"stance {math.degrees(fixed['stance']):.2f} deg, swing "
            f"{math.degrees(fixed['swing']):.2f} deg from vertical") in texts
    renderer = figure.canvas.get_renderer()
    frame = figure.bbox
    for note, _ in figure.sheet_labels.made:
        if note.get_visible():
            box = note.get_window_extent(renderer)
            assert frame.x0 <= box.x0 and box.x1 <= frame.x1, note.get_text()
            assert frame.y0 <= box.y0 and box.y1 <= frame.y1, note.get_text()
    assert overlapping_texts(figure) == []


def test_the_walker_stands_on_the_ramp_in_the_drawing(sheet, expected):
    """The legs drawn: the stance leg from the origin, the trailing leg's foot one step behind
    it on the ramp, both 1000 mm long."""
    figure = draw(sheet)
    legs = [line.get_xydata() for line in figure.axes[0].lines
            if line.get_color() == "tab:blue" and len(line.get_xydata()) == 2]
    assert len(legs) == 2
    for leg in legs:
        assert np.hypot(*(leg[1] - leg[0])) == pytest.approx(1000.0, abs=1e-9)
    behind = expected["step_length"] * 1e3
    assert legs[1][0] == pytest.approx([-behind * math.cos(SLOPE), behind * math.sin(SLOPE)],
                                       abs=1e-6)


def test_the_dxf_dimensions_the_leg_and_the_step(sheet, expected):
    doc = dxf_document(sheet)
    layers = {layer.dxf.name for layer in doc.layers}
    assert {"GROUND", "WALKER", "DIMENSIONS", "NOTES"} <= layers
    msp = doc.modelspace()
    assert len(msp.query('LINE[layer=="WALKER"]')) == 2
    measured = sorted(d.get_measurement() for d in msp.query("DIMENSION"))
    assert measured == pytest.approx(sorted([1000.0, 1e3 * expected["step_length"]]),
                                     abs=1e-6)


def test_the_animated_feet_advance_one_step_length_a_step(spec, expected):
    """From the fixed point, every heel strike moves the stance foot by step_length down the
    ramp; both legs stay 1000 mm long in every frame."""
    start = CompassGaitInitial(*(expected["fixed_point"][n] for n in STATE))
    on_gait = dataclasses.replace(spec, scene=dataclasses.replace(spec.scene, initial=start))
    steps = 5
    run = simulate_compass_gait(on_gait.scene, on_gait.design_at(), stages=steps,
                                accuracy="precise", record_trajectory=True)
    assert run.outcome.completed
    shown = animation(on_gait, run)
    data = shown.data
    feet = []
    for foot in data["foot"]:
        if not feet or foot != feet[-1]:
            feet.append(foot)
    length = 1e3 * expected["step_length"]
    assert len(feet) == steps  # the last frame is just before the last heel strike
    feet.append(data["swing"][-1])  # where that strike puts the next stance foot
    for before, after in zip(feet, feet[1:]):
        assert after[0] - before[0] == pytest.approx(length * math.cos(SLOPE), abs=0.02)
        assert after[1] - before[1] == pytest.approx(-length * math.sin(SLOPE), abs=0.02)
    hip = np.column_stack([data["x"], data["y"]])
    assert np.hypot(*(hip - np.asarray(data["foot"])).T) == pytest.approx(1000.0, abs=0.1)
    assert np.hypot(*(hip - np.asarray(data["swing"])).T) == pytest.approx(1000.0, abs=0.1)
    assert data["window"] > 0 and data["below"] > 0
    page = animation_html(shown)
    assert "D.foot[i]" in page and "D.swing[i]" in page


def test_simulate_writes_its_plot_and_each_foot_lands_one_step_on(tmp_path):
    """`simulate --plot` writes the figure; each record's foot is its step length (2 l sin((q1 -
    q2) / 2), from the angles) from the one before, on the ramp (the y drop over the x advance
    is tan(slope))."""
    from click.testing import CliRunner

    from pdm_design.cli import main

    target = tmp_path / "run.png"
    result = CliRunner().invoke(main, ["simulate", str(RAMP), "--stages", "4", "--format",
                                       "json", "--plot", str(target)])
    assert result.exit_code == 0, result.output
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    records = json.loads(result.stdout)["stages"]
    feet = [(0.0, 0.0)] + [(r["foot_x"], r["foot_y"]) for r in records]
    for (x0, y0), (x1, y1), record in zip(feet, feet[1:], records):
        assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(record["step_length"], abs=1e-12)
        assert (y0 - y1) / (x1 - x0) == pytest.approx(math.tan(SLOPE), abs=1e-9)


def test_the_slope_box_goes_on_the_ramp_in_degrees(spec):
    boxed = make_sheet(spec, "optimal", {"slope": 0.002}, "given for this test", 5)
    assert ("ramp slope", SLOPE, "rad", 0.002) in boxed.summary
    parts, other = parts_list(boxed)
    ramp = {p.name: p for p in parts}["ramp"]
    assert other == () and [t.quantity for t in ramp.tolerances] == ["slope (box)"]
    assert ramp.tolerances[0].shown() == "+-0.1146 deg"  # 0.002 rad = 0.114592 deg


def test_the_simplest_walkers_sheet_lists_no_masses():
    simplest = load_spec(RAMP.parent / "simplest_walker.toml")
    sheet = make_sheet(simplest, "evaluated", None, "given for this test", 3)
    names = [row[0] for row in sheet.summary]
    assert "hip mass" not in names and "leg mass (each leg)" not in names
    texts = [note.get_text() for note, _ in draw(sheet).sheet_labels.made]
    assert "hip" in texts and not any(t.startswith("hip ") for t in texts)
