"""`pdm-design optimize` on fixed designs: the report, the JSON document and the exit codes.

Expected numbers are the paper's (section 4) or closed forms written out here by hand.
"""

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def run(*args):
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def optimize_json(name):
    code, out, _ = run("optimize", str(PROBLEMS / name), "--format", "json")
    return code, json.loads(out)


def test_manipulators_json_has_paper_pitch_and_corrected_speed():
    code, doc = optimize_json("paper_manipulators.toml")
    assert code == 0
    assert doc["status"] == "evaluated"
    assert doc["geometry"]["pitch_x"] == pytest.approx(1.5266, abs=5e-5)
    assert doc["geometry"]["pitch_y"] == pytest.approx(0.3095, abs=5e-5)
    k = 1.0 / 1.1
    speed = math.sqrt(2 * 9.81 * 2 * (math.cos(0.2) - math.cos(0.6))
                      / (1 - (k * math.cos(0.8)) ** 2))
    assert doc["periodic"]["handover_speed"] == pytest.approx(speed, rel=1e-12)
    assert doc["periodic"]["contraction"] == pytest.approx((k * math.cos(0.8)) ** 2, rel=1e-12)


def test_manipulators_json_names_every_design_variable():
    _, doc = optimize_json("paper_manipulators.toml")
    assert doc["design"] == {
        "alpha": 0.2, "beta": 0.6, "link_length": 2.0, "mass_ratio": 10.0,
        "first_pivot_x": 0.0, "first_pivot_y": 0.0,
    }
    assert all(value >= 0 for value in doc["margins"].values())


@pytest.mark.parametrize("name, tread", [
    ("paper_stairs_frictionless.toml", 1.626), ("paper_stairs_friction.toml", 1.565),
])
def test_stairs_json_reproduces_paper_rise_and_tread(name, tread):
    code, doc = optimize_json(name)
    assert code == 0
    assert doc["geometry"]["rise"] == pytest.approx(0.36, abs=1e-12)
    assert doc["geometry"]["tread"] == pytest.approx(tread, abs=1e-3)
    assert doc["periodic"]["impact_speed"] > 0


def test_text_report_shows_status_and_geometry():
    code, out, _ = run("optimize", str(PROBLEMS / "paper_manipulators.toml"))
    assert code == 0
    assert "status: evaluated" in out
    assert "pitch_x" in out and "1.52662 m" in out


