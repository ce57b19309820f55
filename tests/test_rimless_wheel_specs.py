"""The rimless wheel's spec files and template: each reads into the scene and design classes
(as the loader will: [scene] without kind, [initial] into scene.initial) and does what its
comment says."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    Wheel,
    formulation,
    rough,
)
from pdm_design.scenes.rimless_wheel.analysis import analyse_rimless_wheel
from pdm_design.scenes.rimless_wheel.sim import simulate_rimless_wheel
from pdm_design.scenes.rimless_wheel.template import rimless_wheel_template
from pdm_design.spec.model import Bounds, Spec, Verification

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"


def read(text):
    data = tomllib.loads(text)
    table = {k: v for k, v in data["scene"].items() if k != "kind"}
    assert data["scene"]["kind"] == "rimless_wheel"
    wheel = Wheel(**{k: float(v) for k, v in table.pop("wheel", {}).items()})
    scene = RimlessWheelScene(initial=RimlessWheelInitial(**data["initial"]), wheel=wheel,
                              **table)
    design = {k: Bounds(**v) if isinstance(v, dict) else v for k, v in data["design"].items()}
    spec = Spec(source="test", scene=scene, design=design, objective=data.get("objective", {}),
                verification=Verification(stages=data["verification"]["stages"]))
    return data, spec


def test_ramp_problem_as_its_comment_says():
    data, spec = read((PROBLEMS / "rimless_wheel_ramp.toml").read_text())
    design = RimlessWheelDesign(**spec.design)
    a = analyse_rimless_wheel(spec.scene, design, stages=spec.verification.stages)
    assert a.feasible()
    assert a.periodic["post_impact_speed"] == pytest.approx(1.948, abs=5e-4)
    assert a.periodic["step_period"] == pytest.approx(0.340, abs=5e-4)
    assert a.periodic["contraction"] == pytest.approx(0.683, abs=5e-4)
    assert simulate_rimless_wheel(spec.scene, design, stages=50).outcome.completed


def test_stairs_problem_solves_to_a_box_the_simulator_keeps():
    from test_rimless_wheel_formulation import solve

    _, spec = read((PROBLEMS / "rimless_wheel_stairs.toml").read_text())
    x = solve(spec)
    assert x["tolerance"] > 0.005
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=float(x["rise"]),
                                landing_offset=float(x["landing_offset"]))
    rng = np.random.default_rng(4)
    for _ in range(3):
        errors = rng.uniform(-x["tolerance"], x["tolerance"], (20, 2))
        run = simulate_rimless_wheel(spec.scene, design, stages=20, step_errors=[
            {"step": k + 1, "rise": float(r), "tread": float(t)}
            for k, (r, t) in enumerate(errors)])
        assert run.outcome.completed


def test_rough_problem_finds_the_longest_lasting_wheel():
    data, spec = read((PROBLEMS / "rimless_wheel_rough.toml").read_text())
    slope = spec.design["slope"]
    tolerance = data["tolerances"]["slope"]["value"]
    best = rough.longest_lasting(spec.scene, formulation.spoke_counts(spec),
                                 (slope.min, slope.max), 1.0, tolerance)
    by_count = best["by_count"]
    assert best["spokes"] == max(by_count, key=lambda n: by_count[n][1])
    # the slope found beats its neighbours on the finer chain
    n, s = best["spokes"], best["slope"]
    here = best["mfpt"]["estimate"]
    for other in (s - 0.01, s + 0.01):
        design = RimlessWheelDesign(spokes=n, leg_length=1.0, slope=other)
        assert rough.mfpt(spec.scene, design, tolerance)["estimate"] < here


def test_template_reads_and_its_start_vaults_every_slope():
    data, spec = read(rimless_wheel_template())
    slope = spec.design["slope"]
    slow = spec.scene.initial.speed - spec.scene.initial.speed_tolerance
    need = 2 * 9.81 / 1.0 * (1 - math.cos(slope.min - math.pi / 8))
    assert slow**2 > need
    assert formulation.build(spec)


def test_the_scene_object_names_the_pieces_and_imports_nothing_heavy():
    import subprocess
    import sys

    code = ("import sys; from pdm_design.plugin import scene_kind; "
            "s = scene_kind('rimless_wheel'); "
            "print(sorted(m for m in ('numpy', 'scipy', 'casadi') if m in sys.modules)); "
            "print(s.kind, s.margins)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parent.parent, check=True).stdout
    assert out.splitlines()[0] == "[]"
    from pdm_design.plugin import scene_kind
    from pdm_design.scenes.rimless_wheel import plugin
    from pdm_design.scenes.rimless_wheel.sim import FAILURE_KINDS

    scene = scene_kind("rimless_wheel")
    assert plugin.FAILURE_KINDS == FAILURE_KINDS
    data, spec = read(scene.template())
    assert scene.analyse(spec.scene, RimlessWheelDesign(
        spokes=8, leg_length=1.0, slope=0.1)).kind == scene.kind
