"""Custom accuracy settings from the spec (`[verification] accuracy = {...}`) and the command line
(`--accuracy rtol=1e-10,...`): they reach the simulator and verification, the optimizer takes
its base preset's settings, and bad values exit 2 naming the key.

Expected tolerances are the values written in these tests' specs and options, and the presets'
documented values (docs/spec.md, section 8) for the keys left out.
"""

import importlib
import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
PAPER = PROBLEMS / "paper_manipulators.toml"


def spec_with_accuracy(tmp_path, setting: str, name: str = "paper_manipulators") -> str:
    """A copy of a problem whose [verification] table has `accuracy = <setting>` (TOML)."""
    text = (PROBLEMS / f"{name}.toml").read_text(encoding="utf-8")
    assert "[verification]\n" in text
    path = tmp_path / "spec.toml"
    path.write_text(text.replace("[verification]\n", f"[verification]\naccuracy = {setting}\n"),
                    encoding="utf-8")
    return str(path)


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


def tolerances(accuracy) -> tuple:
    return accuracy.rtol, accuracy.atol, accuracy.event_tol, accuracy.agreement


# ------------------------------------------------------------------ the spec's inline table

def test_spec_table_reaches_the_simulator_and_the_report(tmp_path, monkeypatch):
    import pdm_design.scenes.manipulators.sim as manipulators
    from pdm_design.api import design
    from pdm_design.spec import load_spec

    seen = []
    real = manipulators.simulate_manipulators

    def spy(*args, **kwargs):
        seen.append(kwargs["accuracy"])
        return real(*args, **kwargs)

    monkeypatch.setattr(manipulators, "simulate_manipulators", spy)
    spec = load_spec(spec_with_accuracy(
        tmp_path, '{ base = "precise", rtol = 1e-10, agreement = 1e-8 }'))
    outcome = design(spec)
    # rtol and agreement from the table; atol and event_tol from precise (1e-14 each).
    assert seen and all(tolerances(a) == (1e-10, 1e-14, 1e-14, 1e-8) for a in seen)
    assert seen[0].name == "custom" and seen[0].base == "precise"
    assert outcome.verification["passed"]
    assert outcome.verification["accuracy"] == "custom"
    assert outcome.verification["accuracy_settings"] == {
        "base": "precise", "rtol": 1e-10, "atol": 1e-14, "event_tol": 1e-14, "agreement": 1e-8,
            "carry": "closed"}


def test_spec_agreement_governs_verification(tmp_path):
    # The paper's design agrees with the closed forms to ~1e-16: no agreement above that can
    # fail, an agreement of 1e-300 must.
    code, out, _ = run("optimize", spec_with_accuracy(tmp_path, "{ agreement = 1e-300 }"))
    assert code == 1
    assert "disagree" in out and "agreement 1e-300" in out
    code, _, _ = run("optimize", spec_with_accuracy(tmp_path, "{ agreement = 1e-12 }"))
    assert code == 0


def test_table_with_base_alone_is_that_preset(tmp_path):
    from pdm_design.spec import load_spec

    spec = load_spec(spec_with_accuracy(tmp_path, '{ base = "fast" }'))
    assert spec.verification.accuracy.name == "fast"
    assert tolerances(spec.verification.accuracy) == (1e-6, 1e-8, 1e-7, 1e-4)


def test_preset_names_still_load(tmp_path):
    from pdm_design.spec import load_spec

    spec = load_spec(spec_with_accuracy(tmp_path, '"precise"'))
    assert spec.verification.accuracy.name == "precise"
    assert tolerances(spec.verification.accuracy) == (1e-12, 1e-14, 1e-14, 1e-9)
    assert load_spec(PAPER).verification.accuracy.name == "default"


BAD_SPEC = [
    # (setting, key path in the message, what the message says was expected)
    ('{ rtol = "x" }', "verification.accuracy.rtol", "expected a number >= 2.22e-14"),
    ('{ base = "ultra" }', "verification.accuracy.base", "expected one of: fast, default"),
    ("3", "verification.accuracy:", "expected one of: fast, default, precise"),
    ('"quick"', "verification.accuracy:", "expected one of: fast, default, precise"),
    ("{ rtol = -1 }", "verification.accuracy.rtol", "found -1"),
    ("{ rtol = 1e-16 }", "verification.accuracy.rtol", "found 1e-16"),
    ("{ atol = 0 }", "verification.accuracy.atol", "expected a finite number > 0"),
    ("{ event_tol = inf }", "verification.accuracy.event_tol", "found inf"),
    ("{ agreement = nan }", "verification.accuracy.agreement", "found nan"),
    ("{ agreement = 1.5 }", "verification.accuracy.agreement", "< 1"),
    ("{ atol = true }", "verification.accuracy.atol", "found true"),
    ("{ rtoll = 1e-9 }", "verification.accuracy.rtoll", "did you mean 'rtol'?"),
    ("{ atol = 1e-9, speed = 1 }", "verification.accuracy.speed", "unknown key 'speed'"),
]


