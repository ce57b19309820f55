"""`pdm-design sheet`: build sheets of the paper's problems, checked against the geometry written
out here by hand and, for the tolerances, against the event simulator."""

import csv
import io
import json
import math
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main
from pdm_design.scenes.common import StepError
from pdm_design.scenes.manipulators.model import ManipulatorOffset
from pdm_design.sheet import sheet_for
from pdm_design.spec import load_spec
from pdm_design.verify import simulate_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
MANIP = PROBLEMS / "paper_manipulators.toml"
STAIRS = PROBLEMS / "paper_stairs_frictionless.toml"


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


def csv_rows(path):
    return list(csv.DictReader(io.StringIO(Path(path).read_text())))


@pytest.fixture(scope="module")
def manip_sheet():
    return sheet_for(MANIP)


def test_pivots_are_multiples_of_the_pitch(manip_sheet):
    a, b, l = 0.2, 0.6, 2.0
    pitch = (l * (math.sin(a) + math.sin(b)), -l * (math.cos(a) - math.cos(b)))
    assert manip_sheet.count == 6  # the spec's verification.stages
    for k, item in enumerate(manip_sheet.items):
        assert item["manipulator"] == k + 1
        assert item["pivot_x_m"] == pytest.approx(k * pitch[0], abs=1e-12)
        assert item["pivot_y_m"] == pytest.approx(k * pitch[1], abs=1e-12)


def test_paper_pitch_on_the_sheet(manip_sheet):
    second = manip_sheet.items[1]
    assert second["pivot_x_m"] == pytest.approx(1.5266, abs=5e-5)   # the paper's x
    assert second["pivot_y_m"] == pytest.approx(-0.3095, abs=5e-5)  # and y, downward


def test_stop_angles_link_and_palm_mass(manip_sheet):
    for item in manip_sheet.items:
        assert item["back_stop_rad"] == -0.2 and item["handover_rad"] == 0.6
        assert item["front_stop_rad"] == pytest.approx(math.pi / 2, abs=1e-7)
        assert item["link_length_m"] == 2.0
        assert item["palm_mass_kg"] == pytest.approx(1.0 / 10.0)  # M = m / (m/M)


def test_handover_point_is_the_next_palm_at_its_back_stop(manip_sheet):
    for item, after in zip(manip_sheet.items, manip_sheet.items[1:]):
        assert item["handover_x_m"] == pytest.approx(after["palm_at_back_stop_x_m"], abs=1e-12)
        assert item["handover_y_m"] == pytest.approx(after["palm_at_back_stop_y_m"], abs=1e-12)


def test_pivot_tolerance_survives_the_simulator(manip_sheet):
    tol = manip_sheet.tolerance
    assert tol["dx"] > 0 and tol["dy"] > 0
    # every pivot moved by 90 % of its tolerance, in an alternating pattern
    offsets = tuple(ManipulatorOffset(manipulator=k, dx=0.9 * tol["dx"] * (-1) ** k,
                                      dy=-0.9 * tol["dy"] * (-1) ** k) for k in range(1, 7))
    spec = manip_sheet.spec
    result = simulate_spec(spec, spec.design_at(), errors=offsets)
    assert result.outcome.completed


def test_pivot_tolerance_is_the_largest_robust_box(manip_sheet):
    # ... and it is not smaller than it may be: the robust box of the NLP's definition
    # (docs/optimizer.md), solved afresh in numpy by bisection (tests/test_optimize.py, no
    # pdm_design code) at the paper's alpha 0.2, beta 0.6, l 2 m, m/M 10 over 6 manipulators.
    # (Every simulated build of a few times the box still completes here: the robust rows bound
    # margins, lift-off, tipping, the landing on the palm, not the simulator's outright failures.)
    from test_optimize import robust_tolerance_grid

    spec = manip_sheet.spec
    assert spec.verification.stages == 6
    grid = robust_tolerance_grid(spec.scene, [0.2], [0.6], link_length=2.0, mass_ratio=10.0,
                                 stages=6, iters=48)
    expected = float(grid[0, 0])
    assert expected > 0.0
    # the rows keep a backoff of 1e-6 of their scale (formulation/common.py)
    assert manip_sheet.tolerance["dx"] == pytest.approx(expected, rel=1e-4)
    assert manip_sheet.tolerance["dy"] == pytest.approx(expected, rel=1e-4)


