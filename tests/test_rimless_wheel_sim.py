"""The rimless wheel's event simulator (numerical stance, general rigid-body impact) against
the closed forms, its named failures, and the vectorised step map against it."""

import math

import numpy as np
import pytest

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    Wheel,
)
from pdm_design.scenes.rimless_wheel.analysis import analyse_rimless_wheel, resolve
from pdm_design.scenes.rimless_wheel.sim import simulate_rimless_wheel
from pdm_design.scenes.rimless_wheel.steps import CODES, step_map
from pdm_design.sim.core import SimulationRefused

WHEELS = [Wheel(), Wheel(mass=2.0, gyration=0.35), Wheel(mass=1.0, gyration=0.1, spoke_mass=0.2)]


POINT = Wheel()


def scene_of(speed, *, wheel=POINT, ground="ramp", friction=1.0):
    return RimlessWheelScene(initial=RimlessWheelInitial(speed=speed), wheel=wheel,
                             ground=ground, friction=friction)


def on_orbit(n=8, slope=0.08, leg=1.0, wheel=POINT, **kw):
    design = RimlessWheelDesign(spokes=n, leg_length=leg, slope=slope)
    a = analyse_rimless_wheel(scene_of(1.0, wheel=wheel, **kw), design)
    assert a.periodic["energy"] > 0  # the orbit vaults its spokes
    return scene_of(a.periodic["post_impact_speed"], wheel=wheel, **kw), design, a


@pytest.mark.parametrize("wheel", WHEELS)
def test_one_step_from_the_orbit_returns_to_it(wheel):
    """The numerical stance and the general impact reproduce the closed-form orbit: pre- and
    post-impact speeds, the step period, and eta."""
    scene, design, a = on_orbit(n=9, slope=0.07, leg=0.9, wheel=wheel)
    run = simulate_rimless_wheel(scene, design, stages=3, accuracy="precise")
    assert run.outcome.completed
    for rec in run.stages:
        assert rec["speed_before"] == pytest.approx(a.periodic["pre_impact_speed"], rel=1e-9)
        assert rec["speed_after"] == pytest.approx(a.periodic["post_impact_speed"], rel=1e-9)
        assert rec["speed_after"] / rec["speed_before"] == pytest.approx(
            a.geometry["impact_ratio"], rel=1e-9)
    assert run.stages[0]["impact_time"] == pytest.approx(a.periodic["step_period"], rel=1e-8)
    assert run.stages[2]["impact_time"] == pytest.approx(3 * a.periodic["step_period"], rel=1e-8)


def test_contraction_against_a_finite_difference_of_the_simulated_return_map():
    for wheel in WHEELS:
        scene, design, a = on_orbit(n=8, slope=0.1, wheel=wheel)
        w, h = scene.initial.speed, 1e-4

        def next_speed(start, wheel=wheel, design=design):
            run = simulate_rimless_wheel(scene_of(start, wheel=wheel), design, stages=1,
                                         accuracy="precise")
            return run.stages[0]["speed_after"]

        slope = (next_speed(w + h) - next_speed(w - h)) / (2 * h)
        assert slope == pytest.approx(a.periodic["contraction"], rel=1e-6)


def test_a_hundred_spokes():
    scene, design, a = on_orbit(n=100, slope=0.01)
    run = simulate_rimless_wheel(scene, design, stages=5)
    assert run.outcome.completed
    assert run.stages[-1]["speed_after"] == pytest.approx(a.periodic["post_impact_speed"],
                                                          rel=1e-7)


def test_three_spokes_of_a_point_mass_never_roll():
    """eta = -1/2 (the analysis' problem): no start speed gets it through two steps. Its stance
    starts 60 deg behind the vertical, where a point mass needs friction tan 60 deg = 1.73 (it
    slips on friction 1), and a speed that would vault the spoke (omega^2 > 2 g / l (1 - cos
    60 deg)) has l omega^2 above g cos 60 deg: it leaves the ground."""
    design = RimlessWheelDesign(spokes=3, leg_length=1.0, slope=0.05)
    assert not analyse_rimless_wheel(scene_of(2.0), design).feasible()
    kinds = set()
    for speed in np.linspace(0.5, 4.0, 15):
        outcome = simulate_rimless_wheel(scene_of(float(speed)), design, stages=2).outcome
        assert not outcome.completed
        kinds.add(outcome.failure.kind)
    assert kinds == {"flight", "slip"}


def test_named_failures():
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=0.08)
    # too slow to vault the first spoke: E = w^2 - 2 g/l (1 - cos(gamma - alpha)) < 0
    slow = math.sqrt(2 * 9.81 * (1 - math.cos(0.08 - math.pi / 8))) * 0.99
    assert simulate_rimless_wheel(scene_of(slow), design, stages=3).outcome.failure.kind == \
        "stalled"
    # l omega^2 > g cos: the normal force is negative at once
    assert simulate_rimless_wheel(scene_of(4.0), design, stages=3).outcome.failure.kind == \
        "flight"
    # a point mass needs tan(alpha) = 0.414 at the stance's start
    run = simulate_rimless_wheel(scene_of(1.2, friction=0.3), design, stages=3)
    assert run.outcome.failure.kind == "slip"


def stairs(landing=None, tread=None, rise=0.1):
    return RimlessWheelDesign(spokes=8, leg_length=1.0, rise=rise, tread=tread,
                              landing_offset=landing)


