"""Builds as a user meets them: one name for an unbuildable part in the map, the simulator and
`simulate --build`; frictions drawn below 0 taken at 0; tolerances around a nominal of 0
refused; the scale curve's point 1 is the headline yield; one stage convention on both scenes;
the text report's sensitivity and units."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pdm_design.cli import main
from pdm_design.commands.yield_ import yield_text
from pdm_design.scenes.manipulators.model import ManipulatorOffset
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.scenes.manipulators.tolerances import simulate_build
from pdm_design.spec import load_spec
from pdm_design.tolerances import run_builds
from pdm_design.tolerances.draw import draw
from pdm_design.tolerances.yield_ import simulate_one, yield_of

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

ROW = """
name = "row"
[scene]
kind = "manipulators"
gravity = 9.81
[scene.body]
mass = 1.0
width = 0.4
height = 0.2
[scene.palm]
width = 1.6
thickness = 0.05
friction = 0.8
restitution = 0.0
front_stop = 1.5707963
{extra}
[initial]
position = [-1.25, 3.05]
velocity = [3.0, 0.0]
[design]
alpha = 0.2
beta = 0.6
link_length = 2.0
mass_ratio = 10.0
[verification]
stages = 2
[tolerances]
{tolerances}
"""
LINKS = "[scene.links]\nmass = 0.5\ncount = 2\n[scene.pivots]\nfriction_torque = 0.2\n"


def _spec(tmp_path, extra="", tolerances="palm_mass = { value = 0.3, applies_to = \"lot\" }",
          name="row.toml"):
    path = tmp_path / name
    path.write_text(ROW.format(extra=extra, tolerances=tolerances))
    return str(path)


# ------------------------------------------------------------------- unbuildable parts

def test_an_unbuildable_part_is_invalid_part_in_map_and_simulator(tmp_path):
    spec = load_spec(_spec(tmp_path))
    scene, design = spec.scene, spec.design_at()
    dev = {"palm_mass": np.array([[0.0, 0.0], [0.0, -0.1]])}  # palm 2 of build 1: 0 kg
    out = run_builds(scene, design, dev, 2)
    assert list(out.failure) == ["", "invalid_part"] and list(out.stages_passed) == [2, 0]
    run = simulate_build(scene, design, {"palm_mass": dev["palm_mass"][1:]}, 2)
    assert not run.outcome.completed and run.outcome.stages_passed == 0
    failure = run.outcome.failure
    assert failure.kind == "invalid_part" and "manipulator 2's palm_mass = 0 kg" in failure.detail


def test_unbuildable_builds_agree_in_the_confirmation(tmp_path):
    # the palms' lot mass 0.1 +- 0.3 kg (sigma 0.1): about one build in six has palms of
    # no mass; every build confirmed by the simulator agrees with the map, invalid ones too
    spec = load_spec(_spec(tmp_path))
    tols = spec.tolerances
    r = yield_of(spec.scene, spec.design_at(), tols, builds=40, stages=2, seed=0, confirm=40,
                 scales=(), sensitivity_samples=0)
    invalid = int((0.1 + draw(tols, 40, 2, 0, scene=spec.scene)["palm_mass"] <= 0.0).sum())
    assert invalid >= 3 and r.failures.get("invalid_part") == invalid
    assert r.confirmed["random"] == 40 and r.confirmed["agreed"] == 40


def test_simulate_build_reports_an_unbuildable_part_as_its_failure(tmp_path):
    path = _spec(tmp_path)
    spec = load_spec(path)
    masses = 0.1 + draw(spec.tolerances, 100, 2, 0, scene=spec.scene)["palm_mass"]
    index = int(np.flatnonzero(masses <= 0.0)[0])
    result = CliRunner().invoke(main, ["simulate", path, "--build", f"0:{index}", "--stages",
                                       "2"])
    assert result.exit_code == 1, result.output
    assert "error" not in result.output and "refuses" not in result.output
    assert "FAILED, 0 stages passed" in result.output
    assert "failure: invalid_part at stage 1" in result.output
    assert "palm_mass = -" in result.output and "cannot be built (needs > 0)" in result.output
    plotted = CliRunner().invoke(main, ["simulate", path, "--build", f"0:{index}", "--stages",
                                        "2", "--plot", str(tmp_path / "run.png")])
    assert plotted.exit_code == 1 and "internal error" not in plotted.output, plotted.output
    assert "no figures" in plotted.output


def test_a_friction_torque_drawn_below_zero_is_a_frictionless_bearing(tmp_path):
    spec = load_spec(_spec(tmp_path, LINKS, "pivot_friction = { value = 0.3 }"))
    scene, design = spec.scene, spec.design_at()
    tau = scene.pivots.friction_torque
    below = {"pivot_friction": np.array([[-tau - 0.05, 0.0]])}
    at_zero = {"pivot_friction": np.array([[-tau, 0.0]])}
    a, b = (run_builds(scene, design, d, 2) for d in (below, at_zero))
    assert a.failure[0] != "invalid_part"
    assert (a.stages_passed[0], a.failure[0], a.min_margin[0]) == (
        b.stages_passed[0], b.failure[0], b.min_margin[0])
    sims = [simulate_build(scene, design, d, 2).outcome for d in (below, at_zero)]
    assert sims[0] == sims[1] and (sims[0].failure is None
                                   or sims[0].failure.kind != "invalid_part")


# ------------------------------------------------------------------- zero nominals

@pytest.mark.parametrize("extra, tolerance, key, needs", [
    ("", "link_mass = { value = 0.01 }", "tolerances.link_mass", "[scene.links] mass"),
    ("", "pivot_friction = { value = 0.01 }", "tolerances.pivot_friction",
     "[scene.pivots] friction_torque"),
])
def test_a_tolerance_on_a_zero_nominal_is_refused_at_its_key(tmp_path, extra, tolerance, key,
                                                             needs):
    path = _spec(tmp_path, extra, tolerance)
    result = CliRunner().invoke(main, ["yield", path, "--builds", "10"])
    assert result.exit_code == 2, result.output
    assert key in result.output and needs in result.output and "is 0" in result.output


def test_a_friction_tolerance_on_frictionless_stairs_is_refused(tmp_path):
    text = (PROBLEMS / "stairs_yield.toml").read_text()
    text = text.replace('launch_speed = { value = 0.015, applies_to = "lot" }',
                        'friction = { value = 0.01, applies_to = "lot" }')
    path = tmp_path / "st.toml"
    path.write_text(text)
    result = CliRunner().invoke(main, ["yield", str(path), "--builds", "10"])
    assert result.exit_code == 2 and "tolerances.friction" in result.output, result.output


# ------------------------------------------------------------------- the scale curve

def test_the_scale_curves_point_at_one_is_the_headline_yield():
    spec = load_spec(str(PROBLEMS / "stairs_yield.toml"))
    r = yield_of(spec.scene, spec.design_at(), spec.tolerances, builds=1500, stages=100,
                 seed=0, confirm=0, scales=(0.5, 1.0), sensitivity_samples=0)
    point = {p["scale"]: p for p in r.scale_curve}[1.0]
    assert (point["estimate"], point["ci_low"], point["ci_high"], point["builds"]) == (
        r.estimate, r.ci_low, r.ci_high, 1500)
    assert r.estimate < 1.0  # (failures to agree on)


# ------------------------------------------------------------------- stage numbers

def test_a_failure_is_at_stage_stages_passed_plus_one_on_both_scenes():
    # stairs: build 0:48 of stairs_yield over 100 bounces hits the nose of the step it left
    spec = load_spec(str(PROBLEMS / "stairs_yield.toml"))
    run = simulate_one(spec.scene, spec.design_at(), spec.tolerances, 0, 48, 100).outcome
    mapped = run_builds(spec.scene, spec.design_at(),
                        draw(spec.tolerances, 1, 100, 0, scene=spec.scene, start=48), 100)
    assert run.failure.kind == "nose_hit" == mapped.failure[0]
    assert run.stages_passed == mapped.stages_passed[0]
    assert run.failure.stage == run.stages_passed + 1
    assert run.failure.after["step"] == run.stages_passed
    # manipulators: the paper's second manipulator 0.4 m high is in the feed's way: the object
    # hits its side (time stepped, sim/stepped.py), comes down on palm 1 and knocks palm 2 off
    # its back stop; palm 2 swings to its front stop and palm 1 throws the object over it onto
    # palm 3 (skipped_palm at stage 2, one passed); its fourth 0.5 m high is met by the
    # object palm 2 carries, which pushes it off its back stop (sim/pushing.py): it swings out
    # of the way and the object, handed on by palm 3, flies over it onto palm 5 (skipped_palm
    # at stage 4, three passed)
    paper = load_spec(str(PROBLEMS / "paper_manipulators.toml"))
    for k, dy, passed in ((2, 0.4, 1), (4, 0.5, 3)):
        out = simulate_manipulators(paper.scene, paper.design_at(), stages=6,
                                    offsets=(ManipulatorOffset(manipulator=k, dx=0.0, dy=dy),)
                                    ).outcome
        assert not out.completed and out.failure.stage == out.stages_passed + 1
        assert out.stages_passed == passed


# ------------------------------------------------------------------- the text report

def test_the_text_shows_noise_indices_as_zero_and_no_unit_for_a_coefficient(tmp_path):
    spec = load_spec(_spec(tmp_path, tolerances="friction = { value = 0.1, applies_to = "
                           "\"lot\" }\npivot_x = { value = 0.01 }"))
    r = yield_of(spec.scene, spec.design_at(), spec.tolerances, builds=20, stages=2, confirm=3,
                 scales=(), sensitivity_samples=0)
    rows = ({"quantity": "pivot_y", "index": 0.6, "first": 0.5, "confidence": 0.2},
            {"quantity": "pivot_x", "index": 0.05, "first": 0.0, "confidence": 0.1},
            {"quantity": "friction", "index": 5.19e-30, "first": 0.0, "confidence": 0.0})
    curve = ({"scale": 0.5, "simulated": 4, "builds": 20, "estimate": 1.0, "ci_low": 0.8,
              "ci_high": 1.0},
             {"scale": 1.0, "simulated": 0, "builds": 20, "estimate": 1.0, "ci_low": 0.8,
              "ci_high": 1.0})
    text = yield_text(dataclasses.replace(r, sensitivity=rows, scale_curve=curve), "row")
    assert "pivot_y 0.6 +- 0.2, pivot_x 0.05 +- 0.1 (not resolved" in text
    assert "its 95 % interval includes 0), friction 0\n" in text
    assert "e-30" not in text
    (line,) = [s for s in text.splitlines() if s.strip().startswith("friction")]
    assert line.split()[:3] == ["friction", "+-0.1", "lot"]
    assert f"{r.confirmed['simulated'] + 4} builds simulated in all" in text
