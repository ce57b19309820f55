"""`pdm-design check`: the CI gate on specs' expectations."""

import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "problems" / "paper_manipulators.toml"


def run(*args):
    result = CliRunner().invoke(main, ["check", *map(str, args)])
    return result.exit_code, result.stdout, result.stderr


def _spec_with_expect(tmp_path, expect: str, name="spec.toml"):
    text = PAPER.read_text().split("[expect]")[0] + "[expect]\n" + expect + "\n"
    path = tmp_path / name
    path.write_text(text)
    return path


def test_met_expectation_passes(tmp_path):
    code, out, _ = run(_spec_with_expect(tmp_path, "feasible = true"))
    assert code == 0
    assert out.startswith("PASS")


def test_margin_expectation_above_achievable_fails_with_reason(tmp_path):
    # The landing margin of the paper design is 1 - (0.5615 + 0.2) / 0.8 = 0.048 (by hand;
    # asserted in test_analysis_margins.py).
    code, out, _ = run(_spec_with_expect(tmp_path, "min_margin = 0.5"))
    assert code == 1
    assert out.startswith("FAIL") and "smallest margin landing" in out


def test_wrong_feasibility_expectation_fails(tmp_path):
    code, out, _ = run(_spec_with_expect(tmp_path, "feasible = false"))
    assert code == 1
    assert "expected infeasible, got evaluated" in out


def test_directory_is_expanded_one_line_per_spec(tmp_path):
    _spec_with_expect(tmp_path, "feasible = true", "a.toml")
    _spec_with_expect(tmp_path, "min_margin = 0.9", "b.toml")
    code, out, _ = run(tmp_path)
    assert code == 1
    assert [line.split()[0] for line in out.splitlines()] == ["PASS", "FAIL"]


def test_bad_spec_is_reported_and_exits_2(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene]\nkind = 'teapot'\n")
    code, out, _ = run(bad)
    assert code == 2
    assert out.startswith("ERROR") and "scene.kind" in out


def test_junit_report_lists_each_spec(tmp_path):
    good = _spec_with_expect(tmp_path, "feasible = true", "good.toml")
    failing = _spec_with_expect(tmp_path, "min_margin = 0.9", "failing.toml")
    report = tmp_path / "junit.xml"
    run(good, failing, "--junit", report)
    suite = ET.parse(report).getroot()
    assert suite.get("tests") == "2" and suite.get("failures") == "1"
    failed = [c.get("name") for c in suite if c.find("failure") is not None]
    assert failed == [str(failing)]


def _docs_examples():
    text = (ROOT / "docs" / "spec.md").read_text(encoding="utf-8")
    return [b for b in re.findall(r"```toml\n(.*?)```", text, re.DOTALL) if "[scene]" in b]


@pytest.mark.parametrize("index", range(2))
def test_complete_examples_in_docs_meet_their_own_expectations(tmp_path, index):
    # A reader copies these whole; their [expect] tables say what they should get.
    example = _docs_examples()[index]
    assert "[expect]" in example
    path = tmp_path / "example.toml"
    path.write_text(example)
    code, out, _ = run(path)
    assert (code, out.split()[0]) == (0, "PASS"), out


def test_internal_error_in_one_spec_is_its_error_line_and_the_run_goes_on(tmp_path,
                                                                          monkeypatch):
    import pdm_design.check

    real, calls = pdm_design.check.design, []

    def design_failing_the_second_time(spec, *args, **kwargs):
        calls.append(spec)
        if len(calls) == 2:
            raise RuntimeError("boom")
        return real(spec, *args, **kwargs)

    monkeypatch.setattr(pdm_design.check, "design", design_failing_the_second_time)
    for name in ("a.toml", "b.toml", "c.toml"):
        _spec_with_expect(tmp_path, "feasible = true", name)
    report = tmp_path / "report.xml"
    code, out, _ = run(tmp_path, "--junit", report)
    assert code == 2
    second = f"ERROR {tmp_path / 'b.toml'}: internal error (RuntimeError): boom"
    assert out.splitlines()[1] == second
    assert [line.split()[0] for line in out.splitlines()] == ["PASS", "ERROR", "PASS"]
    suite = ET.parse(report).getroot()
    assert (suite.get("tests"), suite.get("errors"), suite.get("failures")) == ("3", "1", "0")


def test_invalid_toml_line_names_the_file_once(tmp_path):
    bad = tmp_path / "b.toml"
    bad.write_text("x = =\n")
    code, out, _ = run(bad)
    assert code == 2
    assert out.startswith(f"ERROR {bad}: expected valid TOML, found ")
    assert out.count(str(bad)) == 1