def test_stairs_landing_drifts_as_the_analysis_says_and_fails_where_its_margin_does():
    scene = scene_of(1.4, ground="stairs")
    base = analyse_rimless_wheel(scene, stairs())
    short = base.geometry["tread"] - 0.02  # footholds move 2 cm forward every step
    design = stairs(landing=0.5, tread=short)
    run = simulate_rimless_wheel(scene, design, stages=40)
    assert run.outcome.failure.kind == "missed_tread"
    made = run.outcome.stages_passed
    # landing k at 0.5 + 0.02 k: beyond the tread first at k = ceil((short - 0.5) / 0.02)
    assert made + 1 == math.ceil((short - 0.5) / 0.02 - 1e-9)
    assert [r["landing_x"] for r in run.stages[:3]] == pytest.approx([0.52, 0.54, 0.56],
                                                                      abs=1e-9)
    assert analyse_rimless_wheel(scene, design, stages=made).margins["landing"] >= 0
    assert analyse_rimless_wheel(scene, design, stages=made + 1).margins["landing"] < 0


def test_stairs_nose_hit_where_the_nose_margin_is_negative():
    """The simulator samples the landing spoke's swing; the analysis uses nose_reach."""
    scene = scene_of(1.4, ground="stairs")
    base = analyse_rimless_wheel(scene, stairs())
    tread, reach = base.geometry["tread"], base.geometry["nose_reach"]
    for landing, fails in ((tread - reach - 0.005, True), (tread - reach + 0.005, False)):
        design = stairs(landing=landing)
        run = simulate_rimless_wheel(scene, design, stages=3)
        assert (run.outcome.failure is not None and run.outcome.failure.kind == "nose_hit") \
            == fails
        assert (analyse_rimless_wheel(scene, design).margins["nose_clearance"] < 0) == fails


def test_refusals():
    with pytest.raises(SimulationRefused, match="slope"):
        simulate_rimless_wheel(scene_of(1.0), RimlessWheelDesign(spokes=8, leg_length=1.0),
                               stages=3)
    with pytest.raises(ValueError, match="spokes"):
        RimlessWheelDesign(spokes=2, leg_length=1.0, slope=0.1)


def test_step_map_matches_the_event_simulator_on_rough_ground():
    scene, design, a = on_orbit(n=8, slope=0.08, wheel=WHEELS[1])
    wh, _, _ = resolve(scene, design)
    rng = np.random.default_rng(3)
    for _ in range(6):
        errors = rng.normal(0.0, 0.02, 60)
        run = simulate_rimless_wheel(scene, design, stages=60, step_errors=[
            {"step": k + 1, "slope": float(e)} for k, e in enumerate(errors)])
        fast = step_map(wh, scene.initial.speed, design.slope + errors[None, :],
                        ground=wh.ground, keep=True)
        assert fast.passed[0] == run.outcome.stages_passed
        kind = CODES[fast.failure[0]]
        assert kind == (run.outcome.failure.kind if run.outcome.failure else "")
        for rec in run.stages:
            assert fast.energies[0, rec["step"]] == pytest.approx(rec["energy_after"], rel=1e-7,
                                                                  abs=1e-9)


def test_a_million_steps_are_all_made():
    """Scale: a million steps of one wheel on slightly rough ground (its speed is timed by
    results/bench_rimless_wheel.py, not here)."""
    scene, design, _ = on_orbit()
    wh, _, _ = resolve(scene, design)
    betas = design.slope + np.random.default_rng(0).normal(0.0, 0.001, (1, 10**6))
    run = step_map(wh, scene.initial.speed, betas, ground=wh.ground)
    assert run.passed[0] == 10**6


@pytest.mark.parametrize("scale", [1e-5, 1e5])
def test_any_size_simulates_the_same_wheel(scale):
    """Lengths x k, speeds x 1/sqrt(k), times x sqrt(k): the same run in the same units."""
    def run(k):
        scene = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.2 / math.sqrt(k)),
                                  wheel=Wheel(gyration=0.2 * k))
        design = RimlessWheelDesign(spokes=8, leg_length=k, slope=0.08)
        return simulate_rimless_wheel(scene, design, stages=5).stages[-1]

    base, scaled = run(1.0), run(scale)
    assert scaled["speed_after"] * math.sqrt(scale) == pytest.approx(base["speed_after"],
                                                                     rel=1e-9)
    assert scaled["impact_time"] / math.sqrt(scale) == pytest.approx(base["impact_time"],
                                                                     rel=1e-9)


@pytest.mark.parametrize("rtol,within", [(1e-9, 1e-8), (1e-12, 1e-11)])
def test_stance_integrator_against_the_elliptic_integral(rtol, within):
    """stance_rk (the Dormand-Prince pair, events located on fresh steps): phi'' = sin phi from
    phi0 = -0.3 at phi' = w0 to the event phi = 0.35; the time is the incomplete elliptic
    integral (docs/rimless_wheel.md section 3; with E = w0^2 - 2 (1 - cos phi0) and u = phi / 2,
    T = (2 / sqrt(E)) [F(u1 | -4 / E) - F(u0 | -4 / E)]), and the speed there the energy's."""
    from scipy.special import ellipkinc

    from pdm_design.scenes.rimless_wheel.stance_rk import integrate

    phi0, phi1, w0 = -0.3, 0.35, 0.5
    energy = w0**2 - 2.0 * (1.0 - math.cos(phi0))
    m = -4.0 / energy
    exact = 2.0 / math.sqrt(energy) * (ellipkinc(phi1 / 2, m) - ellipkinc(phi0 / 2, m))
    t, y, index, _ = integrate((phi0, w0), 50.0, [(lambda y: y[0] - phi1, 1),
                                                  (lambda y: y[1], -1)], rtol, rtol * 1e-2)
    assert index == 0
    assert t == pytest.approx(exact, rel=within)
    assert y[1] == pytest.approx(math.sqrt(energy + 2.0 * (1.0 - math.cos(phi1))), rel=within)
