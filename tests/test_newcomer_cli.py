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
    "yield": "pdm_design.commands.yield_.run_yield",
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
    assert f"a yield of '{STAIRS_YIELD}' (a stairs scene; this report's is manipulators)" in err
    assert not (tmp_path / "r").exists()


def test_report_refuses_a_yield_of_its_spec_before_the_spec_changed(tmp_path):
    spec = tmp_path / "stairs.toml"
    spec.write_text(STAIRS_YIELD.read_text())
    saved = _yield_file(tmp_path, spec)
    spec.write_text(STAIRS_YIELD.read_text().replace("restitution = 0.8", "restitution = 0.79"))
    code, out, err = run("report", spec, "--yield", saved, "--out", tmp_path / "r")
    assert code == 2
    assert f"{saved}: spec_sha256: expected the digest of {spec} as it is now" in err
    assert err.rstrip().endswith(f"a yield of '{spec}' as it was then")  # same kind, same file


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


# ------------------------------------- simulate --build --from: the yield's design, no solve

TOLERANCES = """
[tolerances]
builds = 400
seed = 3
confirm = 5
pivot_x = { value = 0.2, applies_to = "each" }
pivot_y = { value = 0.2, applies_to = "each" }
friction = { value = 0.1, applies_to = "lot" }
"""


def _no_solve(monkeypatch):
    def solve(*args, **kwargs):
        raise AssertionError("solved again")

    import importlib

    import pdm_design.solve

    for target in ("pdm_design.api.design", "pdm_design.commands.yield_.sized_tolerances"):
        monkeypatch.setattr(target, solve)
    monkeypatch.setattr(pdm_design.solve, "optimize", solve)  # the IPOPT solve itself
    monkeypatch.setattr(importlib.import_module("pdm_design.solve.optimize"), "optimize", solve)


@pytest.fixture(scope="module")
def robust_yield(tmp_path_factory):
    """A spec with free alpha and beta and pivots +-200 mm (builds tip), its yield's folder."""
    folder = tmp_path_factory.mktemp("robust")
    spec = folder / "robust.toml"
    spec.write_text((PROBLEMS / "manipulators_robust.toml").read_text() + TOLERANCES)
    code, out, err = run("yield", spec, "--out", folder / "y")
    assert code == 0, err
    return spec, folder / "y", json.loads((folder / "y" / "yield.json").read_text())


def test_simulate_build_from_the_yield_folder_solves_nothing_and_runs_the_drawn_build(
        robust_yield, monkeypatch):
    import pdm_design.tolerances.yield_ as yield_module

    spec, folder, doc = robust_yield
    failing = doc["failing_builds"]
    assert len(failing) >= 3
    solved = {}  # the solving path (the spec's design found again): the second method
    for build in failing[:3]:
        code, out, _ = run("simulate", spec, "--build", f"3:{build['index']}", "--stages", 6,
                           "--format", "json")
        solved[build["index"]] = json.loads(out)["outcome"]
    _no_solve(monkeypatch)
    seen = []
    original = yield_module.simulate_one
    monkeypatch.setattr(yield_module, "simulate_one",
                        lambda *a, **k: seen.append(a) or original(*a, **k))
    for build in failing[:3]:
        assert build["command"].endswith(f"--build 3:{build['index']} --stages 6 --from {folder}")
        code, out, err = run("simulate", spec, "--build", f"3:{build['index']}", "--from",
                             folder, "--format", "json")
        outcome, again = json.loads(out)["outcome"], solved[build["index"]]
        assert code == 1 and outcome["stages_passed"] == again["stages_passed"]
        # a solve again lands within IPOPT's tolerance of the yield's design, not on it
        assert outcome["failure"]["time"] == pytest.approx(again["failure"]["time"], rel=1e-6)
        assert outcome["stages_passed"] == build["stages_passed"]
        assert outcome["failure"]["event"] == build["failure"]
    scene, design, tolerances, seed, index, stages = seen[-1]
    assert (seed, index, stages) == (3, failing[2]["index"], 6)
    assert {v: getattr(design, v) for v in design.VARIABLES} == doc["design"]
    assert [t.value for t in tolerances] == [t["value"] for t in doc["tolerances"]]


def test_simulate_from_a_saved_optimize_document_solves_nothing(robust_yield, tmp_path,
                                                                 monkeypatch):
    spec, _, _ = robust_yield
    code, out, _ = run("optimize", spec, "--format", "json", "--no-verify")
    saved = tmp_path / "design.json"
    saved.write_text(out)
    code, solved, _ = run("simulate", spec, "--build", "3:0", "--stages", 6, "--format", "json")
    _no_solve(monkeypatch)
    monkeypatch.setattr("pdm_design.commands.yield_.sized_tolerances",
                        lambda spec, source, point, stages, **_: spec.tolerances)  # none to size
    code, out, err = run("simulate", spec, "--build", "3:0", "--stages", 6, "--from", saved,
                         "--format", "json")
    assert code == 0, err
    assert json.loads(out)["outcome"] == json.loads(solved)["outcome"]
    code, out, err = run("simulate", spec, "--from", saved, "--stages", 6)
    assert code == 0 and "stage" in out


