"""The rimless wheel's linearised yield (statistical.py) against an exact probability and Monte
Carlo, and a yield target sized by it and judged by Monte Carlo (the yield command's path)."""

import math

import numpy as np
import pytest
from scipy.special import ndtri

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    rough,
)
from pdm_design.scenes.rimless_wheel.analysis import analyse_rimless_wheel
from pdm_design.scenes.rimless_wheel.builds import build_outcome
from pdm_design.scenes.rimless_wheel.statistical import linearised_yield, row_reliability
from pdm_design.tolerance_model import Tolerance

DESIGN = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=0.08)
STAIRS = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=0.0697, landing_offset=0.3836)


def scene_at(speed, ground="ramp"):
    return RimlessWheelScene(initial=RimlessWheelInitial(speed=speed), ground=ground)


def test_one_stall_against_its_exact_probability():
    """A wheel on its orbit stalls in stance 2 iff the slope of step 1 is below the exact root
    (rough.survival_one_step_exact); the linearised row E_1 = eta^2 E* + b(beta_1) puts it a
    Newton step from the nominal slope instead. Their reliability indices (the root's distance
    in sigmas) are in the ratio of the two distances, the same at every sigma: within 2 % here
    (b's curvature over 0.06 rad)."""
    w = analyse_rimless_wheel(scene_at(1.0), DESIGN).periodic["post_impact_speed"]
    scene = scene_at(w)
    for t in (0.015, 0.02, 0.03):
        g, sd, names, step = row_reliability(scene, DESIGN, [Tolerance("slope", value=t)], 2)
        i = next(j for j, n in enumerate(names) if n == "over_the_top" and step[j] == 2)
        exact = -ndtri(1.0 - rough.survival_one_step_exact(scene, DESIGN, t))
        assert g[i] / sd[i] == pytest.approx(exact, rel=0.02)


@pytest.mark.parametrize("ground,t", [("ramp", 0.02), ("stairs", 0.028)])
def test_twenty_steps_against_monte_carlo(ground, t):
    """1 - the union bound over 20 steps against 200 000 builds on the step map: within the
    Monte Carlo's 4 standard errors and the linearisation's 1e-3."""
    scene = scene_at(1.1 if ground == "ramp" else 1.3, ground)
    design = DESIGN if ground == "ramp" else STAIRS
    names = ("slope",) if ground == "ramp" else ("rise", "tread")
    lin = linearised_yield(scene, design, [Tolerance(q, value=t) for q in names], 20)
    rng = np.random.default_rng(5)
    builds, batch = 200_000, 25_000  # in batches: the step map's arrays of 200 000 builds at
    passed = 0                       # once held 0.7 GB
    for _ in range(builds // batch):
        out = build_outcome(scene, design,
                            {q: rng.normal(0, t / 3, (batch, 20)) for q in names}, 20)
        passed += int(np.sum(out.stages_passed >= 20))
    mc = passed / builds
    se = math.sqrt(mc * (1 - mc) / builds)
    assert 0.95 < mc < 0.995
    assert abs(lin["yield"] - mc) < 4 * se + 1e-3


def test_what_is_not_linearised_is_refused():
    with pytest.raises(ValueError, match="leg_length.*uniform"):
        linearised_yield(scene_at(1.1), DESIGN, [Tolerance("leg_length", value=0.01,
                                                           distribution="uniform")], 20)


def test_a_yield_target_sized_and_judged_by_monte_carlo(tmp_path):
    """tolerances.yield_target with an allocated slope: the linearised yield sizes it, the
    Monte Carlo's 95 % lower end is the judge (the yield command's run)."""
    from pdm_design.commands.yield_ import run_yield
    from pdm_design.spec.loader import load_spec

    path = tmp_path / "wheel.toml"
    path.write_text("""
[scene]
kind = "rimless_wheel"
ground = "ramp"
[initial]
speed = 1.1
[design]
spokes = 8
leg_length = 1.0
slope = 0.08
[tolerances]
yield_target = 0.99
slope = { allocate = true, applies_to = "each" }
[verification]
stages = 20
""")
    result = run_yield(load_spec(path), str(path))
    assert result.ci_low >= 0.99
    sized = next(t["value"] for t in result.tolerances if t["quantity"] == "slope")
    # sized near the target: 1.5 times the slope tolerance falls short of it
    assert sized > 0.01
    scaled = linearised_yield(scene_at(1.1), DESIGN, [Tolerance("slope", value=1.5 * sized)],
                              20)
    assert scaled["yield"] < 0.99
