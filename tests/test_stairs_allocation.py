"""Stairs lots in the worst-case allocation (docs/optimizer.md section 4a, "Stairs: restitution,
friction, launch speed"): the allocated box of restitution, friction and launch speed, alone and
with the steps' rise and tread, holds in the event simulator at every corner pattern of the steps
with every sign corner of the lots, and a larger box does not; a given value is a fixed
half-width; the exact nose rows refuse what they do not bound."""

import itertools
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from pdm_design.formulation.common import DEFAULT_BACKOFF
from pdm_design.scenes.stairs import physics as phys
from pdm_design.scenes.stairs.tolerances import simulate_build
from pdm_design.solve import optimize
from pdm_design.spec import load_spec
from pdm_design.verify.tolerance import corner_patterns

ROOT = Path(__file__).resolve().parent.parent
FRICTIONLESS = (ROOT / "problems" / "stairs_design.toml").read_text().split("[expect]")[0]
# the paper's ball with friction and backspin, launch speed and landing place free
PAPER_FRICTION = (ROOT / "problems" / "paper_stairs_friction.toml").read_text() \
    .split("[expect]")[0]
FRICTION = PAPER_FRICTION.replace(
    "launch_speed = 3.0      # m/s (V0)",
    "launch_speed = { min = 0.5, max = 4.0, initial = 3.0 }\n"
    "landing_offset = { min = 0.0, max = 3.0, initial = 1.0 }") + \
    "\n[objective]\nmax_offset_tolerance = 1.0\n"
STEPS = ("rise", "tread")


def _spec(tmp_path, base, tolerances, name="spec.toml"):
    path = tmp_path / name
    path.write_text(base + "\n[tolerances]\n" + tolerances + "\n")
    return load_spec(path)


def _solved(tmp_path, base, tolerances, status="optimal"):
    spec = _spec(tmp_path, base, tolerances)
    result = optimize(spec)
    assert result.status.value == status, result.status
    return spec, result


def _builds(spec, result, scale):
    """Every corner pattern of the steps' box with every sign corner of the lots, the box
    `scale` times the answer's: (name, deviations)."""
    half = {e["quantity"]: scale * e["value"] for e in result.tolerances}
    lots = [q for q in half if q not in STEPS]
    stages = spec.verification.stages
    for name, signs in corner_patterns(stages):
        for corner in itertools.product((1.0, -1.0), repeat=len(lots)):
            yield f"{name} {corner}", {
                "rise": [sr * half.get("rise", 0.0) for sr, _ in signs],
                "tread": [st * half.get("tread", 0.0) for _, st in signs],
                **{q: s * half[q] for q, s in zip(lots, corner, strict=True)}}


def _failures(spec, result, scale):
    """The builds of `_builds` that fail in the event simulator, or whose first impact does not
    end rolling (a `slip` event: the model's condition first_impact_friction)."""
    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    failed = []
    for name, deviations in _builds(spec, result, scale):
        run = simulate_build(spec.scene, design, deviations, spec.verification.stages)
        if not run.outcome.completed:
            failed.append((name, run.outcome.failure.kind))
        elif any(e.kind == "slip" for e in run.events):
            failed.append((name, "slip"))
    return failed


CASES = {
    "restitution": (FRICTIONLESS, "restitution = { allocate = true }"),
    "launch_speed": (FRICTIONLESS, "launch_speed = { allocate = true }"),
    "frictionless together": (FRICTIONLESS, "rise = { allocate = true }\n"
                              "tread = { allocate = true, weight = 0.5 }\n"
                              "restitution = { allocate = true, weight = 4 }\n"
                              "launch_speed = { allocate = true, weight = 0.5 }\n"
                              "launch_x = { allocate = true }"),
    "friction": (FRICTION, "friction = { allocate = true }"),
    "friction together": (FRICTION, "rise = { allocate = true }\n"
                          "tread = { allocate = true }\n"
                          "friction = { allocate = true, weight = 0.1 }\n"
                          "restitution = { allocate = true, weight = 4 }\n"
                          "launch_speed = { allocate = true }"),
}