def test_folder_without_specs_is_bad_input(tmp_path):
    (tmp_path / "notes.txt").write_text("not a spec")
    code, out, err = run(tmp_path)
    assert code == 2
    assert out == ""
    assert err == (f"error: {tmp_path}: expected a spec file or a folder with *.toml files, "
                   "found no *.toml files\n")


def test_empty_junit_path_is_bad_input(tmp_path):
    code, out, err = run(_spec_with_expect(tmp_path, "feasible = true"), "--junit", "")
    assert code == 2
    assert out == ""  # refused before any spec is checked
    assert err == "error: command line: --junit: expected a file name, found ''\n"


def test_a_design_the_simulator_refutes_fails_the_gate(tmp_path):
    """The paper's design with a bouncy palm (restitution 0.9): the closed forms, which assume a
    plastic landing, find it feasible; the simulator sees the object tip on its first palm. So
    `feasible = true` alone fails, and passes only with the refutation accepted in words."""
    from pdm_design.scenes.manipulators.sim import simulate_manipulators
    from pdm_design.spec import load_spec

    text = PAPER.read_text().replace("restitution = 0.0 ", "restitution = 0.9 ")
    bouncy = tmp_path / "bouncy.toml"
    bouncy.write_text(text.split("[expect]")[0] + "[expect]\nfeasible = true\n")
    spec = load_spec(bouncy)
    assert spec.scene.palm.restitution == 0.9
    assert not simulate_manipulators(spec.scene, spec.design_at(), stages=6).outcome.completed

    code, out, _ = run(bouncy)
    assert code == 1 and out.startswith("FAIL") and "simulator refutes" in out
    bouncy.write_text(bouncy.read_text() + "verified = false\n")
    code, out, _ = run(bouncy)
    assert code == 0 and out.startswith("PASS")


def test_a_bouncy_palm_s_disagreement_is_put_down_to_the_plastic_landing(tmp_path):
    # Restitution 0.3: the run completes its 6 stages, but the object hops before it rests and
    # the handover speeds leave the closed forms'; the failure names that cause.
    from pdm_design.api import evaluate
    from pdm_design.spec import load_spec

    bouncy = tmp_path / "bouncy.toml"
    bouncy.write_text(PAPER.read_text().replace("restitution = 0.0 ", "restitution = 0.3 "))
    verification = evaluate(load_spec(bouncy)).verification
    assert verification["outcome"]["completed"] and not verification["passed"]
    (failure,) = verification["failures"]
    assert failure.startswith("simulator and closed form disagree on the handover speeds")
    assert "assume a plastic landing; the palm's restitution 0.3" in failure


def test_junit_report_onto_a_spec_checked_is_refused(tmp_path):
    spec = _spec_with_expect(tmp_path, "feasible = true")
    before = spec.read_text()
    code, _, err = run(tmp_path, "--junit", spec)
    assert code == 2 and "--junit" in err
    assert spec.read_text() == before


def test_control_characters_in_a_key_stay_on_one_line_and_in_valid_xml(tmp_path):
    odd = tmp_path / "odd.toml"
    odd.write_text(PAPER.read_text().replace("[expect]", '[expect]\n"we\\u0001ird\\nkey" = 1'))
    report = tmp_path / "report.xml"
    code, out, _ = run(odd, "--junit", report)
    assert code == 2
    assert len(out.splitlines()) == 1 and out.startswith("ERROR")
    assert '"we\\u0001ird\\nkey"' in out  # the key as TOML would write it
    message = ET.parse(report).getroot().find("testcase/error").get("message")
    assert '"we\\u0001ird\\nkey"' in message


def test_a_reader_that_stops_early_is_not_an_internal_error(tmp_path):
    problems = Path(__file__).resolve().parents[1] / "problems"
    for name in ("a", "b", "c"):  # quick specs: the reader stops after the first line
        (tmp_path / f"{name}.toml").write_text(
            (problems / "paper_stairs_frictionless.toml").read_text())
    proc = subprocess.Popen([sys.executable, "-m", "pdm_design", "check", str(tmp_path)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = proc.stdout.readline()
    proc.stdout.close()  # as `| head -1` does
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 1 and first.startswith("PASS")
    assert err == "error: stdout was closed before all the output was written (its reader " \
                  "stopped early)\n"


@pytest.mark.parametrize("expect, what", [("min_objective = 0.0", "an objective of at least 0"),
                                          ("min_tolerance = 0.0", "a tolerance of at least 0 m")])
def test_a_fixed_design_has_no_objective_or_tolerance_to_meet_a_minimum(tmp_path, expect, what):
    code, out, _ = run(_spec_with_expect(tmp_path, expect))
    noun = what.split(" of ")[0].split()[-1]
    assert code == 1
    assert out.rstrip().endswith(f"expected {what}, got none (a fixed design is evaluated, not "
                                 f"optimised: it has no {noun})")
