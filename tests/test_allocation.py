"""Worst-case tolerance allocation (formulation/allocation.py, docs/optimizer.md section 4a):
today's pivot box is the equal-weights case; the allocated box of every quantity holds in the
event simulator at its corners, and 1.5 times it does not; bad allocations exit 2 in words."""

import itertools
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pdm_design.scenes.manipulators.tolerances import simulate_build
from pdm_design.solve import optimize
from pdm_design.spec import load_spec
from pdm_design.verify.tolerance import corner_patterns

ROOT = Path(__file__).resolve().parent.parent
BASE = (ROOT / "problems" / "manipulators_robust.toml").read_text().split("[expect]")[0]
EVERY = """[tolerances]
pivot_x = { allocate = true, weight = 1 }
pivot_y = { allocate = true, weight = 2 }
feed_x = { allocate = true, weight = 1 }
friction = { allocate = true, weight = 10 }
object_width = { allocate = true, weight = 2 }
feed_speed = { allocate = true, weight = 2 }
palm_mass = { allocate = true, weight = 10 }
object_mass = { allocate = true, weight = 10 }
"""
LOTS = ("feed_x", "friction", "object_width", "feed_speed", "palm_mass", "object_mass")


def _spec(tmp_path, extra, name="spec.toml", base=BASE):
    path = tmp_path / name
    path.write_text(base + "\n" + extra)
    return load_spec(path)


@pytest.fixture(scope="module")
def every(tmp_path_factory):
    spec = _spec(tmp_path_factory.mktemp("every"), EVERY)
    return spec, optimize(spec)


@pytest.mark.parametrize("weight", [1.0, 2.5])
def test_equal_pivot_weights_are_todays_box(tmp_path, weight):
    today = optimize(_spec(tmp_path, "", "today.toml"))
    spec = _spec(tmp_path, f"[tolerances]\npivot_x = {{ allocate = true, weight = {weight} }}\n"
                           f"pivot_y = {{ allocate = true, weight = {weight} }}\n")
    result = optimize(spec)
    assert result.status.value == "optimal"
    assert abs(result.tolerance["dx"] - today.tolerance["dx"]) < 1e-9
    assert abs(result.tolerance["dy"] - today.tolerance["dy"]) < 1e-9
    assert [e["quantity"] for e in result.tolerances] == ["pivot_x", "pivot_y"]


def test_weights_set_the_ratios(tmp_path, every):
    spec, result = every
    assert result.status.value == "optimal"
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    s = value["pivot_x"]  # the smallest weight's tolerance is the scale itself
    assert value["feed_x"] == pytest.approx(s, rel=1e-12)
    assert value["pivot_y"] == pytest.approx(s / 2, rel=1e-12)
    assert value["object_width"] == pytest.approx(s / 2, rel=1e-12)
    assert value["friction"] == pytest.approx(s / 10, rel=1e-12)
    assert value["feed_speed"] == pytest.approx(s / 2, rel=1e-12)
    assert value["palm_mass"] == pytest.approx(s / 10, rel=1e-12)
    assert result.checks["sampled_offsets"]["passed"]


def _simulate(spec, result, scale, lots_signs, signs):
    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    value = {e["quantity"]: scale * e["value"] for e in result.tolerances}
    stages = spec.verification.stages
    deviations = {"pivot_x": np.array([[sx * value["pivot_x"] for sx, _ in signs]]),
                  "pivot_y": np.array([[sy * value["pivot_y"] for _, sy in signs]])}
    for q, sign in zip(LOTS, lots_signs):  # the palms' masses: every palm alike
        deviations[q] = np.full((1, stages), sign * value[q]) if q == "palm_mass" else \
            np.array([sign * value[q]])
    run = simulate_build(spec.scene, design, deviations, stages)
    return run.outcome.completed


def _corners(spec, result, scale):
    """(pattern, lot signs) of every corner of the scaled box where the simulator fails."""
    failed = []
    for name, signs in corner_patterns(spec.verification.stages):
        for lots in itertools.product((1.0, -1.0), repeat=len(LOTS)):
            if not _simulate(spec, result, scale, lots, signs):
                failed.append((name, tuple(lots)))
    return failed


def test_every_corner_of_the_allocated_box_passes(every):
    spec, result = every
    assert _corners(spec, result, 1.0) == []


def test_palm_masses_palm_by_palm(every):
    """The mass bound holds stage by stage: palms alternately heavy and light pass too."""
    spec, result = every
    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    stages = spec.verification.stages
    alternating = np.array([[(-1.0) ** k * value["palm_mass"] for k in range(stages)]])
    for _, signs in corner_patterns(stages):
        for lots in itertools.product((1.0, -1.0), repeat=2):
            deviations = {"pivot_x": np.array([[sx * value["pivot_x"] for sx, _ in signs]]),
                          "pivot_y": np.array([[sy * value["pivot_y"] for _, sy in signs]]),
                          "palm_mass": lots[0] * alternating,
                          "object_mass": np.array([lots[1] * value["object_mass"]])}
            assert simulate_build(spec.scene, design, deviations, stages).outcome.completed