def test_stairs_steps_have_the_periodic_rise_and_tread():
    sheet = sheet_for(STAIRS)
    rise = (1 - 0.8**2) * 1.0
    tread = 2.0 * (1 + 0.8) * math.sqrt(2 * 9.81 * 1.0) / 9.81
    assert sheet.count == 20
    first_back = sheet.items[0]["back_x_m"]
    for k, step in enumerate(sheet.items):
        assert step["rise_m"] == pytest.approx(rise, rel=1e-12)
        assert step["tread_m"] == pytest.approx(tread, rel=1e-12)
        assert step["level_m"] == pytest.approx(-k * rise, abs=1e-12)
        assert step["back_x_m"] == pytest.approx(first_back + k * tread, rel=1e-12)
    # the first landing is mid-tread: the ball flies V0 sqrt(2 h0 / g) to it
    assert first_back + tread / 2 == pytest.approx(2.0 * math.sqrt(2 / 9.81), rel=1e-12)


def test_step_tolerance_survives_the_simulator():
    sheet = sheet_for(STAIRS)
    tol = sheet.tolerance
    assert tol["rise"] > 0 and tol["tread"] > 0
    errors = tuple(StepError(step=k, rise=0.9 * tol["rise"] * (-1) ** k,
                             tread=0.9 * tol["tread"]) for k in range(1, 21))
    result = simulate_spec(sheet.spec, sheet.spec.design_at(), errors=errors)
    assert result.outcome.completed
    # ... and from the other side: the shortest drift (every riser low, every tread long) at
    # the tolerance completes, and at 1.25 times it the simulator refutes the build (it first
    # fails between 1.05 and 1.1 times: the box is no more than about 10 % short of the largest)
    def shortest(k):
        errors = tuple(StepError(step=n, rise=-k * tol["rise"], tread=k * tol["tread"])
                       for n in range(1, 21))
        return simulate_spec(sheet.spec, sheet.spec.design_at(), errors=errors)

    assert shortest(1.0).outcome.completed
    refuted = shortest(1.25)
    assert not refuted.outcome.completed
    assert refuted.outcome.failure.kind in ("nose_hit", "double_landing", "skipped_step")


def test_a_given_tread_off_the_periodic_flight_takes_that_off_its_tolerance(tmp_path):
    # The paper's stairs with the tread given 2 mm longer than the periodic flight's: every step
    # is the periodic design's with a tread error of 2 mm, so its box is the periodic design's
    # with 2 mm less on the tread (the NLP itself refuses a given tread off the orbit).
    periodic = sheet_for(STAIRS).tolerance
    orbit = 2.0 * (1 + 0.8) * math.sqrt(2 * 9.81 * 1.0) / 9.81
    text = STAIRS.read_text().replace(
        "launch_speed = 2.0 ", f"launch_speed = 2.0\nrise = 0.36\ntread = {orbit + 0.002!r} ")
    spec = tmp_path / "long_tread.toml"
    spec.write_text(text)
    sheet = sheet_for(spec)
    assert sheet.tolerance["rise"] == pytest.approx(periodic["rise"], rel=1e-6)
    assert sheet.tolerance["tread"] == pytest.approx(periodic["tread"] - 0.002, rel=1e-6)
    assert "0.002 m offset from the periodic flight's" in sheet.tolerance_note
    # the shortest drift at the sheet's box: every riser low, every tread long
    errors = tuple(StepError(step=n, rise=-sheet.tolerance["rise"],
                             tread=sheet.tolerance["tread"]) for n in range(1, 21))
    assert simulate_spec(sheet.spec, sheet.spec.design_at(), errors=errors).outcome.completed


def test_sheet_command_writes_markdown_csv_and_drawing(tmp_path):
    code, out, err = run("sheet", MANIP, "--out", tmp_path)
    assert code == 0, err
    rows = csv_rows(tmp_path / "sheet.csv")
    assert [int(r["manipulator"]) for r in rows] == [1, 2, 3, 4, 5, 6]
    assert float(rows[2]["pivot_x_m"]) == pytest.approx(2 * 2 * (math.sin(0.2) + math.sin(0.6)))
    text = (tmp_path / "sheet.md").read_text()
    assert "![drawing](sheet.svg)" in text and "| 6 |" in text
    assert (tmp_path / "sheet.png").read_bytes().startswith(b"\x89PNG")
    assert b"<svg" in (tmp_path / "sheet.svg").read_bytes()