@pytest.mark.parametrize("setting, key, expected", BAD_SPEC, ids=[c[0] for c in BAD_SPEC])
def test_bad_spec_setting_exits_2_naming_the_key(tmp_path, setting, key, expected):
    for command in ("optimize", "simulate"):
        code, out, err = run(command, spec_with_accuracy(tmp_path, setting))
        assert code == 2, err
        assert out == "" and "Traceback" not in err
        assert err.startswith(f"error: {tmp_path / 'spec.toml'}: {key}")
        assert expected in err


# ------------------------------------------------------------------ --accuracy on the command line

def test_simulate_accepts_custom_tolerances_and_reports_them():
    stairs = PROBLEMS / "paper_stairs_frictionless.toml"
    code, out, _ = run("simulate", stairs, "--accuracy", "rtol=1e-10,event_tol=1e-12",
                       "--format", "json")
    doc = json.loads(out)
    assert code == 0 and doc["outcome"]["completed"]
    assert doc["accuracy"] == "custom"
    # atol and agreement from the default base (1e-11, 1e-7).
    assert doc["accuracy_settings"] == {"base": "default", "rtol": 1e-10, "atol": 1e-11,
                                        "event_tol": 1e-12, "agreement": 1e-7,
                                        "carry": "closed"}
    code, out, _ = run("simulate", stairs, "--accuracy", "base=fast,rtol=1e-7")
    assert code == 0
    assert "accuracy custom: rtol 1e-07, atol 1e-08, event_tol 1e-07, agreement 0.0001; " \
           "base fast" in out.splitlines()[0]


def test_optimize_accepts_custom_tolerances_and_reports_them():
    code, out, _ = run("optimize", PAPER, "--accuracy", "rtol=1e-10, agreement=1e-8",
                       "--format", "json")
    doc = json.loads(out)
    assert code == 0 and doc["verification"]["passed"]
    assert doc["verification"]["accuracy"] == "custom"
    assert doc["verification"]["accuracy_settings"] == {
        "base": "default", "rtol": 1e-10, "atol": 1e-11, "event_tol": 1e-11, "agreement": 1e-8,
        "carry": "closed"}
    code, out, _ = run("optimize", PAPER, "--accuracy", "rtol=1e-10")
    assert code == 0 and "verification: passed (accuracy custom: rtol 1e-10," in out


def test_command_line_replaces_the_spec_setting(tmp_path):
    spec = spec_with_accuracy(tmp_path, '{ base = "precise", rtol = 1e-10 }')
    code, out, _ = run("simulate", spec, "--accuracy", "fast", "--format", "json")
    assert code == 0 and json.loads(out)["accuracy"] == "fast"


BAD_OPTION = [
    # (value, words the message must contain)
    ("rtol=-1", ("rtol", "expected a number >= 2.22e-14", "found -1")),
    ("foo", ("expected one of: fast, default, precise", "'foo'")),
    ("speed=1", ("speed", "unknown key 'speed'")),
    ("rtol=abc", ("rtol", "'abc'")),
    ("base=ultra", ("base", "expected one of: fast, default, precise", "'ultra'")),
    ("rtol=1e-10,rtol=1e-9", ("rtol", "each key once")),
    ("rtol=1e-10,", ("KEY=VALUE",)),
    ("agreement=2", ("agreement", "< 1")),
]


@pytest.mark.parametrize("value, words", BAD_OPTION, ids=[c[0] for c in BAD_OPTION])
def test_bad_option_exits_2_naming_option_and_key(value, words):
    for command in ("optimize", "simulate"):
        code, out, err = run(command, PAPER, "--accuracy", value)
        assert code == 2, err
        assert out == "" and "Traceback" not in err
        assert err.startswith("error: command line: --accuracy: ")
        for word in words:
            assert word in err


# ------------------------------------------------------------------ the optimizer's settings

@pytest.mark.parametrize("value, ipopt_tol, starts", [
    # SOLVE_PRESETS (api.py): fast's IPOPT tol 1e-5 and 4 starts; default's 1e-8 and 8.
    ("base=fast,rtol=1e-10", 1e-5, 4),
    ("rtol=1e-10,agreement=1e-6", 1e-8, 8),
])
def test_custom_accuracy_solves_with_its_base_preset(monkeypatch, value, ipopt_tol, starts):
    # The module, not the function of the same name that pdm_design.solve exports.
    solve_module = importlib.import_module("pdm_design.solve.optimize")
    tols = []
    real = solve_module.solver_for

    def spy(key, nlp, options):
        tols.append(options.tol)
        return real(key, nlp, options)

    monkeypatch.setattr(solve_module, "solver_for", spy)
    code, out, err = run("optimize", PROBLEMS / "stairs_design.toml", "--accuracy", value,
                         "--format", "json")
    doc = json.loads(out)
    assert code == 0, err
    assert tols and set(tols) == {ipopt_tol}
    assert doc["solver"]["starts"] == starts
    assert doc["verification"]["accuracy"] == "custom"
    assert doc["verification"]["accuracy_settings"]["rtol"] == 1e-10