def test_a_corner_beyond_the_box_fails(every):
    spec, result = every
    assert _corners(spec, result, 1.5)  # the box is not vacuous: 1.5 times it breaks a build


def test_a_mass_tolerance_keeps_a_mass(tmp_path):
    """Alone, the palms' mass tolerance is held by the palms keeping a mass (the speed rows
    allow any mass ratio here): (1 - 1e-3) of the 0.1 kg palm, and the builds pass."""
    spec = _spec(tmp_path, "[tolerances]\npalm_mass = { allocate = true }\n")
    result = optimize(spec)
    assert result.status.value == "optimal"
    value = result.tolerances[0]["value"]
    assert value == pytest.approx(0.1 * (1 - 1e-3), rel=1e-6)
    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    for sign in (1.0, -1.0):
        run = simulate_build(spec.scene, design, {"palm_mass": np.full((1, 6), sign * value)}, 6)
        assert run.outcome.completed


STOPS = """[tolerances]
pivot_x = { allocate = true }
pivot_y = { allocate = true }
back_stop = { allocate = true, weight = 10 }
"""


def _stop_failures(spec, result, scale):
    """Corner patterns of the pivots with the back stops all high, all low or alternating,
    scaled, where the simulator fails."""
    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    value = {e["quantity"]: scale * e["value"] for e in result.tolerances}
    stages = spec.verification.stages
    alternating = np.array([(-1.0) ** k for k in range(stages)])
    failed = []
    for name, signs in corner_patterns(stages):
        for stop_name, stop in (("+", np.ones(stages)), ("-", -np.ones(stages)),
                                ("alt", alternating), ("-alt", -alternating)):
            deviations = {"pivot_x": np.array([[sx * value["pivot_x"] for sx, _ in signs]]),
                          "pivot_y": np.array([[sy * value["pivot_y"] for _, sy in signs]]),
                          "back_stop": (stop * value["back_stop"])[None, :]}
            if not simulate_build(spec.scene, design, deviations, stages).outcome.completed:
                failed.append((name, stop_name))
    return failed


def test_back_stops_hold_at_the_corners(tmp_path):
    spec = _spec(tmp_path, STOPS)
    result = optimize(spec)
    assert result.status.value == "optimal" and result.checks["sampled_offsets"]["passed"]
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    assert value["back_stop"] == pytest.approx(value["pivot_x"] / 10, rel=1e-12)
    assert value["back_stop"] > 0.0
    assert _stop_failures(spec, result, 1.0) == []
    assert _stop_failures(spec, result, 1.5)


def test_json_lists_every_tolerance_with_its_limits(tmp_path):
    path = tmp_path / "every.toml"
    path.write_text(BASE + "\n" + EVERY)
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path),
                          "--format", "json"], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    entries = {e["quantity"]: e for e in doc["tolerances"]}
    assert set(entries) == {"pivot_x", "pivot_y", *LOTS}
    for e in entries.values():
        assert set(e) == {"quantity", "applies_to", "value", "unit", "allocated", "limited_by"}
    assert entries["pivot_x"]["unit"] == "m" and entries["friction"]["applies_to"] == "lot"
    # the landing row binds and involves the pivots' places and the feed, not the friction
    assert any(r["condition"] == "landing" for r in entries["pivot_x"]["limited_by"])
    assert not any(r["condition"] == "landing" for r in entries["friction"]["limited_by"])
    assert doc["verification"]["passed"]


def test_given_value_is_a_fixed_half_width(tmp_path, every):
    _, result = every
    spec = _spec(tmp_path, "[tolerances]\npivot_x = { allocate = true }\n"
                           "pivot_y = { allocate = true }\nfeed_x = { value = 0.05 }\n")
    given = optimize(spec)
    assert given.status.value == "optimal"
    entries = {e["quantity"]: e for e in given.tolerances}
    assert entries["feed_x"]["value"] == 0.05 and not entries["feed_x"]["allocated"]
    today = optimize(_spec(tmp_path, "", "today.toml"))
    assert given.tolerance["dx"] < today.tolerance["dx"]  # the feed's error takes a share


LINKS = "[scene.links]\nmass = 0.5\ncount = 2\n"


@pytest.mark.parametrize("extra, key, why", [
    ("link_length = { allocate = true }\nback_stop = { allocate = true }\n" + LINKS,
     "tolerances.link_length", "expected the back stops exact"),
    ("pivot_x = { allocate = true }\nlink_length = { value = 0.01 }\n"
     "back_stop = { value = 0.001 }\n" + LINKS, "tolerances.link_length",
     "expected the back stops exact"),
])
def test_unbounded_quantities_are_refused(tmp_path, extra, key, why):
    path = tmp_path / "bad.toml"
    path.write_text(BASE + "\n[tolerances]\n" + extra + "\n")
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 2
    assert key in run.stderr and why in run.stderr and "Traceback" not in run.stderr
    assert str(path) in run.stderr