def test_every_step_is_drawn_and_the_pdf_has_a_page_for_each_six(tmp_path):
    import re

    code, _, err = run("sheet", STAIRS, "--out", tmp_path, "--count", "40", "--no-tolerance")
    assert code == 0, err
    assert len(csv_rows(tmp_path / "sheet.csv")) == 40
    assert b"40 steps (millimetres)" in (tmp_path / "sheet.svg").read_bytes()
    pdf = (tmp_path / "sheet.pdf").read_bytes()
    pages = len(re.findall(rb"/Type /Page\b(?!s)", pdf))
    assert pages == 1 + math.ceil(40 / 6) + 1  # the whole, six steps a page, the table


def test_sheet_of_a_saved_design_json_matches_the_spec(tmp_path):
    code, out, _ = run("optimize", MANIP, "--format", "json")
    assert code == 0
    saved = tmp_path / "design.json"
    saved.write_text(out)
    assert run("sheet", saved, "--out", tmp_path / "a", "--no-drawing")[0] == 0
    assert run("sheet", MANIP, "--out", tmp_path / "b", "--no-drawing")[0] == 0
    assert (tmp_path / "a" / "sheet.csv").read_text() == (tmp_path / "b" / "sheet.csv").read_text()


@pytest.mark.parametrize("content", ["not json", json.dumps({"schema": "other"}),
                                     json.dumps({"schema": "pdm-design/optimize/1",
                                                 "spec": "missing.toml", "design": {}})])
def test_bad_design_json_is_bad_input(tmp_path, content):
    path = tmp_path / "design.json"
    path.write_text(content)
    code, _, err = run("sheet", path, "--out", tmp_path / "out")
    assert code == 2 and str(path) in err


def test_sheet_of_a_design_that_does_not_work_exits_1(tmp_path):
    spec = tmp_path / "slip.toml"
    spec.write_text(MANIP.read_text().replace("friction = 0.8", "friction = 0.3"))
    code, _, err = run("sheet", spec, "--out", tmp_path / "out", "--no-tolerance")
    assert code == 1 and "infeasible" in err
    assert (tmp_path / "out" / "sheet.csv").exists()


@pytest.fixture(scope="module")
def saved_stairs_design():
    code, out, _ = run("optimize", PROBLEMS / "stairs_design.toml", "--format", "json",
                       "--no-verify")
    assert code == 0
    return json.loads(out)


@pytest.mark.parametrize("where, value, key", [
    ("design", -1.0, "design.launch_speed"),     # below the spec's bounds (0.5 to 3 m/s)
    ("design", "x", "design.launch_speed"),
    ("design", True, "design.launch_speed"),      # JSON true is not a number
    ("tolerance", -1.0, "tolerance.rise"),
])
def test_an_edited_design_json_is_bad_input_naming_its_key(tmp_path, saved_stairs_design,
                                                           where, value, key):
    doc = json.loads(json.dumps(saved_stairs_design))
    doc[where]["rise" if where == "tolerance" else "launch_speed"] = value
    path = tmp_path / "design.json"
    path.write_text(json.dumps(doc))
    code, _, err = run("sheet", path, "--out", tmp_path / "out", "--no-drawing")
    assert code == 2 and f"{path}: {key}: expected" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.filterwarnings("error")  # matplotlib warned of identical limits on a zero box
def test_a_zero_tolerance_is_listed_as_zero_not_as_none(tmp_path):
    code, out, _ = run("optimize", PROBLEMS / "manipulators_robust.toml", "--format", "json",
                       "--no-verify")
    assert code == 0
    doc = json.loads(out)
    doc["tolerance"] = {"dx": 0.0, "dy": 0.0}  # build every pivot exactly
    path = tmp_path / "design.json"
    path.write_text(json.dumps(doc))
    code, _, err = run("sheet", path, "--out", tmp_path / "out")
    assert code == 0, err
    lines = (tmp_path / "out" / "sheet.md").read_text().splitlines()
    pivots = [line for line in lines if line.startswith("| pivot k ")]
    assert len(pivots) == 2 and all(line.endswith("| mm | 0 |") for line in pivots), pivots


