"""Tolerances of the built device's links and pivots (docs/tolerances.md): link_mass and
pivot_friction per part or per lot, every part on real links in the vectorised map and in the
event simulator, build by build; the yield of a one-quantity interval is its exact probability.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar
from scipy.special import ndtr

from pdm_design.scenes.manipulators.tolerances import simulate_build
from pdm_design.spec.loader import load_spec
from pdm_design.tolerances import Tolerance, Tolerances, run_builds
from pdm_design.tolerances.draw import draw
from pdm_design.tolerances.yield_ import yield_of

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT / "problems" / "manipulators_real_links.toml"
# manipulators_real_links.toml's optimum (pdm-design optimize, maximise the pivot tolerance)
OPTIMUM = {"alpha": 0.1215629877192597, "beta": 0.4573079775884297}


@pytest.fixture(scope="module")
def real():
    spec = load_spec(REAL)
    return spec.scene, spec.design_at(OPTIMUM)


PARTS = Tolerances((
    Tolerance("pivot_x", "each", 0.1), Tolerance("pivot_y", "each", 0.1),
    Tolerance("link_length", "each", 0.02), Tolerance("back_stop", "each", 0.02),
    Tolerance("palm_mass", "each", 0.01), Tolerance("link_mass", "each", 0.15),
    Tolerance("pivot_friction", "each", 0.3), Tolerance("friction", "lot", 0.03),
    Tolerance("feed_x", "lot", 0.3),
))


def test_map_and_simulator_agree_build_by_build_on_real_links(real):
    scene, design = real
    # a grippier palm (mu 1.5): the optimum's binding slip margins left to the pivots and stops
    scene = dataclasses.replace(scene, palm=dataclasses.replace(scene.palm, friction=1.5))
    stages, builds = 6, 150
    dev = draw(PARTS, builds, stages, seed=5, scene=scene)
    out = run_builds(scene, design, dev, stages)
    closed = np.flatnonzero(out.closed_form)
    assert len(closed) > 100 and "" in set(out.failure[closed])
    # the map's tip onsets are the simulator's to follow (the object rocks from there): the
    # simulator meets each onset the map predicts
    handed = np.flatnonzero(~out.closed_form)
    assert len(handed) >= 1 and set(out.failure[handed]) == {"tip"}
    for i in handed:
        one = {k: v[i:i + 1] for k, v in dev.items()}
        run = simulate_build(scene, design, one, stages, accuracy="precise")
        assert out.min_margin[i] < 0 and any(e.kind == "rock" for e in run.events), i
    # torques drawn below 0 are taken at 0 by both (the sample holds builds that have them)
    assert (dev["pivot_friction"] < -0.2).any(axis=1)[closed].sum() > 10
    for i in closed:
        one = {k: v[i:i + 1] for k, v in dev.items()}
        sim = simulate_build(scene, design, one, stages, accuracy="precise").outcome
        name = "" if sim.completed else sim.failure.kind
        assert (sim.stages_passed, name) == (out.stages_passed[i], out.failure[i]), i
        assert (out.min_margin[i] < 0) == (name != "")


def test_link_mass_and_friction_parts_move_the_map_as_the_simulator(real):
    """One heavy link pair and one stiff pivot: the map's verdict follows them (a stall)."""
    scene, design = real
    stages = 4
    dev = {"link_mass": np.array([[0.0, 0.0, 0.0, 0.0], [0.0, 3.0, 0.0, 0.0]]),
           "pivot_friction": np.array([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]])}
    out = run_builds(scene, design, dev, stages)
    assert out.failure[0] == "" and out.stages_passed[0] == stages
    for i in range(2):
        sim = simulate_build(scene, design, {k: v[i:i + 1] for k, v in dev.items()}, stages,
                             accuracy="precise").outcome
        name = "" if sim.completed else sim.failure.kind
        assert sim.stages_passed == out.stages_passed[i]
        assert name == out.failure[i] or not out.closed_form[i]  # (then the simulator's word)
        assert (name == "") == (i == 0)


