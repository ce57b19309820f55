"""Spokes of their own lengths and the hub's mass in the robust NLP's box (spread.py): one
quantity against its closed form, the box of the problem (and a flight of stairs) at every
corner of the spokes on the step map and in the event simulator, failures a little beyond it,
and a hub mass that moves nothing refused in words."""

import itertools
import math

import numpy as np
import pytest

from pdm_design.errors import SpecError
from pdm_design.scenes.rimless_wheel import RimlessWheelDesign, formulation
from pdm_design.scenes.rimless_wheel.builds import build_outcome
from pdm_design.scenes.rimless_wheel.sim import simulate_rimless_wheel
from pdm_design.solve.optimize import optimize
from pdm_design.spec.loader import load_spec

RAMP = """
name = "leg_box_test"
[scene]
kind = "rimless_wheel"
ground = "{ground}"
friction = 1.0
[scene.wheel]
mass = 1.0
gyration = {gyration}
spoke_mass = {spoke_mass}
[initial]
speed = {speed}
[design]
spokes = 8
leg_length = 1.0
{design}
[objective]
max_offset_tolerance = 1.0
[tolerances]
{tolerances}
[verification]
stages = 20
"""


def spec_of(tmp_path, *, ground="ramp", gyration=0.1, spoke_mass=0.1, speed=1.0,
            design="slope = 0.06", tolerances="mass = { allocate = true }"):
    path = tmp_path / "spec.toml"
    path.write_text(RAMP.format(ground=ground, gyration=gyration, spoke_mass=spoke_mass,
                                speed=speed, design=design, tolerances=tolerances))
    return load_spec(path)


def allocated(result):
    return {e["quantity"]: e["value"] for e in result.tolerances}


def rows_at(spec, t):
    """{condition: its smallest slack / scale} of the NLP's inequality rows at a fixed design
    and tolerance scale t."""
    from pdm_design.formulation.common import assemble

    model, bounds, _ = formulation.build(spec)
    form = assemble(spec, model, key=repr((spec.source, t)), bounds=bounds)
    x = form.start_vector({})
    x[form.x_names.index("tolerance")] = t
    slack, scale, _, _ = (np.asarray(v).ravel() for v in form.evaluate(x, form.parameters()))
    out = {}
    for info, s, c in zip(form.conditions, slack, scale):
        if not info.equality and c != 0.0:
            out[info.name] = min(out.get(info.name, math.inf), s / c)
    return out


def test_the_hub_mass_alone_against_its_closed_form(tmp_path):
    """A fixed wheel on a shallow ramp, the hub's mass the only tolerance. k^2 = (M k_h^2 +
    S l^2/3) / (M + S) falls with M (k_h^2 < l^2/3), and the orbit's E*/rate = eta^2 2 sin a
    sin b / (1 - eta^2) - vers(b - a) rises with eta, so the heavy end stalls first: E* = 0 at
    eta_c^2 = v / (2 sin a sin b + v), v = vers(b - a); k_c^2 = 2 l^2 sin^2 a / (1 - eta_c)
    - l^2, M_c = S (l^2/3 - k_c^2) / (k_c^2 - k_h^2): the box is M_c - M."""
    spec = spec_of(tmp_path)
    n, leg, kh, ms, mass, beta = 8, 1.0, 0.1, 0.1, 1.0, 0.06
    alpha, s = math.pi / n, n * ms
    v = 2.0 * math.sin((beta - alpha) / 2) ** 2
    eta_c = math.sqrt(v / (2.0 * math.sin(alpha) * math.sin(beta) + v))
    k2_c = 2.0 * leg**2 * math.sin(alpha) ** 2 / (1.0 - eta_c) - leg**2
    closed = s * (leg**2 / 3.0 - k2_c) / (k2_c - kh**2) - mass
    assert 0.3 < closed < 1.0
    # the rows cross 0 at the closed form: over_the_top binds, everything else holds
    assert abs(rows_at(spec, closed)["over_the_top"]) < 1e-8
    assert min(rows_at(spec, closed).values()) > -1e-8
    result = optimize(spec)
    assert allocated(result)["mass"] == pytest.approx(closed, rel=1e-4)
    # the event simulator: the heavy hub's wheel rolls at the box's end and stalls beyond it
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=beta)

    def run(extra):
        import dataclasses

        scene = dataclasses.replace(spec.scene, wheel=dataclasses.replace(
            spec.scene.wheel, mass=mass + extra))
        return simulate_rimless_wheel(scene, design, stages=300).outcome

    assert run(0.999 * closed).completed and run(-0.999 * closed).completed
    beyond = run(1.05 * closed)
    assert not beyond.completed and beyond.failure.kind == "stalled"