@pytest.fixture(scope="module", params=list(CASES))
def case(request, tmp_path_factory):
    base, tolerances = CASES[request.param]
    return request.param, *_solved(tmp_path_factory.mktemp("case"), base, tolerances)


def test_every_corner_of_the_box_passes(case):
    name, spec, result = case
    shares = {t.quantity: min(u.weight for u in spec.tolerances) / t.weight
              for t in spec.tolerances}
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    assert set(value) == set(shares)
    s = max(value.values())
    for q, share in shares.items():  # the weights' proportions
        assert value[q] == pytest.approx(s * share, rel=1e-12)
        assert value[q] > 0.0
    assert _failures(spec, result, 1.0) == []


# How much larger: the smooth nose rows ask up to a radius more than the disc-to-corner contact
# (docs/optimizer.md section 2), and the paper's friction ball has a radius of 0.5 m.
LARGER = {"friction": 1.2, "friction together": 2.0}


def test_a_larger_box_fails(case):
    name, spec, result = case
    failed = _failures(spec, result, LARGER.get(name, 1.5))
    assert failed
    if name == "friction":  # only the low friction, where the first impact slides
        assert all(build.endswith("(-1.0,)") for build, _ in failed)


def test_friction_alone_is_the_first_impact_demand(tmp_path):
    """A fixed design (the paper's, launched at 3 m/s) allocating the friction alone: every row
    but first_impact_friction is free of it, so the tolerance is mu minus the demand of the first
    impact, a closed form (docs/physics.md: the slip |v0 + r omega0| needs an impulse
    m J |slip| / (J + m r^2) against the normal one m (1 + eps) sqrt(2 g h0)). Just beyond
    it the first impact slides."""
    spec, result = _solved(tmp_path, PAPER_FRICTION + "\n[objective]\n"
                           "max_offset_tolerance = 1.0\n", "friction = { allocate = true }",
                           status="evaluated")  # no design variable: the box alone
    ball, h0 = spec.scene.ball, spec.scene.initial.drop_height
    slip = abs(3.0 + ball.radius * spec.scene.initial.spin)
    demand = slip * ball.inertia / (ball.inertia + ball.mass * ball.radius**2) / (
        1.8 * math.sqrt(2 * 9.81 * h0))
    # every margin row is met with the solver's backoff, DEFAULT_BACKOFF of its scale (mu),
    # to IPOPT's tolerance (1e-8 of the row)
    held = 0.5 - demand - DEFAULT_BACKOFF * 0.5
    assert result.tolerances[0]["value"] == pytest.approx(held, abs=2e-8)
    assert result.tolerances[0]["value"] < 0.5 - demand
    assert _failures(spec, result, 1.0) == []
    assert {kind for _, kind in _failures(spec, result, 1.01)} == {"slip"}


def test_restitution_widens_every_landing_the_far_way(tmp_path):
    """The far end of the restitution is the higher one: every flight is longer (the simulator,
    on the stairs_design optimum, lands each bounce further than the nominal ball)."""
    spec, result = _solved(tmp_path, FRICTIONLESS, "restitution = { allocate = true }")
    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    t = result.tolerances[0]["value"]
    stages = spec.verification.stages
    runs = {s: simulate_build(spec.scene, design, {"restitution": s * t}, stages)
            for s in (-1.0, 0.0, 1.0)}
    places = {s: [r["landing_x"] for r in run.stages] for s, run in runs.items()}
    for k in range(1, stages):
        assert places[-1.0][k] < places[0.0][k] < places[1.0][k]


def test_given_lots_are_fixed_half_widths(tmp_path):
    """restitution, friction and launch speed given as values while the steps are allocated:
    the steps' box shrinks below the one without them, and the simulator passes its corners with
    the lots at either end."""
    _, alone = _solved(tmp_path, FRICTION, "rise = { allocate = true }\n"
                       "tread = { allocate = true }")
    spec, result = _solved(tmp_path, FRICTION, "rise = { allocate = true }\n"
                           "tread = { allocate = true }\nrestitution = { value = 0.002 }\n"
                           "friction = { value = 0.05 }\nlaunch_speed = { value = 0.01 }")
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    assert value["restitution"] == 0.002 and value["friction"] == 0.05
    assert value["launch_speed"] == 0.01
    assert 0.0 < result.tolerance["rise"] < alone.tolerance["rise"]
    assert _failures(spec, result, 1.0) == []