def test_a_saved_design_whose_spec_changed_since_is_refused(tmp_path):
    spec = tmp_path / "row.toml"
    spec.write_text(MANIP.read_text())
    code, out, _ = run("optimize", spec, "--format", "json", "--no-verify")
    saved = tmp_path / "row.json"
    saved.write_text(out)
    spec.write_text("# a comment changes no value\n" + MANIP.read_text())
    assert run("sheet", saved, "--out", tmp_path / "a", "--no-drawing")[0] == 0
    spec.write_text(MANIP.read_text().replace("friction = 0.8", "friction = 0.05"))
    code, _, err = run("sheet", saved, "--out", tmp_path / "b", "--no-drawing")
    assert code == 2 and f"{saved}: spec_sha256: expected the digest of" in err
    assert "the spec changed since this design was saved" in err
    assert not (tmp_path / "b").exists()


# ------------------------------------------------------------------- the simulator's verdict

def bouncing_object_spec(tmp_path):
    """The paper's row with an object that bounces on the palm (restitution 0.9): the closed
    forms, which assume a plastic landing, still call it a success."""
    spec = tmp_path / "bouncing.toml"
    text = MANIP.read_text()
    assert "restitution = 0.0 " in text
    spec.write_text(text.replace("restitution = 0.0 ", "restitution = 0.9 "))
    return spec


@pytest.mark.parametrize("source", ["spec", "saved json", "saved json, not verified"])
def test_sheet_of_a_design_the_simulator_refutes_warns_and_exits_1(tmp_path, source):
    spec = bouncing_object_spec(tmp_path)
    # the simulator's verdict on the design as built, independent of the sheet
    loaded = load_spec(spec)
    outcome = simulate_spec(loaded, loaded.design_at()).outcome
    assert not outcome.completed
    named = f"{outcome.failure.kind} at stage {outcome.failure.stage}"
    target = spec
    if source != "spec":
        flags = ["--no-verify"] if source.endswith("not verified") else []
        code, out, _ = run("optimize", spec, "--format", "json", *flags)
        assert code == (0 if flags else 1)
        target = tmp_path / "design.json"
        target.write_text(out)
    code, _, err = run("sheet", target, "--out", tmp_path / "out", "--no-tolerance")
    assert code == 1 and named in err
    text = (tmp_path / "out" / "sheet.md").read_text()
    warning = text.index("WARNING: this design does not work")
    assert warning < text.index("Spec:") and named in text[warning:text.index("Spec:")]
    assert len(csv_rows(tmp_path / "out" / "sheet.csv")) == 6  # written all the same
    assert b"DO NOT BUILD" in (tmp_path / "out" / "sheet.svg").read_bytes()


def test_sheet_of_a_design_the_simulator_confirms_carries_no_warning(tmp_path):
    loaded = load_spec(MANIP)
    assert simulate_spec(loaded, loaded.design_at()).outcome.completed
    code, _, err = run("sheet", MANIP, "--out", tmp_path, "--no-drawing", "--no-tolerance")
    assert code == 0 and "warning" not in err
    text = (tmp_path / "sheet.md").read_text()
    assert "WARNING" not in text and "Verification (the event simulator): passed" in text


# --------------------------------------------------------------------------- tolerance rows

TOLERANCE_COLUMNS = {"manipulators": ("pivot_x_tolerance_m", "pivot_y_tolerance_m"),
                     "stairs": ("rise_tolerance_m", "tread_tolerance_m")}


@pytest.mark.parametrize("spec, count", [(STAIRS, 60), (MANIP, 10)])
def test_tolerance_is_listed_only_for_the_stages_it_was_solved_for(tmp_path, spec, count):
    with open(spec, "rb") as handle:
        raw = tomllib.load(handle)
    stages, kind = raw["verification"]["stages"], raw["scene"]["kind"]
    assert count > stages
    code, out, err = run("sheet", spec, "--out", tmp_path, "--count", count, "--no-drawing")
    assert code == 0, err
    rows = csv_rows(tmp_path / "sheet.csv")
    assert len(rows) == count
    for k, row in enumerate(rows, start=1):
        for column in TOLERANCE_COLUMNS[kind]:  # the columns stay; the cells beyond are blank
            assert (row[column] != "") == (k <= stages), (k, column)
    text = (tmp_path / "sheet.md").read_text()
    assert f"first {stages} " in text and f"`verification.stages = {count}`" in text


