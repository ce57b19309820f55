"""Worst-case allocation on the device as built (docs/optimizer.md section 4a): link masses,
pivot friction torques, palm and object masses with real links and pivot friction. The ends of
the carry's effective terms are exact (against physics.carry_terms over the box); the allocated
box holds in the event simulator at every corner pattern with every sign corner of the others
(per part: all high, all low, and palm by palm alternating) and is not vacuous (a larger box
fails, as the simulator says)."""

import dataclasses
import itertools
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pdm_design.api import optimize
from pdm_design.formulation.common import DEFAULT_BACKOFF
from pdm_design.scenes.manipulators import physics as phys
from pdm_design.scenes.manipulators.formulation import _Model, carry_box
from pdm_design.scenes.manipulators.formulation.rows import MASS_KEPT
from pdm_design.scenes.manipulators.tolerances import simulate_build
from pdm_design.spec import load_spec
from pdm_design.verify.tolerance import corner_patterns, random_builds

ROOT = Path(__file__).resolve().parent.parent
BASE = (ROOT / "problems" / "manipulators_real_links.toml").read_text().split("[expect]")[0]
PER_PART = ("palm_mass", "link_mass", "pivot_friction", "back_stop")
# weights: a share of each quantity that matters next to the pivots' (+-29 mm: +-0.29 N m of
# friction, +-73 g of link and object, +-15 g of palm)
WEIGHTS = {"link_mass": 0.4, "pivot_friction": 0.1, "object_mass": 0.4, "palm_mass": 2.0}
PIVOTS = "pivot_x = { allocate = true }\npivot_y = { allocate = true }\n"


def _spec(tmp_path, extra, name="spec.toml", base=BASE):
    path = tmp_path / name
    path.write_text(base + "\n[tolerances]\n" + extra)
    return load_spec(path)


def _line(q, weight=1.0):
    return f"{q} = {{ allocate = true, weight = {weight} }}\n"


def _deviations(spec, value, scale, signs, lot_signs, alternate=False):
    """One build: pivots by the pattern's signs, the others at their sign (per part: every
    manipulator alike, or alternately heavy and light)."""
    stages = spec.verification.stages
    dev = {"pivot_x": np.array([[sx * scale * value.get("pivot_x", 0.0) for sx, _ in signs]]),
           "pivot_y": np.array([[sy * scale * value.get("pivot_y", 0.0) for _, sy in signs]])}
    flip = np.array([(-1.0) ** k if alternate else 1.0 for k in range(stages)])
    for q, sign in lot_signs.items():
        t = sign * scale * value[q]
        dev[q] = (t * flip)[None, :] if q in PER_PART else np.array([t])
    return dev


def _builds(spec, value, scale, alternate=False):
    """Every corner pattern of the pivots (the pivots exact: one) with every sign corner of the
    other quantities: (name, deviations)."""
    stages = spec.verification.stages
    others = [q for q in value if q not in ("pivot_x", "pivot_y")]
    patterns = corner_patterns(stages) if "pivot_x" in value else [("exact", [(0, 0)] * stages)]
    for name, signs in patterns:
        for lots in itertools.product((1.0, -1.0), repeat=len(others)):
            lot_signs = dict(zip(others, lots))
            yield f"{name} {lot_signs}", _deviations(spec, value, scale, signs, lot_signs,
                                                     alternate)


def _design(spec, result):
    return spec.design_at({n: result.analysis.design[n] for n in spec.free_variables})


def _failures(spec, result, scale, alternate=False, first=False):
    design = _design(spec, result)
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    out = []
    for name, dev in _builds(spec, value, scale, alternate):
        run = simulate_build(spec.scene, design, dev, spec.verification.stages)
        if not run.outcome.completed:
            out.append((name, run.outcome.failure.kind))
            if first:
                break
    return out


# -- the effective terms' ends are exact --------------------------------------------------------

