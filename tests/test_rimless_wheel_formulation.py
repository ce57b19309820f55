"""The rimless wheel's NLP rows: at a fixed design they are the analysis' margins; the robust
box they find holds in the simulator at its corners and fails just beyond them."""

import math

import casadi as ca
import numpy as np
import pytest

from pdm_design.errors import SpecError
from pdm_design.formulation.common import assemble
from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    formulation,
)
from pdm_design.scenes.rimless_wheel.analysis import analyse_rimless_wheel, resolve
from pdm_design.scenes.rimless_wheel.sim import simulate_rimless_wheel
from pdm_design.scenes.rimless_wheel.steps import step_map
from pdm_design.spec.model import Bounds, Spec, Verification

STAGES = 20


def spec_of(design, *, ground="ramp", speed=1.3, speed_tolerance=0.0, objective=None,
            stages=STAGES):
    scene = RimlessWheelScene(initial=RimlessWheelInitial(speed=speed,
                                                          speed_tolerance=speed_tolerance),
                              ground=ground)
    return Spec(source="test", scene=scene, design=design, objective=objective or {},
                verification=Verification(stages=stages))


def formulated(spec):
    model, bounds, _ = formulation.build(spec)
    return assemble(spec, model, key=repr(spec), bounds=bounds), bounds


def solve(spec, **options):
    form, bounds = formulated(spec)
    solver = ca.nlpsol("wheel", "ipopt", form.nlp, {"ipopt.print_level": 0, "print_time": 0,
                                                    "ipopt.sb": "yes", **options})
    x0 = form.start_vector({n: bounds[n][2] for n in form.design_names})
    sol = solver(x0=x0, lbx=form.lbx, ubx=form.ubx, lbg=form.lbg, ubg=form.ubg,
                 p=form.parameters())
    assert solver.stats()["success"]
    x = np.asarray(sol["x"]).ravel()
    return dict(zip(form.x_names, x))


def row_margins(spec):
    """The smallest slack / scale of each margin's rows at the spec's (fixed) design."""
    form, bounds = formulated(spec)
    x = form.start_vector({})
    slack, scale, _, _ = form.evaluate(x, form.parameters())
    with np.errstate(divide="ignore"):  # a slip row's scale mu N is 0 where N <= 0
        ratio = np.asarray(slack).ravel() / np.asarray(scale).ravel()
    out = {}
    for info, value in zip(form.conditions, ratio):
        if info.kind == "margin" and not info.equality:
            out[info.name] = min(out.get(info.name, math.inf), float(value))
    return out


@pytest.mark.parametrize("ground,design", [
    ("ramp", {"spokes": 8, "leg_length": 1.0, "slope": 0.08}),
    ("ramp", {"spokes": 12, "leg_length": 0.5, "slope": 0.05}),
    ("ramp", {"spokes": 8, "leg_length": 1.0, "slope": 0.45}),  # starts past the vertical
    ("stairs", {"spokes": 8, "leg_length": 1.0, "rise": 0.1, "landing_offset": 0.45}),
])
def test_rows_at_a_fixed_design_are_the_analysis_margins(ground, design):
    """The rows bound the whole approach by its start and its limit, the orbit: the analysis
    followed until it converged; the footholds over the verification's steps."""
    spec = spec_of(design, ground=ground)
    analysis = analyse_rimless_wheel(spec.scene, RimlessWheelDesign(**design))
    footholds = analyse_rimless_wheel(spec.scene, RimlessWheelDesign(**design), stages=STAGES)
    rows = row_margins(spec)
    for name in ("over_the_top", "impact_friction"):
        assert rows[name] == pytest.approx(analysis.margins[name], rel=1e-9, abs=1e-12)
    for name in ("landing", "nose_clearance"):
        if name in footholds.margins:
            assert rows[name] == pytest.approx(footholds.margins[name], rel=1e-9, abs=1e-12)
    # the force rows judge the approach's two ends at 9 angles, the analysis every stance at 33
    # (a row's slack / scale is 1 - demand / capacity on both sides of 0; a failed margin is
    # -(1 - capacity / demand): there only the sign is the same)
    for name in ("no_flight", "no_slip"):
        if analysis.margins[name] >= 0:
            assert rows[name] == pytest.approx(analysis.margins[name], abs=2e-3)
        else:
            assert rows[name] < 0


