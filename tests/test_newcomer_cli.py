"""What a newcomer tripped on at the command line: saved documents used with the wrong spec,
output paths found unwritable only after the work, init making folders, simulate --build solving
again, which tolerance the workshop builds to, limited_by in JSON, and the docs against --help.
"""

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ROOT / "problems"


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


# ------------------------------------------------------------ init --out makes no folders

def test_init_into_a_missing_folder_is_bad_input_and_creates_nothing(tmp_path):
    target = tmp_path / "no" / "such" / "dir" / "x.toml"
    code, out, err = run("init", "manipulators", "--out", target)
    assert code == 2 and out == ""
    assert err.startswith("error: command line: --out: expected a file in an existing folder")
    assert f"no folder {target.parent}" in err
    assert list(tmp_path.iterdir()) == []  # not even tmp_path/no


def test_init_into_an_existing_folder_writes_only_the_file(tmp_path):
    target = tmp_path / "x.toml"
    code, out, err = run("init", "stairs", "--out", target)
    assert code == 0 and err == ""
    assert [p.name for p in tmp_path.iterdir()] == ["x.toml"]
    assert "[scene]" in target.read_text()


# ------------------------------------------- an unwritable output is refused before the work

STAIRS = PROBLEMS / "paper_stairs_frictionless.toml"
WORK = {  # the function each command computes with: refusing the output must come first
    "yield": "pdm_design.tolerances.command.run_yield",
    "sheet": "pdm_design.sheet.sheet_for",
    "report": "pdm_design.report.page.report_command",
    "table": "pdm_design.sweep.run.run_sweep",
    "simulate": "pdm_design.verify.simulate_spec",
    "check": "pdm_design.check.check_spec",
}


def _args(command, target):
    spec = PROBLEMS / "stairs_yield.toml" if command == "yield" else STAIRS
    return {"yield": ["--out", target], "sheet": ["--out", target], "report": ["--out", target],
            "table": ["--sweep", "restitution=0.7:0.8:2", "--out", target],
            "simulate": ["--plot", f"{target}.png"],
            "check": ["--junit", f"{target}.xml"]}[command], spec


@pytest.mark.parametrize("command", sorted(WORK))
def test_an_output_under_a_file_is_refused_before_any_work(tmp_path, monkeypatch, command):
    def no_work(*args, **kwargs):
        raise AssertionError("the work started before the output was checked")

    monkeypatch.setattr(WORK[command], no_work)
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    options, spec = _args(command, blocker / "out")
    code, out, err = run(command, spec, *options)
    option = options[-2]
    assert code == 2, err
    assert err.startswith(f"error: command line: {option}: expected a ")
    assert f"that can be written, found {options[-1]}: {blocker} is a file, not a folder" in err
    assert blocker.read_text() == "" and list(tmp_path.iterdir()) == [blocker]


def test_an_output_folder_whose_file_name_is_a_folder_is_refused_before_the_yield(
        tmp_path, monkeypatch):
    monkeypatch.setattr(WORK["yield"], lambda *a, **k: pytest.fail("the yield ran"))
    (tmp_path / "yield.json").mkdir()
    code, out, err = run("yield", PROBLEMS / "stairs_yield.toml", "--out", tmp_path)
    assert code == 2
    assert f"--out: expected a folder that can be written, found {tmp_path}, whose " \
           "yield.json is a folder" in err


# --------------------------------------------- report --yield of another spec is refused

STAIRS_YIELD = PROBLEMS / "stairs_yield.toml"


def _yield_file(tmp_path, spec, name="y", builds=40):
    code, out, err = run("yield", spec, "--builds", builds, "--out", tmp_path / name)
    assert code == 0, err
    return tmp_path / name / "yield.json"


def test_a_yield_names_its_spec_by_schema_digest_and_design(tmp_path):
    import tomllib

    from pdm_design.spec.loader import content_digest

    doc = json.loads(_yield_file(tmp_path, STAIRS_YIELD).read_text())
    data = tomllib.loads(STAIRS_YIELD.read_text())
    assert doc["schema"] == "pdm-design/yield/1" and doc["scene"] == "stairs"
    assert doc["spec"] == str(STAIRS_YIELD) and doc["name"] == data["name"]
    assert doc["spec_sha256"] == content_digest(data)
    assert doc["design"]["restitution"] == data["design"]["restitution"]


def test_report_refuses_a_yield_of_a_stairs_spec_for_a_manipulator_row(tmp_path):
    saved = _yield_file(tmp_path, STAIRS_YIELD)
    target = PROBLEMS / "paper_manipulators.toml"
    code, out, err = run("report", target, "--yield", saved, "--out", tmp_path / "r")
    assert code == 2 and out == ""
    assert err.startswith(f"error: {saved}: spec_sha256: expected the digest of {target}")
    assert "a yield of a stairs scene, this report's is manipulators" in err
    assert f"run on '{STAIRS_YIELD}'" in err
    assert not (tmp_path / "r").exists()


def test_report_refuses_a_yield_of_its_spec_before_the_spec_changed(tmp_path):
    spec = tmp_path / "stairs.toml"
    spec.write_text(STAIRS_YIELD.read_text())
    saved = _yield_file(tmp_path, spec)
    spec.write_text(STAIRS_YIELD.read_text().replace("restitution = 0.8", "restitution = 0.79"))
    code, out, err = run("report", spec, "--yield", saved, "--out", tmp_path / "r")
    assert code == 2
    assert f"{saved}: spec_sha256: expected the digest of {spec} as it is now" in err
    assert "scene" not in err.split("found")[1]  # the same kind and the same file: only content


def test_report_shows_a_yield_of_its_own_spec_and_refuses_one_without_schema(tmp_path):
    saved = _yield_file(tmp_path, STAIRS_YIELD)
    code, out, err = run("report", STAIRS_YIELD, "--yield", saved, "--out", tmp_path / "r")
    assert code == 0, err
    doc = json.loads(saved.read_text())
    assert f"{100 * doc['yield']['estimate']:.2f} %" in (tmp_path / "r" / "report.html").read_text()
    old = {k: v for k, v in doc.items() if k not in ("schema", "spec_sha256")}
    saved.write_text(json.dumps(old))
    code, out, err = run("report", STAIRS_YIELD, "--yield", saved, "--out", tmp_path / "r")
    assert code == 2 and err.startswith(f"error: {saved}: schema: expected 'pdm-design/yield/1'")