@pytest.mark.parametrize("inertia", [None, 0.4])
def test_effective_ends_are_the_extremes_over_the_box(inertia):
    """q_e, g_e and f of every build in the box (physics.carry_terms at random points and at
    every corner) lie within carry_box.terms' ends, and the ends are attained. inertia 0.4 kg m^2
    a link of 0.1 kg on 2 m makes J > W: g_e then falls with the link mass (the other sign)."""
    spec = load_spec(ROOT / "problems" / "manipulators_real_links.toml")
    scene = spec.scene
    if inertia is not None:
        scene = dataclasses.replace(scene, links=dataclasses.replace(scene.links, mass=0.1,
                                                                     inertia=inertia))
    values = {"alpha": 0.15, "beta": 0.5, "link_length": 2.0, "mass_ratio": 10.0,
              "first_pivot_x": 0.0, "first_pivot_y": 0.0}
    box = {"object_mass": 0.3, "palm_mass": 0.04, "link_mass": 0.05, "pivot_friction": 0.3}
    ends = carry_box.terms(_Model(scene, values, 6), box)
    m0, M0, mu0, tau0 = 1.0, 0.1, scene.links.mass, scene.pivots.friction_torque

    def terms(m, M, mu, tau):
        mech = scene.mechanism(link_mass=mu, friction_torque=max(tau, 0.0))
        return phys.carry_terms(m / M, object_mass=m, gravity=9.81, link_length=2.0, **mech)

    half = [box[q] for q in carry_box.QUANTITIES]
    centre = [m0, M0, mu0, tau0]
    corners = np.array([terms(*(c + s * t for c, s, t in zip(centre, signs, half)))
                        for signs in itertools.product((-1.0, 1.0), repeat=4)])
    rng = np.random.default_rng(1)
    inside = np.array([terms(*(c + u * t for c, u, t in zip(centre, draw, half)))
                       for draw in rng.uniform(-1.0, 1.0, size=(2000, 4))])
    for i, name in enumerate(("q", "g", "f")):
        lo, hi = (float(v) for v in (getattr(ends, name)[0], getattr(ends, name)[-1]))
        assert lo == pytest.approx(corners[:, i].min(), rel=1e-12)
        assert hi == pytest.approx(corners[:, i].max(), rel=1e-12)
        assert np.all(inside[:, i] >= lo * (1 - 1e-12)) and np.all(inside[:, i] <= hi * (1 + 1e-12))
    rising = ends.g[-1] == pytest.approx(terms(m0 - 0.3, M0 - 0.04, mu0 + 0.05, tau0)[1])
    assert rising == (inertia is None)  # uniform rods: W = 3J/2 > J, g_e grows with the links


# -- one quantity alone -------------------------------------------------------------------------

@pytest.mark.parametrize("quantity, scale, sign, failure", [
    ("link_mass", 2.0, 1.0, "stall"),      # heavier links: more inertia than pull, and friction
    ("pivot_friction", 1.5, 1.0, "stall"),  # more friction: the carry stops short of the top
    ("object_mass", 1.5, -1.0, "stall"),    # a lighter object lands slower
])
def test_one_quantity_alone_holds_at_its_ends(tmp_path, quantity, scale, sign, failure):
    spec = _spec(tmp_path, _line(quantity))
    result = optimize(spec)
    assert result.status.value == "optimal"  # verified: the simulator ran both ends
    assert _failures(spec, result, 1.0) == []
    assert _failures(spec, result, 1.0, alternate=True) == []
    design = _design(spec, result)
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    dev = _deviations(spec, value, scale, [(0, 0)] * 6, {quantity: sign})
    run = simulate_build(spec.scene, design, dev, 6)
    assert not run.outcome.completed and run.outcome.failure.kind == failure


def test_palm_mass_alone_is_held_by_the_palms_keeping_a_mass(tmp_path):
    """On real links the speed rows allow any palm mass here too: the tolerance is the validity
    row's (1 - 1e-3) of the 0.1 kg palm (less the solver's backoff), the simulator passes both
    ends and palms alternately heavy and light, and 1.5 times it is a palm of negative mass
    (invalid_part)."""
    spec = _spec(tmp_path, _line("palm_mass"))
    result = optimize(spec)
    assert result.status.value == "optimal"
    # the row met with the solver's backoff (1e-6 of the row's scale, the palm's mass)
    kept = 0.1 * (1 - MASS_KEPT) - DEFAULT_BACKOFF * 0.1
    assert result.tolerances[0]["value"] == pytest.approx(kept, rel=1e-8)
    assert _failures(spec, result, 1.0) == []
    assert _failures(spec, result, 1.0, alternate=True) == []
    assert [kind for _, kind in _failures(spec, result, 1.5)] == ["invalid_part"]


