"""Every manipulator's own parts on real links and pivots: link length, back stop, palm mass,
link mass and pivot friction torque, each palm its own mechanism (docs/physics.md, section 2.1).

Independent numbers: the stage map written out here from Lagrange's equation of palm + links +
stuck object (generalized mass (m + M + J) l^2, J = n m_l / 3 for uniform rods; weight
(m + M + n m_l / 2) g l sin th; Coulomb work tau (a + b)), palm by palm."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from pdm_design.scenes.manipulators.model import Links, Pivots
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.scenes.manipulators.sim.geometry import Parts
from pdm_design.sim.core import SimulationRefused
from pdm_design.spec.loader import load_spec

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "problems" / "paper_manipulators.toml"
N_LINKS = 2


def real(spec, *, link_mass=0.5, torque=0.2, damping=0.0, mu=1.5):
    scene = dataclasses.replace(spec.scene, links=Links(mass=link_mass, count=N_LINKS),
                                pivots=Pivots(friction_torque=torque, damping=damping))
    return dataclasses.replace(scene, palm=dataclasses.replace(scene.palm, friction=mu))


def stage_map(rec_prev_speed, a, b, l, g, m, palm, link, torque):
    """Landing speed and handover speed on one palm from the previous handover speed s:
    momentum along t(-a) kept by object + palm + links (the links' inertia felt as J), then the
    energy balance of the carry from -a to b."""
    j = N_LINKS * link / 3.0
    inertia = m + palm + j
    u = m * rec_prev_speed * math.cos(a + b) / inertia
    weight = m + palm + N_LINKS * link / 2.0
    v2 = u * u + (2.0 * weight * g * l * (math.cos(a) - math.cos(b))
                  - 2.0 * torque * (a + b)) / inertia
    return u, math.sqrt(v2)


def test_each_palm_its_own_mass_links_and_friction_is_its_own_stage_map():
    spec = load_spec(PAPER)
    design = spec.design_at()
    scene = real(spec)
    m, g, l = scene.body.mass, scene.gravity, design.link_length
    palms = (0.1, 0.13, 0.08, 0.11, 0.1)
    links = (0.5, 0.7, 0.3, 0.55, 0.45)
    torques = (0.2, 0.05, 0.35, 0.0, 0.25)
    parts = Parts(palm_mass=palms, link_mass=links, pivot_friction=torques)
    result = simulate_manipulators(scene, design, stages=5, accuracy="precise", parts=parts)
    assert result.outcome.completed and not any(st["slipped"] for st in result.stages)
    a, b = design.alpha, design.beta
    for k in range(1, 5):
        s = result.stages[k - 1]["handover_speed"]
        u, v = stage_map(s, a, b, l, g, m, palms[k], links[k], torques[k])
        assert result.stages[k]["landing_speed"] == pytest.approx(u, rel=1e-12)
        if k < 4:  # (the last palm carries the object to beta: no handover)
            assert result.stages[k]["handover_speed"] == pytest.approx(v, rel=1e-9)
    # and the row as a whole differs from the design's: the parts are not ignored
    nominal = simulate_manipulators(scene, design, stages=5, accuracy="precise")
    assert abs(nominal.stages[2]["handover_speed"] - result.stages[2]["handover_speed"]) > 1e-3


def test_a_longer_link_on_real_links_lands_where_the_geometry_says():
    """Palm 3's link 2 cm longer: it rests lower, so palm 2 hands over at cos th = (y of palm 3's
    top - y of pivot 2) / l past beta, and palm 3's carry is its own (longer link, heavier rods:
    uniform rods of the same section, mass proportional to length)."""
    spec = load_spec(PAPER)
    design = spec.design_at()
    scene = real(spec, torque=0.1)
    m, g, l, a, b = scene.body.mass, scene.gravity, design.link_length, design.alpha, design.beta
    palm = m / design.mass_ratio
    long_l = l + 0.02
    lengths = (l, l, long_l, l)
    link3 = 0.5 * long_l / l
    parts = Parts(link_length=lengths, link_mass=(0.5, 0.5, link3, 0.5))
    result = simulate_manipulators(scene, design, stages=4, accuracy="precise", parts=parts)
    assert result.outcome.completed
    pitch_y = l * (math.cos(a) - math.cos(b))
    top3 = -2 * pitch_y + long_l * math.cos(a)  # palm 3's resting top, pivot 2 at -pitch_y
    theta = math.acos((top3 + pitch_y) / l)
    assert result.stages[1]["handover_angle"] == pytest.approx(theta, rel=1e-12)
    # palm 2's speed at theta (its own carry, the design's parts)
    u2 = result.stages[1]["landing_speed"]
    inertia = m + palm + N_LINKS * 0.5 / 3.0
    weight = m + palm + N_LINKS * 0.5 / 2.0
    v2 = u2 * u2 + (2 * weight * g * l * (math.cos(a) - math.cos(theta))
                    - 2 * 0.1 * (a + theta)) / inertia
    s2 = result.stages[1]["handover_speed"]
    assert s2 == pytest.approx(math.sqrt(v2), rel=1e-9)
    # palm 3: landing along t(-a) at s2 cos(a + theta), then its longer, heavier links
    j3, w3 = N_LINKS * link3 / 3.0, N_LINKS * link3 / 2.0
    u3 = m * s2 * math.cos(a + theta) / (m + palm + j3)
    assert result.stages[2]["landing_speed"] == pytest.approx(u3, rel=1e-12)
    # palm 3 hands over to palm 4 (nominal) where its object comes down to palm 4's top
    top4 = -3 * pitch_y + l * math.cos(a)
    theta3 = math.acos((top4 + 2 * pitch_y) / long_l)
    v3 = u3 * u3 + (2 * (m + palm + w3) * g * long_l * (math.cos(a) - math.cos(theta3))
                    - 2 * 0.1 * (a + theta3)) / (m + palm + j3)
    assert result.stages[2]["handover_speed"] == pytest.approx(math.sqrt(v3), rel=1e-9)


def test_parts_as_designed_on_real_links_change_nothing():
    spec = load_spec(PAPER)
    design = spec.design_at()
    scene = real(spec)
    palm = scene.body.mass / design.mass_ratio
    built = Parts(link_length=(design.link_length,) * 4, back_stop=(design.alpha,) * 4,
                  link_mass=(0.5,) * 4, pivot_friction=(0.2,) * 4)
    a = simulate_manipulators(scene, design, stages=4)
    b = simulate_manipulators(scene, design, stages=4, parts=built)
    assert a.stages == b.stages
    c = simulate_manipulators(scene, design, stages=4, parts=Parts(palm_mass=(palm,) * 4))
    assert np.allclose([s["handover_speed"] for s in c.stages[:3]],
                       [s["handover_speed"] for s in a.stages[:3]], rtol=1e-14, atol=0.0)


def test_link_mass_and_friction_parts_on_a_plain_scene_make_it_real():
    """The paper's scene with one palm's links given a mass: that palm alone is heavier."""
    spec = load_spec(PAPER)
    design = spec.design_at()
    scene = dataclasses.replace(spec.scene, palm=dataclasses.replace(spec.scene.palm,
                                                                     friction=1.5))
    m, g, l, a, b = scene.body.mass, scene.gravity, design.link_length, design.alpha, design.beta
    palm = m / design.mass_ratio
    parts = Parts(link_mass=(0.0, 0.4, 0.0, 0.0), pivot_friction=(0.0, 0.0, 0.3, 0.0))
    result = simulate_manipulators(scene, design, stages=4, accuracy="precise", parts=parts)
    assert result.outcome.completed
    for k, (link, torque) in enumerate(((0.4, 0.0), (0.0, 0.3)), start=1):
        u, v = stage_map(result.stages[k - 1]["handover_speed"], a, b, l, g, m, palm, link,
                         torque)
        assert result.stages[k]["handover_speed"] == pytest.approx(v, rel=1e-9)


@pytest.mark.parametrize("field,value", [("link_mass", -0.1), ("pivot_friction", -1.0)])
def test_negative_link_mass_or_friction_parts_are_refused(field, value):
    spec = load_spec(PAPER)
    with pytest.raises(SimulationRefused, match=field):
        simulate_manipulators(real(spec), spec.design_at(), stages=2,
                              parts=Parts(**{field: (0.5, value)}))