def corner(wh, spec, slope_error, speed, steps):
    betas = np.full((1, steps), wh.beta + slope_error)
    return step_map(wh, speed, betas, ground=wh.ground)


def test_robust_ramp_box_holds_at_its_corners_and_fails_beyond():
    design = {"spokes": 8, "leg_length": 1.0, "slope": Bounds(min=0.02, max=0.3, initial=0.1)}
    spec = spec_of(design, speed_tolerance=0.05, objective={"max_offset_tolerance": 1.0})
    x = solve(spec)
    tau, slope = x["tolerance"], x["slope"]
    assert tau > 0.01
    fixed = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=float(slope))
    wh, _, _ = resolve(spec.scene, fixed)
    for sign, speed in ((-1, 1.25), (1, 1.35)):
        run = corner(wh, spec, sign * tau * (1 - 1e-4), speed, 100_000)
        assert run.passed[0] == 100_000
    # the lowest slopes' orbit stalls a little beyond the box (the over_the_top row binds)
    assert corner(wh, spec, -tau * 1.02, 1.25, 100_000).passed[0] < 100_000
    # random builds inside the box, in the event simulator
    rng = np.random.default_rng(2)
    for _ in range(4):
        errors = rng.uniform(-tau, tau, STAGES)
        scene = spec_of({}, speed=float(1.3 + rng.uniform(-0.05, 0.05))).scene
        run = simulate_rimless_wheel(scene, fixed, stages=STAGES, step_errors=[
            {"step": k + 1, "slope": float(e)} for k, e in enumerate(errors)])
        assert run.outcome.completed


def test_robust_stairs_box_in_the_simulator():
    design = {"spokes": 8, "leg_length": 1.0, "rise": Bounds(min=0.01, max=0.3, initial=0.1)}
    spec = spec_of(design, ground="stairs", speed_tolerance=0.05,
                   objective={"max_offset_tolerance": 1.0})
    x = solve(spec)
    tau = x["tolerance"]
    fixed = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=float(x["rise"]))
    scene = spec.scene

    def worst(scale):  # every rise and tread short: the footholds run furthest forward
        errors = [{"step": k, "rise": -scale * tau, "tread": -scale * tau}
                  for k in range(1, STAGES + 1)]
        return simulate_rimless_wheel(scene, fixed, stages=STAGES, step_errors=errors).outcome

    assert worst(1 - 1e-4).completed
    beyond = worst(1.05)
    # two rows bind at the optimum: the furthest foothold and the lowest rises' orbit
    assert not beyond.completed and beyond.failure.kind in ("missed_tread", "stalled")


def test_spoke_counts():
    spec = spec_of({"spokes": Bounds(min=5.5, max=9.0), "leg_length": 1.0, "slope": 0.1})
    assert formulation.spoke_counts(spec) == [6, 7, 8, 9]
    with pytest.raises(SpecError, match="spokes"):
        formulation.build(spec)
    fixed = formulation.with_spokes(spec, 7)
    assert fixed.design["spokes"] == 7 and formulation.build(fixed)