# -- with the pivots ----------------------------------------------------------------------------

@pytest.mark.parametrize("quantity", ["link_mass", "pivot_friction", "object_mass", "palm_mass"])
def test_with_the_pivots_every_corner_passes(tmp_path, quantity):
    spec = _spec(tmp_path, PIVOTS + _line(quantity, WEIGHTS[quantity]))
    result = optimize(spec)
    assert result.status.value == "optimal"
    # the optimizer's verification: 12 pivot patterns x the quantity's 2 signs, and random builds
    assert result.verification["passed"]
    assert result.verification["samples"] == 12 * 2 + random_builds(16, 6) + 1  # + nominal
    assert _failures(spec, result, 1.0, alternate=quantity in PER_PART) == []
    # not vacuous: 3 times the box fails (the simulator's first failure: a skipped palm on an
    # alternating pattern; with link_mass 2.5 times passes, the tip onset there rocking back
    # since the simulator follows it; the NLP's slip rows hold where the simulator slides on)
    assert _failures(spec, result, 3.0, first=True)


@pytest.fixture(scope="module")
def every(tmp_path_factory):
    spec = _spec(tmp_path_factory.mktemp("every"),
                 PIVOTS + "".join(_line(q, w) for q, w in WEIGHTS.items()))
    return spec, optimize(spec)


def test_every_quantity_with_the_pivots(every):
    """All four with the pivots: the 12 pivot patterns x 16 sign corners pass (the optimizer's
    own verification, 192 + 16 random builds; and per part alternating here), twice fails."""
    spec, result = every
    assert result.status.value == "optimal"
    value = {e["quantity"]: e["value"] for e in result.tolerances}
    s = value["pivot_friction"]  # the smallest weight's tolerance is the scale
    for q, w in WEIGHTS.items():
        assert value[q] == pytest.approx(s * 0.1 / w, rel=1e-12)
    assert result.verification["passed"]
    assert result.verification["samples"] == 12 * 16 + random_builds(16, 6) + 1
    assert _failures(spec, result, 1.0, alternate=True) == []
    assert _failures(spec, result, 2.0, first=True)


# -- refused in words ---------------------------------------------------------------------------

@pytest.mark.parametrize("base, extra, key, words", [
    ((ROOT / "problems" / "manipulators_robust.toml").read_text().split("[expect]")[0],
     "link_mass = { allocate = true }\n", "tolerances.link_mass", "scene.links.mass > 0"),
    ((ROOT / "problems" / "manipulators_robust.toml").read_text().split("[expect]")[0],
     "pivot_friction = { allocate = true }\n", "tolerances.pivot_friction",
     "scene.pivots.friction_torque > 0"),
])
def test_refused_in_words(tmp_path, base, extra, key, words):
    path = tmp_path / "bad.toml"
    path.write_text(base + "\n[tolerances]\n" + extra)
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 2
    assert key in run.stderr and words in run.stderr and "Traceback" not in run.stderr


def test_verification_draws_a_part_quantity_palm_by_palm(tmp_path):
    """The optimizer's random builds draw a part's quantity for every manipulator on its own:
    three times the link-mass box puts some link below 0 kg in most builds (invalid_part),
    and each such build lists its six different link-mass deviations."""
    from pdm_design.verify.tolerance import verify_tolerance

    spec = _spec(tmp_path, _line("link_mass"))
    result = optimize(spec, verify=False)
    t = 3.0 * result.tolerances[0]["value"]
    box = verify_tolerance(spec, _design(spec, result), {"dx": 0.0, "dy": 0.0}, samples=8,
                           lots=[{"quantity": "link_mass", "value": t}])
    drawn = [(f["lots"]["link_mass"], f["failure"]) for f in box["failures"]
             if f["build"].startswith("random")]
    assert drawn and all(len(set(d)) == 6 and max(map(abs, d)) <= t for d, _ in drawn)
    negative = [why for d, why in drawn if min(d) < -spec.scene.links.mass]
    assert negative and all(why.startswith("invalid_part") for why in negative)