def test_simulate_from_a_yield_of_another_spec_is_bad_input(robust_yield, tmp_path,
                                                              monkeypatch):
    _, folder, _ = robust_yield
    _no_solve(monkeypatch)
    other = tmp_path / "other.toml"
    other.write_text((PROBLEMS / "manipulators_robust.toml").read_text().replace(
        "stages = 6", "stages = 5") + TOLERANCES)
    code, out, err = run("simulate", other, "--build", "3:0", "--from", folder)
    assert code == 2 and out == ""
    assert err.startswith(f"error: {folder / 'yield.json'}: spec_sha256: expected the digest "
                          f"of {other} as it is now")


# ------------------------------------- limited_by of a quantity sized by its weight's share

SHARE = """
[tolerances]
pivot_x = { allocate = true, weight = 1 }
pivot_y = { allocate = true, weight = 1 }
palm_mass = { allocate = true, weight = 10 }
"""


def test_json_says_a_tolerance_is_held_by_its_weights_share_as_the_text_does(tmp_path):
    spec = tmp_path / "share.toml"
    spec.write_text((PROBLEMS / "manipulators_robust.toml").read_text().split("[expect]")[0]
                    + SHARE)
    code, out, err = run("optimize", spec, "--format", "json", "--no-verify")
    assert code == 0, err
    entries = {e["quantity"]: e for e in json.loads(out)["tolerances"]}
    # t_q = s w_min / w_q (docs/tolerances.md): the palm mass gets a tenth of the pivots' scale
    assert entries["palm_mass"]["value"] == pytest.approx(entries["pivot_x"]["value"] / 10,
                                                          rel=1e-12)
    assert entries["palm_mass"]["limited_by"] == [
        {"condition": "weight_share", "where": "", "share": None}]
    assert all(r["condition"] != "weight_share" for q in ("pivot_x", "pivot_y")
               for r in entries[q]["limited_by"]) and entries["pivot_x"]["limited_by"]
    code, text, _ = run("optimize", spec, "--no-verify")
    line = next(li for li in text.splitlines()
                if li.strip().startswith("palm_mass") and "limited by" in li)
    assert line.endswith("limited by: its weight's share of the others' (no binding row "
                         "involves it)")


# ---------------------------------- two tolerances on one bracket: which one to build to

def test_sheet_and_report_say_which_of_two_pivot_tolerances_the_workshop_builds_to(
        robust_yield, tmp_path):
    from pdm_design.sheet import sheet_for
    from pdm_design.sheet.drawing import _notes

    spec, _, _ = robust_yield  # pivots +-200 mm in its [tolerances], alpha and beta free
    code, out, _ = run("optimize", spec, "--format", "json", "--no-verify")
    box = json.loads(out)["tolerance"]  # the worst-case box, a second command's answer
    wanted = (f"Build to the spec's tolerances (spec): pivot x +-200 mm, pivot y +-200 mm; "
              "the yield (pdm-design yield) is the fraction of such builds that work. The "
              f"worst-case box (box), pivot x +-{1000 * box['dx']:.4g} mm, pivot y "
              f"+-{1000 * box['dy']:.4g} mm, is narrower")
    code, out, err = run("sheet", spec, "--out", tmp_path / "s", "--no-drawing")
    assert code == 0, err
    assert wanted in (tmp_path / "s" / "sheet.md").read_text()
    code, out, err = run("report", spec, "--out", tmp_path / "r", "--no-yield")
    assert code == 0, err
    assert wanted in (tmp_path / "r" / "report.html").read_text()
    assert wanted.split(";")[0] in " ".join(_notes(sheet_for(str(spec))))  # under the drawing


def test_no_word_on_building_to_when_the_sheet_has_one_pivot_tolerance(tmp_path):
    code, out, err = run("sheet", PROBLEMS / "manipulators_robust.toml", "--out", tmp_path,
                         "--no-drawing")
    assert code == 0 and "(box)" in (tmp_path / "sheet.md").read_text()
    assert "Build to" not in (tmp_path / "sheet.md").read_text()


# ------------------------------------------------------------- the docs against --help

COMMANDS = ("init", "optimize", "simulate", "table", "sheet", "yield", "report", "check")


