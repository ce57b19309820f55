"""`pdm-design simulate`: JSON outcome, offsets from the command line, plots, bad options."""

import json
import math
from pathlib import Path

import pytest
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
    # manipulator 2 raised 0.4 m: its palm stands in the object's way before palm 1 is reached
    code, out, _ = run(PAPER, "--offset", "2:0,0.4", "--format", "json")
    doc = json.loads(out)
    assert code == 1
    assert not doc["outcome"]["completed"]
    assert doc["outcome"]["failure"]["event"] in {"blocked", "stall", "slid_off", "tip",
                                                  "skipped_palm", "fell_clear", "missed",
                                                  "stranded"}


def test_a_lift_off_is_an_event_the_run_goes_on_from():
    # eq. 43: the object lifts off palm 1, flies over the low palm 2 onto palm 3: palm 2 is
    # skipped, a failure by name (a spec may allow it: [verification] allow_skips)
    code, out, _ = run(PAPER, "--offset", "2:0,-0.4", "--format", "json")
    doc = json.loads(out)
    assert code == 1 and not doc["outcome"]["completed"]
    assert doc["outcome"]["failure"]["event"] == "skipped_palm"
    assert doc["outcome"]["stages_passed"] == 1
    lift = [e for e in doc["events"] if e["kind"] == "lift_off"]
    assert len(lift) == 1 and lift[0]["stage"] == 1 and not lift[0]["failure"]


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


STAIRS = PROBLEMS / "paper_stairs_frictionless.toml"


@pytest.mark.parametrize("spec, option, value", [(PAPER, "--offset", "2:1e7,0"),
                                                 (PAPER, "--offset", "2:0,-1.5e6"),
                                                 (STAIRS, "--step-error", "3:2e6,0")])
def test_value_beyond_a_thousand_kilometres_is_bad_input(spec, option, value):
    code, _, err = run(spec, option, value)
    assert code == 2
    assert err.startswith(f"error: command line: {option}: expected ")
    assert "1e+06 m" in err and "internal error" not in err


@pytest.mark.parametrize("spec, option, takes, other", [
    (PAPER, "--step-error", "stairs", "manipulators"),
    (STAIRS, "--offset", "manipulators", "stairs")])
def test_option_for_the_other_scene_kind_is_refused(spec, option, takes, other):
    code, _, err = run(spec, option, "2:0.1,0")
    assert code == 2
    assert err.startswith(f"error: command line: {option}: expected a {takes} spec ")
    assert err.endswith(f"found a {other} spec\n")


@pytest.mark.parametrize("spec, option", [(PAPER, "--offset"), (STAIRS, "--step-error")])
def test_same_k_twice_is_refused(spec, option):
    code, _, err = run(spec, option, "2:0.1,0", option, "2:0,0.1")
    assert code == 2
    assert err == (f"error: command line: {option}: expected each K listed once, "
                   "found K = 2 again in '2:0,0.1'\n")


@pytest.mark.parametrize("name", ["out.txt", "noext", ""])
def test_plot_file_matplotlib_cannot_write_is_refused_before_any_work(tmp_path, name):
    # The spec does not exist: the --plot error proves the option was checked first.
    target = str(tmp_path / name) if name else ""
    code, _, err = run(tmp_path / "missing.toml", "--plot", target)
    assert code == 2
    assert err.startswith("error: command line: --plot: expected a file name ending in ")
    assert all(f in err for f in ("png", "svg", "pdf")) and err.endswith(f"found {target!r}\n")
    assert list(tmp_path.iterdir()) == []