def _scaled(text, k):
    """The same device k times larger (lengths x k, speeds x sqrt k, torques x k: f / (g l)
    and every angle unchanged), the torque's weight / k so that its share is the same."""
    for key, value in (("width = 0.4 ", 0.4), ("height = 0.2 ", 0.2), ("width = 1.6 ", 1.6),
                       ("thickness = 0.05 ", 0.05), ("friction_torque = 0.2 ", 0.2),
                       ("link_length = 2.0 ", 2.0)):
        assert key in text
        text = text.replace(key, f"{key.split('=')[0]}= {value * k!r} ")
    text = text.replace("position = [-1.25, 3.05]", f"position = [{-1.25 * k!r}, {3.05 * k!r}]")
    return text.replace("velocity = [3.0, 0.0]", f"velocity = [{3.0 * k ** 0.5!r}, 0.0]")


@pytest.mark.parametrize("k", [100.0, 1e4])
def test_a_larger_device_gets_the_same_masses_and_k_times_the_torque(tmp_path, k):
    """Scale: the device k times larger is the same device in units of l and sqrt(g l), so the
    allocated masses are the same and the torque k times it (no size enters the bounds)."""
    lines = "".join(_line(q) for q in ("link_mass", "object_mass")) + _line("palm_mass", 5.0)
    one = optimize(_spec(tmp_path, lines + _line("pivot_friction"), "one.toml"), verify=False)
    big = optimize(_spec(tmp_path, lines + _line("pivot_friction", 1.0 / k), "big.toml",
                         base=_scaled(BASE, k)), verify=False)
    assert one.status.value == big.status.value == "optimal"
    small = {e["quantity"]: e["value"] for e in one.tolerances}
    for e in big.tolerances:
        factor = k if e["quantity"] == "pivot_friction" else 1.0
        assert e["value"] / factor == pytest.approx(small[e["quantity"]], rel=1e-6)


# -- the back stops on real links ---------------------------------------------------------------

@pytest.mark.parametrize("others, scale", [
    ("", 2.5),  # the simulator's first failure at 1.95 times (a tip), bisected once
    (_line("link_mass", 0.4) + _line("pivot_friction", 0.1), 2.5),  # 2.42 times (a stall)
])
def test_back_stops_on_real_links_hold_at_the_corners(tmp_path, others, scale):
    """The stops over [a_lo, a_hi] at the back stop's contact rows (carry_box.back_contact):
    every pivot pattern with the stops (and the others) all high, all low and palm by palm
    alternating passes; a larger box fails."""
    spec = _spec(tmp_path, PIVOTS + _line("back_stop", 10.0) + others)
    result = optimize(spec)
    assert result.status.value == "optimal" and result.verification["passed"]
    assert _failures(spec, result, 1.0, alternate=True) == []
    assert _failures(spec, result, scale, first=True)


def test_back_stops_alone_on_real_links_are_held_by_their_range(tmp_path):
    """Alone, the stops take the whole of alpha (the validity row back_stop_range: no stop
    beyond the vertical; the design moves alpha to it): both ends pass, 1.5 times fails."""
    spec = _spec(tmp_path, _line("back_stop"))
    result = optimize(spec)
    assert result.status.value == "optimal"
    t = result.tolerances[0]["value"]
    # alpha - t >= the solver's backoff (the row's scale is 1 rad)
    assert t == pytest.approx(result.analysis.design["alpha"] - DEFAULT_BACKOFF, abs=1e-8)
    assert _failures(spec, result, 1.0) == [] and _failures(spec, result, 1.0, alternate=True) == []
    assert _failures(spec, result, 1.5, first=True)