def _write(tmp_path, text, name="spec.toml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_insufficient_friction_is_infeasible_with_reason(tmp_path):
    text = (PROBLEMS / "paper_stairs_friction.toml").read_text().replace(
        "friction = 0.5 ", "friction = 0.05 ")
    code, out, _ = run("optimize", _write(tmp_path, text))
    assert code == 1
    assert "status: infeasible" in out
    assert "cannot stop the ball slipping" in out


def test_beta_not_beyond_alpha_is_infeasible(tmp_path):
    text = (PROBLEMS / "paper_manipulators.toml").read_text().replace(
        "beta = 0.6 ", "beta = 0.1 ")
    code, out, _ = run("optimize", _write(tmp_path, text), "--format", "json")
    doc = json.loads(out)
    assert code == 1
    assert doc["status"] == "infeasible"
    # every quantity of the missing orbit is null, and it has no margins (docs/json-schema.md)
    periodic = doc["periodic"]
    assert set(periodic) == {"handover_speed", "landing_speed", "contraction", "drop_per_stage",
                             "effective_mass"}
    assert [k for k, v in periodic.items() if v is None] == [
        "handover_speed", "landing_speed", "drop_per_stage"]
    assert "over_the_top" not in doc["margins"] and "first_over_the_top" in doc["margins"]
    assert any("gains no height" in v for v in doc["violations"])


@pytest.mark.parametrize("replace, key", [
    (("mass = 1.0 ", 'mass = "heavy" '), "scene.body.mass"),
    (("mass = 1.0 ", "mass = -1.0 "), "scene.body.mass"),
    (("restitution = 0.0 ", "restitution = 1.5 "), "scene.palm.restitution"),
    (("alpha = 0.2 ", "alpha = 2.0 "), "design.alpha"),
    (("beta = 0.6 ", "beta = nan "), "design.beta"),
    (("[scene.palm]", "[scene.palm]\nwidht = 1.0"), "scene.palm.widht"),
])
def test_bad_spec_exits_2_naming_file_and_key(tmp_path, replace, key):
    text = (PROBLEMS / "paper_manipulators.toml").read_text()
    assert replace[0] in text
    path = _write(tmp_path, text.replace(*replace, 1))
    code, out, err = run("optimize", path)
    assert code == 2
    assert path in err and key in err
    assert "Traceback" not in err + out


def test_missing_file_exits_2(tmp_path):
    code, _, err = run("optimize", str(tmp_path / "nope.toml"))
    assert code == 2
    assert "nope.toml" in err


def test_console_script_runs_as_a_newcomer_would():
    done = subprocess.run(
        [sys.executable, "-m", "pdm_design", "optimize",
         str(PROBLEMS / "paper_manipulators.toml"), "--format", "json"],
        capture_output=True, text=True, timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["scene"] == "manipulators"


def test_fixed_rise_stairs_verify_against_the_closed_form_transient(tmp_path):
    # With a rise that does not match h0 the vertical impact speed converges by eps^2 per
    # bounce; the verification must compare the simulator with that transient, not the limit.
    text = (PROBLEMS / "paper_stairs_frictionless.toml").read_text().replace(
        "launch_speed = 2.0 ", "launch_speed = 2.0\nrise = 0.3 ")
    code, out, _ = run("optimize", _write(tmp_path, text), "--format", "json")
    doc = json.loads(out)
    assert code == 0, doc["verification"]
    assert doc["verification"]["passed"]
    assert doc["verification"]["agreement"]["compared"] == 20


# --- every documented key is in the document (docs/json-schema.md, parsed here) ---

SCHEMA_DOC = Path(__file__).resolve().parents[1] / "docs" / "json-schema.md"


def _without_parentheses(text):
    """text with every balanced (...) removed: the names in a bullet, not those it mentions."""
    out, depth = [], 0
    for ch in text:
        depth += ch == "("
        if depth == 0:
            out.append(ch)
        depth -= ch == ")" and depth > 0
    return "".join(out)


def _names(text):
    import re

    return re.findall(r"`([a-z_]+)`", _without_parentheses(text))


def documented_keys():
    """{"top": [...], "verification": [...], (scene, object): [...]} from docs/json-schema.md."""
    text = SCHEMA_DOC.read_text().split("## `pdm-design simulate")[0]
    keys = {"top": [], "verification": []}
    for line in text.splitlines():
        if line.startswith("| `"):
            name = line.split("`")[1]
            keys["top"].append(name)
            if name == "verification":
                keys["verification"] = _names(line.split("|")[3])
    keys["verification"] += [m for m in ("accuracy", "accuracy_settings")
                             if f"`verification.{m}`" in text]
    for scene in ("manipulators", "stairs"):
        section = text.split(f"### {scene.capitalize()}")[1].split("###")[0]
        for bullet in section.split("\n- ")[1:]:
            bullet = " ".join(bullet.split())
            name, rest = bullet.split(":", 1)
            keys[(scene, name.strip("`"))] = _names(rest)
    return keys


def test_the_schema_parser_reads_the_documented_keys():
    keys = documented_keys()
    assert "tolerance_failures" in keys["verification"] and "agreement" in keys["verification"]
    assert keys[("stairs", "periodic")] == ["impact_speed", "vertical_impact_speed",
                                            "horizontal_speed", "spin", "flight_time",
                                            "drift_per_bounce"]
    assert keys[("manipulators", "geometry")][-1] == "landing_offset"


def _assert_every_documented_key(doc, keys):
    scene = doc["scene"]
    assert set(keys["top"]) <= set(doc)
    for part in ("design", "geometry", "periodic", "approach"):
        missing = set(keys[(scene, part)]) - set(doc[part])
        assert not missing, f"{part} lacks {missing}"
    if doc["verification"] is not None:
        assert set(keys["verification"]) <= set(doc["verification"])


@pytest.mark.parametrize("problem", ["paper_manipulators.toml", "paper_stairs_friction.toml",
                                     "manipulators_robust.toml"])
def test_every_documented_key_is_present(problem):
    _, doc = optimize_json(problem)
    _assert_every_documented_key(doc, documented_keys())
    assert isinstance(doc["verification"]["tolerance_failures"], list)


def test_a_ball_that_does_not_bounce_has_every_key_null(tmp_path):
    """restitution 0 (valid): no flight, so every quantity of it is null, not left out."""
    text = (PROBLEMS / "paper_stairs_frictionless.toml").read_text()
    assert "restitution = 0.8" in text
    code, out, _ = run("optimize", _write(tmp_path, text.replace("restitution = 0.8",
                                                                  "restitution = 0.0")),
                       "--format", "json")
    doc = json.loads(out)
    assert code == 1
    _assert_every_documented_key(doc, documented_keys())
    assert doc["geometry"]["landing_offset"] is None and doc["geometry"]["nose_clearance"] is None
    assert set(doc["periodic"].values()) == {None}


def test_without_a_fixed_point_the_contraction_is_still_the_maps_slope(tmp_path):
    """beta < alpha: no periodic orbit, but the handover map's slope (m/(m+M))^2 cos^2(a+b) is
    a property of the design (docs/json-schema.md)."""
    text = (PROBLEMS / "paper_manipulators.toml").read_text().replace("beta = 0.6 ", "beta = 0.1 ")
    _, out, _ = run("optimize", _write(tmp_path, text), "--format", "json")
    doc = json.loads(out)
    _assert_every_documented_key(doc, documented_keys())
    assert doc["periodic"]["contraction"] == pytest.approx((1 / 1.1 * math.cos(0.3)) ** 2,
                                                           rel=1e-12)
