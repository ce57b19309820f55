"""`pdm-design simulate`: JSON outcome, offsets from the command line, plots, bad options."""

import json
import math
from pathlib import Path

from click.testing import CliRunner

from pdm_design.cli import main

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
PAPER = str(PROBLEMS / "paper_manipulators.toml")


def run(*args):
    result = CliRunner().invoke(main, ["simulate", *map(str, args)])
    return result.exit_code, result.stdout, result.stderr


def test_json_outcome_and_stages_for_the_nominal_paper_run():
    code, out, _ = run(PAPER, "--stages", "6", "--format", "json")
    doc = json.loads(out)
    assert code == 0
    assert doc["outcome"] == {"completed": True, "stages_passed": 6, "failure": None}
    assert len(doc["stages"]) == 6
    # Nominal geometry: every handover at beta (paper's design, 0.6 rad).
    handovers = [s["handover_angle"] for s in doc["stages"] if s["handover_angle"] is not None]
    assert handovers and all(math.isclose(a, 0.6, abs_tol=1e-9) for a in handovers)


def test_offset_from_the_command_line_moves_the_handover():
    # Manipulator 2 lowered by 0.2 m: palm 1 must swing on until cos th = cos 0.6 - 0.2 / 2
    # (unless the object slips first, which it does at atan(0.8) = 0.675 rad).
    _, out, _ = run(PAPER, "--offset", "2:0.1,-0.2", "--format", "json")
    doc = json.loads(out)
    assert doc["outcome"]["completed"]
    assert doc["stages"][0]["handover_angle"] > 0.6 + 0.05


def test_large_offset_fails_with_a_named_event_and_exit_1():
    code, out, _ = run(PAPER, "--offset", "2:0,-0.4", "--format", "json")
    doc = json.loads(out)
    assert code == 1
    assert not doc["outcome"]["completed"]
    assert doc["outcome"]["failure"]["event"] in {"lift_off", "blocked", "stall", "slid_off",
                                                  "tip", "fell_clear", "stranded"}


def test_plot_is_written(tmp_path):
    target = tmp_path / "run.png"
    code, _, _ = run(PAPER, "--stages", "3", "--plot", target)
    assert code == 0
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["run.png"]  # no temporary file left


def test_stairs_step_error_option():
    code, out, _ = run(PROBLEMS / "paper_stairs_frictionless.toml", "--step-error", "3:0,0.1",
                       "--format", "json")
    doc = json.loads(out)
    assert code == 0
    # A tread error shifts every later landing back by the error (neutral stability).
    shift = doc["stages"][4]["landing_x"] - doc["stages"][1]["landing_x"]
    assert math.isclose(shift, -0.1, abs_tol=1e-9)


def test_malformed_offset_is_bad_input():
    code, _, err = run(PAPER, "--offset", "two:0.1")
    assert code == 2
    assert "--offset" in err and "K:DX,DY" in err


def test_offset_beyond_the_row_is_bad_input():
    code, _, err = run(PAPER, "--stages", "6", "--offset", "7:0.1,0")
    assert code == 2
    assert "--offset" in err and "from 1 to 6" in err