def test_one_leg_length_for_every_spoke_of_a_point_mass(tmp_path):
    """A lot of leg_length on a point mass: eta = cos 2 alpha and the orbit in units of
    rate do not depend on l, so only the first stance feels it: E_0 = w0^2 - (2 g / l)
    vers(beta - alpha) > 0 iff l > 2 g vers(beta - alpha) / w0^2; the box is l - that."""
    spec = spec_of(tmp_path, gyration=0.0, spoke_mass=0.0, speed=1.0, design="slope = 0.1",
                   tolerances='leg_length = { allocate = true, applies_to = "lot" }')
    alpha = math.pi / 8
    closed = 1.0 - 2.0 * spec.scene.gravity * 2.0 * math.sin((0.1 - alpha) / 2) ** 2
    assert 0.1 < closed < 0.3
    assert allocated(optimize(spec))["leg_length"] == pytest.approx(closed, rel=1e-4)


def test_a_hub_mass_that_moves_nothing_is_refused_in_words(tmp_path):
    """No spoke mass: k^2 = k_h^2 at every hub mass, so no mass changes the motion (the
    event simulator agrees: the same run at a tenth and ten times the mass) and its box is
    unbounded: said so, not a number."""
    spec = spec_of(tmp_path, spoke_mass=0.0)
    with pytest.raises(SpecError, match="unbounded"):
        formulation.build(spec)
    design = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=0.06)
    import dataclasses

    runs = [simulate_rimless_wheel(dataclasses.replace(spec.scene, wheel=dataclasses.replace(
        spec.scene.wheel, mass=m)), design, stages=30).stages for m in (0.1, 10.0)]
    assert [r["speed_after"] for r in runs[0]] == pytest.approx(
        [r["speed_after"] for r in runs[1]], rel=1e-12)


def test_zero_spread_gives_the_box_rows(tmp_path):
    """The spread rows with spokes and hub exact are the slope (rise, tread) box's rows: the
    same smallest margin of every condition (the new forward row aside, which holds). One
    difference: the spread's bound of every stance is min(first stance, orbit) measured on
    the orbit's start speed; where the first stance is the lower (these stairs) its margin is
    that energy on the orbit's scale, not the first stance's own, so no larger."""
    for ground, design, box in (("ramp", "slope = 0.1", "slope = { allocate = true }"),
                                ("stairs", "rise = 0.1\nlanding_offset = 0.4",
                                 "rise = { allocate = true }\ntread = { allocate = true }")):
        plain = spec_of(tmp_path, ground=ground, design=design, speed=1.3, tolerances=box)
        spread = spec_of(tmp_path, ground=ground, design=design, speed=1.3,
                         tolerances=box + "\nleg_length = { value = 1e-300 }")
        a, b = rows_at(plain, 0.01), rows_at(spread, 0.01)
        for name, value in a.items():
            if ground == "stairs" and name == "over_the_top":
                assert 0.0 < b[name] < value
            elif name != "descends":
                assert b[name] == pytest.approx(value, rel=1e-9, abs=1e-12), (ground, name)