def test_the_tolerance_of_a_short_staircase_does_not_hold_for_a_longer_one():
    """Why the sheet leaves the rows past verification.stages blank (the simulator's word)."""
    sheet = sheet_for(STAIRS, count=40)
    stages = sheet.spec.verification.stages
    tol = sheet.tolerance

    def build(steps):  # every step low by the rise tolerance and long by the tread's
        errors = tuple(StepError(step=k, rise=-tol["rise"], tread=tol["tread"])
                       for k in range(1, steps + 1))
        return simulate_spec(sheet.spec, sheet.spec.design_at(), stages=steps,
                             errors=errors).outcome

    assert build(stages).completed
    assert not build(2 * stages).completed


# --------------------------------------------------------------------------- stale drawings

def test_sheet_without_drawing_removes_an_earlier_drawing_only(tmp_path):
    assert run("sheet", MANIP, "--out", tmp_path, "--no-tolerance")[0] == 0
    assert (tmp_path / "sheet.png").exists() and (tmp_path / "sheet.svg").exists()
    (tmp_path / "notes.txt").write_text("the workshop's")
    (tmp_path / "sheet.dwg").write_text("not the sheet's")
    code, out, err = run("sheet", STAIRS, "--out", tmp_path, "--no-tolerance", "--no-drawing")
    assert code == 0, err
    for name in ("sheet.png", "sheet.svg", "sheet.pdf", "sheet.dxf", "sheet_dxf.png"):
        assert not (tmp_path / name).exists(), name
    assert len(csv_rows(tmp_path / "sheet.csv")) == 20 and "sheet.svg" not in (
        tmp_path / "sheet.md").read_text()
    assert (tmp_path / "notes.txt").read_text() == "the workshop's"
    assert (tmp_path / "sheet.dwg").read_text() == "not the sheet's"


def test_stale_drawing_removal_leaves_folders_and_link_targets(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere.svg"
    (out / "sheet.png").mkdir(parents=True)
    (out / "sheet.png" / "kept.txt").write_text("kept")
    elsewhere.write_text("<svg/>")
    (out / "sheet.svg").symlink_to(elsewhere)
    code, _, err = run("sheet", STAIRS, "--out", out, "--no-tolerance", "--no-drawing")
    assert code == 0, err
    assert (out / "sheet.png" / "kept.txt").read_text() == "kept"
    assert not (out / "sheet.svg").is_symlink() and elsewhere.read_text() == "<svg/>"


def test_a_design_that_does_not_work_gets_no_tolerance_search(tmp_path):
    spec = tmp_path / "slip.toml"
    spec.write_text(MANIP.read_text().replace("friction = 0.8", "friction = 0.3"))
    sheet = sheet_for(spec)
    assert sheet.tolerance is None
    assert sheet.tolerance_note == "tolerance not computed: the design's status is infeasible"


def test_the_specs_tolerances_go_on_their_parts_apart_from_the_box(tmp_path):
    from pdm_design.sheet.parts import parts_list

    spec = tmp_path / "toleranced.toml"
    spec.write_text(MANIP.read_text().replace(
        "[verification]", "[tolerances]\npivot_x = { value = 0.09 }\npivot_y = { value = 0.09 }"
        "\nback_stop = { value = 0.01745, distribution = \"uniform\" }\n"
        "palm_mass = { value = 0.01 }\nfriction = { value = 0.1, applies_to = \"lot\" }\n\n"
        "[verification]"))
    sheet = sheet_for(spec, tolerance=False)
    parts, _ = parts_list(sheet)
    on = {p.name: {e.quantity: e for e in p.tolerances} for p in parts}
    assert on["pivot bracket"]["pivot x (spec)"].shown() == "+-90 mm"
    assert on["pivot bracket"]["pivot y (spec)"].shown() == "+-90 mm"
    assert on["back stop"]["back stop (spec)"].shown() == f"+-{math.degrees(0.01745):.4g} deg"
    assert on["palm"]["palm mass (spec)"].shown() == "+-10 g"
    assert "uniform" in on["back stop"]["back stop (spec)"].limited_by
    assert "normal" in on["palm"]["palm mass (spec)"].limited_by
    code, out, _ = run("sheet", spec, "--out", tmp_path / "s")
    page = (tmp_path / "s" / "sheet.md").read_text()
    assert code == 0 and "pivot x (spec) | every pivot bracket | +-90 mm" in page
    box = next(line for line in page.splitlines() if line.startswith("| pivot x (box)"))
    assert "worst-case box the optimizer computed" in box
