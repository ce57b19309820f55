"""Spokes of their own lengths and a hub of its own mass (the leg_length and mass tolerances):
the step map of such builds against the equal spokes' map, the event simulator, and the closed
form of the impact between two spokes of different lengths."""

import dataclasses
import math

import numpy as np
import pytest

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    Wheel,
)
from pdm_design.scenes.rimless_wheel.analysis import resolve
from pdm_design.scenes.rimless_wheel.builds import build_outcome
from pdm_design.scenes.rimless_wheel.sim import simulate_rimless_wheel
from pdm_design.scenes.rimless_wheel.steps import CODES, spoke_map, step_map

RAMP = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.6), friction=0.8,
                         wheel=Wheel(mass=2.0, gyration=0.1, spoke_mass=0.05))
RAMP_DESIGN = RimlessWheelDesign(spokes=10, leg_length=0.5, slope=0.08)
STAIRS = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.3), ground="stairs",
                           wheel=Wheel(mass=1.0, gyration=0.2))
STAIRS_DESIGN = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=0.0697, landing_offset=0.3836)


def stairs_ground(geo, rise_errors, tread_errors):
    treads = np.concatenate([np.full((len(tread_errors), 1), geo["tread"]),
                             geo["tread"] + tread_errors], axis=1)
    return {"rise": geo["rise"] + rise_errors, "tread": treads,
            "landing_offset": geo["landing_offset"]}


def test_equal_spokes_make_the_equal_spokes_map():
    """spoke_map (a loop over the steps, the general forms) with every spoke the design's is
    step_map (the linear filter, the equal spokes' forms): the same steps and failures."""
    rng = np.random.default_rng(1)
    wh, _, _ = resolve(RAMP, RAMP_DESIGN)
    betas = wh.beta + rng.normal(0, 0.04, (3000, 100))
    a = step_map(wh, 1.6, betas, ground=wh.ground)
    b = spoke_map(wh, 1.6, np.full((3000, 10), wh.leg), wh.k2, ground=wh.ground, betas=betas)
    assert (a.failure != 0).sum() > 30
    assert np.array_equal(a.passed, b.passed) and np.array_equal(a.failure, b.failure)
    wh, geo, _ = resolve(STAIRS, STAIRS_DESIGN)
    ground = stairs_ground(geo, rng.normal(0, 0.012, (3000, 20)), rng.normal(0, 0.012,
                                                                           (3000, 20)))
    betas = np.arcsin(ground["rise"] / wh.chord)
    a = step_map(wh, 1.3, betas, ground=0.0, stairs=ground)
    b = spoke_map(wh, 1.3, np.full((3000, 8), 1.0), wh.k2, ground=0.0, stairs=ground)
    assert (a.failure != 0).sum() > 30
    assert np.array_equal(a.passed, b.passed) and np.array_equal(a.failure, b.failure)


@pytest.mark.parametrize("ground", ["ramp", "stairs"])
def test_builds_of_unequal_spokes_and_masses_in_the_event_simulator(ground):
    """Random builds (each spoke its own length, the hub its own mass, every step its own
    ground): the step map's steps made and failure against the event simulator's, which
    integrates each stance on its own spoke and solves each impact as a rigid body's."""
    rng = np.random.default_rng(7 if ground == "ramp" else 8)
    scene, design = (RAMP, RAMP_DESIGN) if ground == "ramp" else (STAIRS, STAIRS_DESIGN)
    builds, stages = 12, 25
    n = design.spokes
    deviations = {"leg_length": rng.normal(0, 0.01 * design.leg_length, (builds, stages)),
                  "mass": rng.normal(0, 0.2, builds)}
    if ground == "ramp":
        deviations["slope"] = rng.normal(0, 0.1, (builds, stages))
    else:
        deviations["rise"] = rng.normal(0, 0.008, (builds, stages))
    mapped = build_outcome(scene, design, deviations, stages)
    assert 0 < int((mapped.stages_passed < stages).sum()) < builds
    for i in range(builds):
        errors = [{"step": k + 1, **{q: float(deviations[q][i, k])
                                     for q in ("slope", "rise") if q in deviations}}
                  for k in range(stages)]
        built = dataclasses.replace(scene, wheel=dataclasses.replace(
            scene.wheel, mass=scene.wheel.mass + float(deviations["mass"][i])))
        run = simulate_rimless_wheel(built, design, stages=stages, step_errors=errors,
                                     spoke_lengths=design.leg_length
                                     + deviations["leg_length"][i, :n])
        assert run.outcome.stages_passed == mapped.stages_passed[i]
        kind = run.outcome.failure.kind if run.outcome.failure else ""
        assert kind == mapped.failure[i]