def test_simulator_refusal_names_the_spec_and_exits_1(tmp_path):
    # Heavy backspin (50 rad/s, r = 0.5 m) keeps the ball slipping through the first impact, so
    # friction takes its full mu (1 + eps) sqrt(2 g h0) = 3.986 m/s (mu = 0.5, eps = 0.8,
    # h0 = 1 m) off V0 = 0.1 m/s: vx1 < 0, the ball goes back, and no tread follows.
    text = (PROBLEMS / "paper_stairs_friction.toml").read_text()
    text = text.replace("launch_speed = 3.0 ", "launch_speed = 0.1 ")
    text = text.replace("spin = 0.5 ", "spin = 50.0 ")
    spec = tmp_path / "backspin.toml"
    spec.write_text(text)
    code, out, err = run(spec)
    assert code == 1
    prefix = f"error: {spec}: the simulator refuses this design: the ball moves at "
    assert err.startswith(prefix) and "it does not go down them" in err
    expected = 0.1 - 0.5 * 1.8 * math.sqrt(2 * 9.81 * 1.0)
    assert math.isclose(float(err[len(prefix):].split()[0]), expected, rel_tol=1e-5)


def test_stages_beyond_the_manipulator_limit_is_bad_input():
    code, _, err = run(PAPER, "--stages", "100001")
    assert code == 2
    assert err.startswith("error: command line: --stages: expected at most 100000 manipulators")
    assert err.endswith("found 100001\n")


def _paper_with_offset(tmp_path, manipulator=5, dx=0.3):
    text = Path(PAPER).read_text().replace(
        "[verification]", f"[verification]\noffsets = [{{manipulator = {manipulator}, dx = {dx}}}]")
    path = tmp_path / "offset.toml"
    path.write_text(text)
    return path


def test_command_line_offsets_join_the_spec_s_own(tmp_path):
    """The spec moves pivot 5 by 0.3 m; --offset moves pivot 2 by 1 cm. With the heights
    untouched every carry ends at beta, so a landing is the previous one's offset less the
    difference of the two pivots' shifts: palm 2's 1 cm short, palm 5's 0.3 m short."""
    from pdm_design.scenes.manipulators.model import ManipulatorOffset
    from pdm_design.scenes.manipulators.sim import simulate_manipulators
    from pdm_design.spec import load_spec

    spec = _paper_with_offset(tmp_path)
    code, out, _ = run(spec, "--offset", "2:0.01,0", "--format", "json")
    assert code == 0
    got = [s["landing_offset"] for s in json.loads(out)["stages"]]
    loaded = load_spec(spec)
    both = (ManipulatorOffset(manipulator=2, dx=0.01, dy=0.0),
            ManipulatorOffset(manipulator=5, dx=0.3, dy=0.0))
    expected = [s["landing_offset"] for s in simulate_manipulators(
        loaded.scene, loaded.design_at(), stages=loaded.verification.stages,
        offsets=both).stages]
    assert got == pytest.approx(expected, abs=1e-12)
    assert got[1] == pytest.approx(got[0] - 0.01, abs=1e-9)
    assert got[4] == pytest.approx(got[0] - 0.3, abs=1e-9)


def test_a_shorter_row_than_the_spec_s_offsets_is_bad_input(tmp_path):
    code, _, err = run(_paper_with_offset(tmp_path), "--stages", "3")
    assert code == 2 and "--stages" in err and "verification.offsets" in err


def test_pgf_is_refused_before_any_work_without_latex(tmp_path, monkeypatch):
    import shutil

    monkeypatch.setattr(shutil, "which", lambda name: None)
    code, _, err = run(PAPER, "--plot", tmp_path / "figure.pgf")
    assert code == 2 and "--plot" in err and not (tmp_path / "figure.pgf").exists()


def test_a_spec_with_no_feasible_design_runs_its_least_violation_design_and_exits_1():
    spec = PROBLEMS / "infeasible_manipulators.toml"
    code, out, err = run(spec)
    assert code == 1
    assert err == (f"warning: {spec}: the optimizer found no design that meets every requirement "
                   "(status infeasible); simulating its least-violation design\n")
    assert out.startswith("infeasible_manipulators (manipulators): ")  # the run is still shown
    # a feasible free design is run quietly
    code, _, err = run(PROBLEMS / "manipulators_robust.toml")
    assert code == 0 and err == ""