def test_optimize_verifies_the_lots_corners(tmp_path):
    path = tmp_path / "lots.toml"
    path.write_text(FRICTION + "\n[tolerances]\nrise = { allocate = true }\n"
                    "tread = { allocate = true }\nfriction = { allocate = true, weight = 0.1 }\n"
                    "launch_speed = { allocate = true }\n")
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path),
                          "--format", "json"], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert doc["verification"]["passed"]
    # nominal, the 12 step patterns x 4 sign corners of the two lots, 16 random builds
    assert doc["verification"]["samples"] == 1 + 12 * 4 + 16


@pytest.mark.parametrize("quantity", ["restitution", "launch_speed"])
def test_the_exact_nose_rows_refuse_the_orbit_lots(tmp_path, quantity):
    path = tmp_path / "exact.toml"
    required = FRICTIONLESS.replace("riser_clearance = 0.02",
                                    "riser_clearance = 0.02\nnose_clearance = 0.01")
    path.write_text(required + "\n[tolerances]\nrise = { allocate = true }\n"
                    f"{quantity} = {{ value = 0.001 }}\n")
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 2 and f"tolerances.{quantity}" in run.stderr
    assert "exact nose rows" in run.stderr and "Traceback" not in run.stderr


def test_the_rolling_row_is_the_simulators_test():
    """first_impact_friction's demand is the simulator's own: at mu just above the closed-form
    demand the first impact rolls, just below it slides (physics.stairs.rolling_impulse_ratio
    against sim.stairs.impact_map)."""
    from pdm_design.scenes.stairs.sim.maps import impact_map

    r, m, J, eps, v0, spin, vy = 0.5, 0.283, 0.035, 0.8, 3.0, 0.5, -math.sqrt(2 * 9.81)
    demand = phys.rolling_impulse_ratio(v0, spin, vy, eps, radius=r, mass=m, inertia=J)
    assert not impact_map(v0, vy, spin, eps, demand * (1 + 1e-9), r, m, J).slipped
    assert impact_map(v0, vy, spin, eps, demand * (1 - 1e-9), r, m, J).slipped


def _stairs_times(k):
    """problems/stairs_design.toml with every length times k and every speed times sqrt(k):
    the same stairs in units of h0."""
    r = math.sqrt(k)
    text = FRICTIONLESS.replace("radius = 0.05 ", f"radius = {0.05 * k!r} ").replace(
        "drop_height = 1.0 ", f"drop_height = {k!r} ")
    return text.replace(
        "launch_speed = { min = 0.5, max = 3.0, initial = 2.0 }",
        f"launch_speed = {{ min = {0.5 * r!r}, max = {3.0 * r!r}, initial = {2.0 * r!r} }}"
    ).replace("landing_offset = { min = 0.0, max = 3.0, initial = 0.8 }",
              f"landing_offset = {{ min = 0.0, max = {3.0 * k!r}, initial = {0.8 * k!r} }}")


def test_a_restitution_box_is_the_same_at_any_size(tmp_path):
    """The same stairs at any size have the same restitution tolerance (a ratio): the NLP's
    rows and objective are pure numbers (docs/optimizer.md sections 4, 4a)."""
    assert _stairs_times(1.0) == FRICTIONLESS
    at = {k: _solved(tmp_path, _stairs_times(k), "restitution = { allocate = true }")[1]
          .tolerances[0]["value"] for k in (1.0, 1e-4, 1e4)}
    assert at[1e-4] == pytest.approx(at[1.0], rel=1e-7)
    assert at[1e4] == pytest.approx(at[1.0], rel=1e-7)