def test_the_impact_between_unequal_spokes():
    """One impact in the event simulator (its 5 x 5 rigid-body system): omega+ / omega- =
    (k^2 + a b cos 2 alpha) / (k^2 + b^2), the angular momentum about the landing tip."""
    wh, _, _ = resolve(RAMP, RAMP_DESIGN)
    lengths = np.full(10, 0.5)
    lengths[0], lengths[1] = 0.52, 0.47
    run = simulate_rimless_wheel(RAMP, RAMP_DESIGN, stages=1, spoke_lengths=lengths)
    rec = run.stages[0]
    a, b, c2 = 0.52, 0.47, math.cos(2 * math.pi / 10)
    assert rec["speed_after"] / rec["speed_before"] == pytest.approx(
        (wh.k2 + a * b * c2) / (wh.k2 + b * b), rel=1e-12)
    # and the landing tip on the ramp: the chord between the tips at the ramp's angle
    assert -rec["foot_y"] / rec["foot_x"] == pytest.approx(math.tan(0.08), rel=1e-9)
    # the next stance on spoke b from phi1 - 2 alpha, phi1 = atan2(a - b c2, b sin 2 alpha) + beta
    alpha = math.pi / 10
    phi1 = math.atan2(a - b * c2, b * math.sin(2 * alpha)) + 0.08
    rate_b = 2 * 9.81 * b / (wh.k2 + b * b)
    assert rec["energy_after"] == pytest.approx(
        rec["speed_after"]**2 - rate_b * (1 - math.cos(phi1 - 2 * alpha)), rel=1e-12)


def test_a_point_mass_wheel_does_not_feel_its_mass():
    """With no radius of gyration and massless spokes k^2 = 0 whatever the hub's mass: the
    builds of a mass tolerance are the builds without it, exactly."""
    scene = dataclasses.replace(RAMP, wheel=Wheel(mass=1.0))
    rng = np.random.default_rng(3)
    slope = {"slope": rng.normal(0, 0.04, (2000, 50))}
    alone = build_outcome(scene, RAMP_DESIGN, slope, 50)
    massed = build_outcome(scene, RAMP_DESIGN, {**slope, "mass": rng.normal(0, 0.3, 2000)}, 50)
    assert (alone.stages_passed < 50).sum() > 20
    assert np.array_equal(alone.stages_passed, massed.stages_passed)
    assert list(alone.failure) == list(massed.failure)


def test_each_spoke_needs_as_many_steps_as_spokes():
    from pdm_design.plugin import of
    from pdm_design.spec.loader import parse_spec

    data = {"scene": {"kind": "rimless_wheel", "ground": "ramp"}, "initial": {"speed": 1.6},
            "design": {"spokes": 10, "leg_length": 0.5, "slope": 0.08},
            "tolerances": {"leg_length": {"value": 0.01, "applies_to": "each"}},
            "verification": {"stages": 6}}
    spec = parse_spec(data)
    assert of(spec).tolerance_refusal(spec, "leg_length")[0] == "verification.stages"
    data["verification"]["stages"] = 10
    assert of(parse_spec(data)).tolerance_refusal(parse_spec(data), "leg_length") is None
    assert CODES[0] == ""