def _first_stall_torque(scene, design):
    """The pivot friction torque (all manipulators' the same: a lot) above which palm 1 cannot
    carry the object from -a to beta, from Lagrange's equation of palm + two rods + object:
    v(th)^2 = u^2 + [2 (m + M + m_l) g l (cos a - cos th) - 2 tau (a + th)] / (m + M + 2 m_l / 3)
    after a plastic landing u = m V . t(-a) / (m + M + 2 m_l / 3); the carry stalls when the
    smallest v^2 on [-a, beta] reaches 0 (found by a bounded scalar minimisation)."""
    m, g, l = scene.body.mass, scene.gravity, design.link_length
    palm, ml = m / design.mass_ratio, scene.links.mass
    a, b = design.alpha, design.beta
    inertia, weight = m + palm + 2 * ml / 3, m + palm + ml
    (_, y0), (vx, vy) = scene.initial.position, scene.initial.velocity
    fall = math.sqrt(vy * vy + 2 * g * (y0 - l * math.cos(a)))
    u = m * (vx * math.cos(a) - fall * math.sin(a)) / inertia

    def lowest(tau):
        def v2(th):
            return u * u + (2 * weight * g * l * (math.cos(a) - math.cos(th))
                            - 2 * tau * (a + th)) / inertia
        return minimize_scalar(v2, bounds=(-a, b), method="bounded",
                               options={"xatol": 1e-12}).fun

    return brentq(lowest, 0.0, 50.0, xtol=1e-12)


@pytest.mark.parametrize("distribution, t", [("normal", 9.0), ("uniform", 10.0)])
def test_yield_of_a_pivot_friction_lot_is_its_exact_probability(real, distribution, t):
    """One stage, only the lot's pivot friction varies: a torque drawn below 0 is taken at 0
    (a frictionless bearing, which carries the object on), and the build fails above the stall
    torque, so the yield is the probability of the deviation lying below tau_stall - tau_0."""
    scene, design = real
    tau0 = scene.pivots.friction_torque
    stall = _first_stall_torque(scene, design)
    low, high = -tau0, stall - tau0
    assert -t < low < 0.0 < high < t  # (a tenth of the builds or more have a torque below 0)
    if distribution == "normal":
        exact = ndtr(high / (t / 3))
    else:
        exact = (high + t) / (2 * t)
    tols = Tolerances((Tolerance("pivot_friction", "lot", t, 1.0, distribution),))
    r = yield_of(scene, design, tols, builds=20_000, stages=1, seed=2, confirm=0, scales=())
    assert r.ci_low <= exact <= r.ci_high
    assert r.ci_high - r.ci_low < 0.02
    assert set(r.failures) == {"stall"}


def test_a_palm_that_friction_can_hold_short_of_its_front_stop_is_left_to_the_simulator(real):
    """Palm 1's friction torque at or beyond what its empty weight turns at the handover angle,
    (M + 2 m_l / 2) g l sin(theta): it could stop past the handover, held there, not at its
    front stop where the map takes parked palms, so the map leaves the build to the simulator
    (a conservative rule: here the palm's speed carries it to its stop all the same). Just
    below that torque the map judges the build itself, as the simulator does."""
    scene, design = real
    m = scene.body
    weight = (m.mass / design.mass_ratio + scene.links.mass) * scene.gravity * design.link_length
    held = weight * math.sin(design.beta) - scene.pivots.friction_torque  # (a deviation)
    dev = {"pivot_friction": np.array([[held * 1.001, 0.0, 0.0], [held * 0.999, 0.0, 0.0]])}
    out = run_builds(scene, design, dev, 3)
    assert list(out.closed_form) == [False, True]
    for i in range(2):
        sim = simulate_build(scene, design, {"pivot_friction": dev["pivot_friction"][i:i + 1]},
                             3, accuracy="precise")
        assert sim.outcome.completed and out.failure[i] == "" and out.stages_passed[i] == 3
        assert [e.after["theta"] for e in sim.events
                if e.kind == "front_stop" and e.stage == 1] == [scene.palm.front_stop]