def test_allocation_needs_the_tolerance_objective(tmp_path):
    path = tmp_path / "no_objective.toml"
    path.write_text(BASE.replace("max_offset_tolerance = 1.0", "min_drop = 1.0")
                    + "\n[tolerances]\npivot_x = { allocate = true }\n")
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 2 and "tolerances.pivot_x.allocate" in run.stderr
    assert "max_offset_tolerance" in run.stderr and "Traceback" not in run.stderr


STAIRS = (ROOT / "problems" / "stairs_design.toml").read_text().split("[expect]")[0]


def test_stairs_equal_weights_are_todays_box(tmp_path):
    today = optimize(_spec(tmp_path, "", "today.toml", base=STAIRS))
    spec = _spec(tmp_path, "[tolerances]\nrise = { allocate = true, weight = 3 }\n"
                           "tread = { allocate = true, weight = 3 }\n", base=STAIRS)
    result = optimize(spec)
    assert result.status.value == "optimal"
    for axis in ("rise", "tread"):
        assert abs(result.tolerance[axis] - today.tolerance[axis]) < 1e-9


def _stairs_corners(spec, result, scale):
    """Corner patterns of the scaled (rise, tread) box where the simulator fails."""
    from pdm_design.scenes.stairs.tolerances import simulate_build as simulate_stairs_build

    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    stages = spec.verification.stages
    t_r, t_t = scale * result.tolerance["rise"], scale * result.tolerance["tread"]
    failed = []
    for name, signs in corner_patterns(stages):
        run = simulate_stairs_build(spec.scene, design, {
            "rise": [sr * t_r for sr, _ in signs], "tread": [st * t_t for _, st in signs]},
            stages)
        if not run.outcome.completed:
            failed.append(name)
    return failed


def test_stairs_unequal_weights_hold_at_the_corners(tmp_path):
    today = optimize(_spec(tmp_path, "", "today.toml", base=STAIRS))
    spec = _spec(tmp_path, "[tolerances]\nrise = { allocate = true, weight = 1 }\n"
                           "tread = { allocate = true, weight = 0.5 }\n", base=STAIRS)
    result = optimize(spec)
    assert result.status.value == "optimal"
    assert result.tolerance["tread"] == pytest.approx(2 * result.tolerance["rise"], rel=1e-12)
    assert result.tolerance["tread"] > today.tolerance["tread"]  # the tread's share grew
    assert result.checks["sampled_offsets"]["passed"]
    assert _stairs_corners(spec, result, 1.0) == []
    assert _stairs_corners(spec, result, 1.5)


def test_stairs_launch_place_holds_at_the_corners(tmp_path):
    spec = _spec(tmp_path, "[tolerances]\nrise = { allocate = true }\n"
                           "tread = { allocate = true }\nlaunch_x = { allocate = true }\n",
                 base=STAIRS)
    result = optimize(spec)
    assert result.status.value == "optimal"
    t_l = {e["quantity"]: e["value"] for e in result.tolerances}["launch_x"]
    assert t_l == result.tolerance["rise"] == result.tolerance["tread"]
    from pdm_design.scenes.stairs.tolerances import simulate_build as simulate_stairs_build

    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    stages = spec.verification.stages

    def failures(scale):
        t = scale * t_l
        return [(name, sl) for name, signs in corner_patterns(stages) for sl in (1.0, -1.0)
                if not simulate_stairs_build(spec.scene, design, {
                    "rise": [sr * t for sr, _ in signs], "tread": [st * t for _, st in signs],
                    "launch_x": sl * t}, stages).outcome.completed]

    assert failures(1.0) == []
    assert failures(1.5)


def test_stairs_verification_runs_the_launch_place_corners(tmp_path):
    path = tmp_path / "launch.toml"
    path.write_text(STAIRS + "\n[tolerances]\nrise = { allocate = true }\n"
                    "tread = { allocate = true }\nlaunch_x = { allocate = true, weight = 0.5 }\n")
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path),
                          "--format", "json"], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    value = {e["quantity"]: e["value"] for e in doc["tolerances"]}
    assert value["launch_x"] == pytest.approx(2 * value["rise"], rel=1e-12)
    assert doc["verification"]["passed"]
    assert doc["verification"]["samples"] == 1 + 12 * 2 + 16  # nominal, corners x lot, random


def test_stairs_launch_place_with_exact_rows_is_refused_in_words(tmp_path):
    path = tmp_path / "stairs.toml"
    path.write_text(STAIRS.replace("max_offset_tolerance = 1.0", "max_offset_tolerance = 1.0\n"
                                   "max_min_margin = 1.0")
                    + "\n[tolerances]\nrise = { allocate = true }\nlaunch_x = { value = 0.01 }\n")
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 2 and "tolerances.launch_x" in run.stderr
    assert "exact launch rows" in run.stderr and "Traceback" not in run.stderr