def test_a_hundred_spokes_and_three():
    """100 spokes: the box holds at its corners on the step map; 3 spokes of a point mass
    (eta = -1/2): IPOPT finds no design, the impact row is the one broken."""
    spec = spec_of({"spokes": 100, "leg_length": 1.0, "slope": Bounds(min=0.001, max=0.05)},
                   speed=3.0, objective={"max_offset_tolerance": 1.0})
    x = solve(spec)
    fixed = RimlessWheelDesign(spokes=100, leg_length=1.0, slope=float(x["slope"]))
    wh, _, _ = resolve(spec.scene, fixed)
    for sign in (-1, 1):
        assert corner(wh, spec, sign * x["tolerance"] * (1 - 1e-4), 3.0, 10_000).passed[0] \
            == 10_000
    three = spec_of({"spokes": 3, "leg_length": 1.0, "slope": Bounds(min=0.01, max=1.0)},
                    speed=1.0)
    form, bounds = formulated(three)
    solver = ca.nlpsol("three", "ipopt", form.nlp, {"ipopt.print_level": 0, "print_time": 0,
                                                    "ipopt.sb": "yes"})
    sol = solver(x0=form.start_vector({"slope": 0.5}), lbx=form.lbx, ubx=form.ubx,
                 lbg=form.lbg, ubg=form.ubg, p=form.parameters())
    assert not solver.stats()["success"]
    rows = np.asarray(form.evaluate(sol["x"], form.parameters())[0]).ravel()
    broken = {form.conditions[i].name for i in np.flatnonzero(rows < -1e-6)}
    assert "impact_ratio" in broken


@pytest.mark.parametrize("ground", ["ramp", "stairs"])
@pytest.mark.parametrize("size", [1e-5, 1e5])
def test_the_same_design_at_any_size(ground, size):
    """Lengths x k, speeds x 1/sqrt(k): the same slope (rise / k) and box. The rows are pure
    numbers; IPOPT's own gradient-based scaling of the SI variables (not used here) moves the
    answer at 1e-5 m by 3e-4 of itself."""
    def answer(k):
        design = ({"spokes": 8, "leg_length": k, "slope": Bounds(min=0.02, max=0.3,
                                                                   initial=0.1)}
                  if ground == "ramp" else
                  {"spokes": 8, "leg_length": k, "rise": Bounds(min=0.01 * k, max=0.3 * k,
                                                                 initial=0.1 * k)})
        spec = spec_of(design, ground=ground, speed=1.3 / math.sqrt(k),
                       speed_tolerance=0.05 / math.sqrt(k),
                       objective={"max_offset_tolerance": 1.0})
        x = solve(spec, **{"ipopt.nlp_scaling_method": "none"})
        unit = 1.0 if ground == "ramp" else k
        return x["slope" if ground == "ramp" else "rise"] / unit, x["tolerance"] / unit

    base, scaled = answer(1.0), answer(size)
    assert scaled == pytest.approx(base, rel=1e-7)


def test_stairs_box_of_the_problem_holds_at_every_corner_and_is_tight():
    """problems/rimless_wheel_stairs.toml: the box the NLP claims, in the event simulator at
    every corner of (every rise, every tread, the start speed): all complete just inside it;
    2 % beyond it the (+, +) corners fail at a nose (the landing spoke's reach
    l sin 2 alpha / cos(alpha - beta) shrinks as a long rise steepens the chord) and the short
    rises' orbit stalls (over_the_top)."""
    from pdm_design.spec.loader import load_spec

    spec = load_spec("problems/rimless_wheel_stairs.toml")
    x = solve(spec)
    tau = x["tolerance"]
    fixed = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=float(x["rise"]),
                               landing_offset=float(x["landing_offset"]))

    def corner_run(scale, rise_sign, tread_sign, speed_sign):
        scene = spec_of({}, ground="stairs",
                        speed=1.3 + speed_sign * 0.05 * min(scale, 1.0)).scene
        errors = [{"step": k, "rise": rise_sign * scale * tau, "tread": tread_sign * scale * tau}
                  for k in range(1, spec.verification.stages + 1)]
        return simulate_rimless_wheel(scene, fixed, stages=spec.verification.stages,
                                      step_errors=errors).outcome

    signs = [(r, t, s) for r in (-1, 1) for t in (-1, 1) for s in (-1, 1)]
    assert all(corner_run(1 - 1e-4, *c).completed for c in signs)
    beyond = {c: corner_run(1.02, *c) for c in signs}
    failed = {c: o.failure.kind for c, o in beyond.items() if not o.completed}
    # the (+, +) corner: the landing spoke strikes a nose; short rises: their orbit stalls
    assert {failed.get((1, 1, s)) for s in (-1, 1)} == {"nose_hit"}
    assert {failed.get((-1, t, s)) for t in (-1, 1) for s in (-1, 1)} == {"stalled"}