def _readme_rows() -> dict[str, str]:
    """The README's command table: command -> its first cell (usage), backslashes dropped."""
    import re

    rows = {}
    for line in (ROOT / "README.md").read_text().splitlines():
        found = re.match(r"\| `pdm-design (\w+)(.*?)` \|", line)
        if found and found.group(1) in COMMANDS:
            rows[found.group(1)] = found.group(2).replace("\\|", "|")
    return rows


def _help(command) -> tuple[set[str], list[str]]:
    """(every option of `command --help` but --help, the arguments of its usage line)."""
    import re

    code, out, _ = run(command, "--help")
    assert code == 0
    usage = out.splitlines()[0].split("[OPTIONS]")[1].split()
    listed = out.split("\nOptions:\n")[1]
    options = set(re.findall(r"^  (?:-\w, )?(--[a-z][a-z-]*)", listed, flags=re.M)) - {"--help"}
    return options, usage


@pytest.mark.parametrize("command", COMMANDS)
def test_the_readme_command_table_lists_every_option_and_argument_help_gives(command):
    import re

    row = _readme_rows()[command]
    options, arguments = _help(command)
    assert set(re.findall(r"--[a-z][a-z-]*", row)) == options
    shown = re.sub(r"\[[^\]]*\]", " ", row).split()
    assert [a.strip("{}") for a in arguments] == [shown[0]]


def test_the_readme_example_is_what_optimize_prints():
    text = (ROOT / "README.md").read_text()
    block = text.split("$ pdm-design optimize problems/paper_manipulators.toml\n")[1]
    shown = block.split("  ...\n")[0].splitlines()
    assert "  effective_mass  0.1 kg" in shown  # M (1 + 0): massless links, docs/physics.md
    code, out, _ = run("optimize", PROBLEMS / "paper_manipulators.toml")
    assert out.splitlines()[: len(shown)] == shown


def test_help_names_every_file_sheet_and_table_write(tmp_path):
    code, _, err = run("sheet", STAIRS, "--out", tmp_path / "s")
    assert code == 0, err
    _, sheet_help, _ = run("sheet", "--help")
    for written in (tmp_path / "s").iterdir():
        assert written.name in " ".join(sheet_help.split()), written.name
    code, _, err = run("table", STAIRS, "--sweep", "restitution=0.7:0.8:2", "--workers", 1,
                       "--out", tmp_path / "t")
    assert code == 0, err
    _, table_help, _ = run("table", "--help")
    for written in (tmp_path / "t").iterdir():
        named = "plots, PNG and SVG" if written.suffix in (".png", ".svg") else written.name
        assert named in " ".join(table_help.split()), written.name
    _, simulate_help, _ = run("simulate", "--help")
    assert "--plot FILE" in simulate_help and "TEXT" not in simulate_help


def test_default_folders_are_named_after_the_specs_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = tmp_path / "draft-3.toml"
    spec.write_text(STAIRS.read_text())  # name = "paper_stairs_frictionless"
    code, out, err = run("sheet", spec, "--no-drawing")
    assert code == 0, err
    assert (tmp_path / "paper_stairs_frictionless-sheet" / "sheet.md").is_file()
    spec.write_text(STAIRS.read_text().replace('name = "paper_stairs_frictionless"',
                                               'name = "my stairs / v2"'))
    code, out, err = run("sheet", spec, "--no-drawing")
    assert code == 0 and (tmp_path / "draft-3-sheet" / "sheet.md").is_file()  # not a file name


def test_one_build_is_one_build_in_words(tmp_path):
    code, out, err = run("yield", PROBLEMS / "stairs_yield.toml", "--builds", 1)
    assert code == 0, err
    assert "stairs_yield (stairs): 1 build of 100 stages, seed 0" in out
    assert "1 builds" not in out and "of 1 random build agrees" in out


def test_an_internal_error_message_ends_in_one_full_stop(monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("the design could not be evaluated while sampling.")

    monkeypatch.setattr("pdm_design.api.design", broken)
    code, out, err = run("optimize", PROBLEMS / "paper_manipulators.toml")
    assert code == 1
    assert err == ("internal error (RuntimeError): the design could not be evaluated while "
                   "sampling. Please report it with the spec that caused it.\n")


def test_the_linearised_ellipsoid_is_named_by_its_smallest_semi_axis():
    code, out, err = run("optimize", PROBLEMS / "manipulators_robust.toml", "--linearised",
                         "--no-verify", "--format", "json")
    semi = json.loads(out)["tolerance"]["linearised"]["ellipsoid"]["min_semi_axis"]
    code, out, err = run("optimize", PROBLEMS / "manipulators_robust.toml", "--linearised",
                         "--no-verify")
    assert f"ellipsoid with its smallest semi-axis {semi * 1e3:.2f} mm" in out
    assert "and up" not in out