def corner_builds(spec, design, tol, scale, steps):
    """Every corner of the box on the step map: every spoke long or short (2^n, the spoke box
    times scale), every step's chord (and tread) low or high, the hub light or heavy, the
    start slow or fast. (failures, their kinds, the failing builds: (spoke lengths, the
    ground's signs, hub mass, start speed))."""
    n = design.spokes
    spokes = np.array(list(itertools.product((-1.0, 1.0), repeat=n))) * tol["leg_length"] * scale
    count, kinds, failing = 0, set(), []
    axes = ("slope",) if spec.scene.ground == "ramp" else ("rise", "tread")
    for signs in itertools.product((-1.0, 1.0), repeat=len(axes) + 2):
        *ground, mass, speed = signs
        b = len(spokes)
        dev = {"leg_length": np.tile(spokes, (1, steps // n + 1))[:, :steps],
               "mass": np.full(b, mass * tol.get("mass", 0.0)),
               "start_speed": np.full(b, speed * tol.get("start_speed", 0.0))}
        for q, sign in zip(axes, ground):
            dev[q] = np.full((b, steps), sign * tol[q])
        out = build_outcome(spec.scene, design, dev, steps)
        failed = out.stages_passed < steps
        count += int(failed.sum())
        kinds |= set(out.failure[failed])
        failing += [(design.leg_length + spokes[i], dict(zip(axes, ground)), dev["mass"][0],
                     dev["start_speed"][0], out.failure[i]) for i in np.flatnonzero(failed)]
    return count, kinds, failing


def replay(spec, design, tol, build, steps):
    """One corner build in the event simulator: its outcome."""
    import dataclasses

    lengths, ground, mass, speed, _ = build
    scene = dataclasses.replace(
        spec.scene, wheel=dataclasses.replace(spec.scene.wheel, mass=spec.scene.wheel.mass
                                              + mass),
        initial=dataclasses.replace(spec.scene.initial, speed=spec.scene.initial.speed
                                    + speed))
    errors = [{"step": k + 1, **{q: sign * tol[q] for q, sign in ground.items()}}
              for k in range(steps)]
    return simulate_rimless_wheel(scene, design, stages=steps, step_errors=errors,
                                  spoke_lengths=lengths).outcome


def random_builds_in_the_simulator(spec, design, tol, count, seed):
    """Uniform builds inside the box in the event simulator: every one completes."""
    rng = np.random.default_rng(seed)
    stages = spec.verification.stages
    axes = ("slope",) if spec.scene.ground == "ramp" else ("rise", "tread")
    import dataclasses

    for _ in range(count):
        lengths = 1.0 + rng.uniform(-1, 1, design.spokes) * tol["leg_length"]
        scene = dataclasses.replace(
            spec.scene, wheel=dataclasses.replace(
                spec.scene.wheel, mass=1.0 + rng.uniform(-1, 1) * tol["mass"]),
            initial=dataclasses.replace(spec.scene.initial, speed=spec.scene.initial.speed
                                        + rng.uniform(-1, 1) * tol["start_speed"]))
        errors = [{"step": k + 1, **{q: float(rng.uniform(-1, 1) * tol[q]) for q in axes}}
                  for k in range(stages)]
        run = simulate_rimless_wheel(scene, design, stages=stages, step_errors=errors,
                                     spoke_lengths=lengths)
        assert run.outcome.completed, run.outcome.failure


def fixed_design(result):
    return RimlessWheelDesign(**{k: v for k, v in result.design.items()
                                 if k in RimlessWheelDesign.VARIABLES and v is not None})


def test_the_problem_box_holds_at_every_corner_and_fails_just_beyond():
    """problems/rimless_wheel_leg_box.toml: all 2^8 spoke corners with every corner of the
    slope, the hub and the start hold for 200 steps (the rows bound every step, not only the
    20 verified); at 1.05 x the spoke box some stall; the event simulator agrees on a
    failing corner and runs random builds inside the box to the end."""
    spec = load_spec("problems/rimless_wheel_leg_box.toml")
    result = optimize(spec)
    tol = allocated(result)
    assert tol["leg_length"] > 0.03
    design = fixed_design(result)
    assert corner_builds(spec, design, tol, 1 - 1e-4, 200)[:2] == (0, set())
    count, kinds, failing = corner_builds(spec, design, tol, 1.05, 200)
    assert count > 0 and kinds == {"stalled"}
    for build in failing[::max(len(failing) // 3, 1)]:  # the event simulator agrees
        out = replay(spec, design, tol, build, 200)
        assert not out.completed and out.failure.kind == "stalled"
    random_builds_in_the_simulator(spec, design, tol, 8, seed=3)
    # the corners stand for the box: 5000 uniform builds inside it make the 200 steps too
    rng = np.random.default_rng(0)
    builds, steps = 5000, 200
    inside = {"leg_length": rng.uniform(-1, 1, (builds, steps)) * tol["leg_length"],
              "slope": rng.uniform(-1, 1, (builds, steps)) * tol["slope"],
              "mass": rng.uniform(-1, 1, builds) * tol["mass"],
              "start_speed": rng.uniform(-1, 1, builds) * tol["start_speed"]}
    assert (build_outcome(spec.scene, design, inside, steps).stages_passed == steps).all()


def test_a_stairs_box_of_spokes_and_hub(tmp_path):
    """Stairs (the rise and first foothold free), each spoke's length allocated, the hub's
    mass, every rise and tread and the start given: every corner holds over the 20 steps, and
    1.05 x the spoke box misses treads (the longest chords run the footholds off them)."""
    spec = spec_of(tmp_path, ground="stairs", gyration=0.2, spoke_mass=0.05, speed=1.3,
                   design="rise = { min = 0.01, max = 0.3, initial = 0.1 }\n"
                          "landing_offset = { min = 0.0, max = 0.7, initial = 0.4 }",
                   tolerances='leg_length = { allocate = true, applies_to = "each" }\n'
                              "mass = { value = 0.3 }\nstart_speed = { value = 0.05 }\n"
                              "rise = { value = 0.01 }\ntread = { value = 0.01 }")
    result = optimize(spec)
    tol = allocated(result)
    assert tol["leg_length"] > 0.005
    design = fixed_design(result)
    assert corner_builds(spec, design, tol, 1 - 1e-4, 20)[:2] == (0, set())
    count, kinds, failing = corner_builds(spec, design, tol, 1.05, 20)
    assert count > 0 and "missed_tread" in kinds
    for build in failing[::max(len(failing) // 3, 1)]:  # the event simulator agrees
        out = replay(spec, design, tol, build, 20)
        assert not out.completed and out.failure.kind == build[-1]
    random_builds_in_the_simulator(spec, design, tol, 6, seed=5)


@pytest.mark.parametrize("ground,tolerances,key", [
    ("ramp", "mass = { value = 1.0 }\nslope = { allocate = true }", "tolerances.mass.value"),
    ("ramp", "rise = { allocate = true }", "tolerances.rise"),
    ("stairs", "slope = { allocate = true }", "tolerances.slope"),
    ("ramp", "start_speed = { value = 1.5 }\nslope = { allocate = true }",
     "tolerances.start_speed.value"),
])
def test_allocations_the_rows_cannot_bound_are_refused(tmp_path, ground, tolerances, key):
    """A hub mass or start speed tolerance that reaches 0, a quantity of the other ground."""
    design = "slope = 0.1" if ground == "ramp" else "rise = 0.1"
    spec = spec_of(tmp_path, ground=ground, design=design, speed=1.3, tolerances=tolerances)
    with pytest.raises(SpecError, match=key.replace(".", r"\.")):
        formulation.build(spec)


def test_spokes_of_their_own_need_a_step_a_spoke(tmp_path):
    """The box's builds draw spoke j's length from step j's draw: stages >= spokes."""
    path = tmp_path / "few.toml"
    path.write_text(RAMP.format(ground="ramp", gyration=0.1, spoke_mass=0.1, speed=1.3,
                                design="slope = 0.1", tolerances="leg_length = { allocate = "
                                "true }").replace("stages = 20", "stages = 5"))
    with pytest.raises(SpecError, match="verification.stages"):
        formulation.build(load_spec(path))
