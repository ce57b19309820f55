"""A scene that gives only the core of the interface (analyse, simulate, formulate) still gets a
build sheet, a drawing, a DXF, a plot, a simulate table and an animated report from the defaults
of pdm_design.plugin.Scene: the stairs scene with every sheet and report method taken back to
those defaults, checked against the periodic bounce's closed forms."""

import math
from pathlib import Path

import pytest

from pdm_design import plugin
from pdm_design.plugin import Scene
from pdm_design.scenes.stairs.plugin import Stairs
from pdm_design.spec import load_spec
from pdm_design.verify import simulate_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
STAIRS = PROBLEMS / "paper_stairs_frictionless.toml"
G, H0, V0, EPS = 9.81, 1.0, 2.0, 0.8  # the spec's gravity, drop height, launch speed, eps
RISE = H0 * (1 - EPS ** 2)
TREAD = V0 * (1 + EPS) * math.sqrt(2 * H0 / G)
FIRST_LANDING = V0 * math.sqrt(2 * H0 / G)
DEFAULTS = ("tolerance_axes", "sheet_rows", "sheet_words", "box_shift", "box_tolerances",
            "part_words", "parts", "table_rows", "draw_sheet", "dxf_layers", "draw_dxf",
            "document_keys", "scene_parameters", "stage_columns", "plot_run", "animation")


class BareStairs(Stairs):
    """The stairs' core only: nothing of its own for sheets, drawings and reports."""


for _name in DEFAULTS:
    setattr(BareStairs, _name, Scene.__dict__[_name])


@pytest.fixture
def bare(monkeypatch):
    scene = BareStairs()
    monkeypatch.setattr(plugin, "scene_kind", lambda kind: scene)
    return scene


def impacts(count):
    """Where the ball lands on tread k (its lowest point), mm: the periodic bounce."""
    return [((FIRST_LANDING + k * TREAD) * 1e3, -k * RISE * 1e3) for k in range(count)]


def test_the_sheet_lists_the_design_and_one_row_a_stage(bare):
    from pdm_design.sheet import make_sheet, sheet_csv, sheet_markdown
    from pdm_design.sheet.parts import parts_list

    sheet = make_sheet(load_spec(STAIRS), "evaluated", {"rise": 0.001}, "given", 5)
    assert sheet.items == [{"step": k} for k in range(1, 6)]
    values = {name: value for name, value, _, _ in sheet.summary}
    assert values["steps"] == 5 and values["restitution"] == EPS
    assert values["launch_speed"] == V0
    assert parts_list(sheet)[0] == ()
    assert sheet_csv(sheet) == "step\n1\n2\n3\n4\n5\n"
    text = sheet_markdown(sheet)
    assert "## Every step" in text and "| restitution | 0.8 |" in text
    # the box a scene has no axes for is no tolerance of its own
    assert "rise (box)" not in text


def test_the_drawing_and_the_dxf_show_the_simulated_path(bare):
    import io

    import ezdxf

    from pdm_design.sheet import make_sheet
    from pdm_design.sheet.drawing import draw, drawing_pdf
    from pdm_design.sheet.dxf import dxf_bytes

    sheet = make_sheet(load_spec(STAIRS), "evaluated", None, "none", 6)
    figure = draw(sheet)
    numbered = {note.get_text(): note.xy for note, _ in figure.sheet_labels.made}
    assert sorted(numbered, key=int) == ["1", "2", "3", "4", "5", "6"]
    for k, (ex, ey) in enumerate(impacts(6), 1):  # each number at its stage's impact
        x, y = numbered[str(k)]
        assert abs(x - ex) < 1e-6 and abs(y - ey) < 1e-6
    assert drawing_pdf(sheet, figure).startswith(b"%PDF")
    doc = ezdxf.read(io.StringIO(dxf_bytes(sheet).decode()))
    found = [(p.dxf.location.x, p.dxf.location.y) for p in doc.modelspace().query("POINT")]
    assert len(found) == 6
    for (x, y), (ex, ey) in zip(found, impacts(6)):
        assert abs(x - ex) < 1e-6 and abs(y - ey) < 1e-6
    assert len(doc.modelspace().query("LWPOLYLINE")) == 1


def test_the_run_is_plotted_tabled_and_animated(bare, tmp_path):
    from pdm_design.report.animation import GENERIC_SCRIPT, animation
    from pdm_design.report.plots import plot_simulation
    from pdm_design.report.simulation import simulation_text

    spec = load_spec(STAIRS)
    run = simulate_spec(spec, spec.design_at(), stages=4, record_trajectory=True)
    plot_simulation(spec, spec.design_at(), run, tmp_path / "run.png")
    assert (tmp_path / "run.png").read_bytes().startswith(b"\x89PNG")
    text = simulation_text(spec, run)
    header = text.split("\n")[2].split()
    assert header == list(run.stages[0])  # every key of a stage record, in its order
    shown = animation(spec, run)
    assert shown.script == GENERIC_SCRIPT
    width = (FIRST_LANDING + 3 * TREAD) * 1e3  # from the launch at x = 0 to the 4th impact
    assert abs(shown.data["window"] - (2 * width + 200)) < 1e-6
    assert shown.data["below"] == 0.0
