"""The palm's force on the stuck object on real links with pivot friction (docs/physics.md
section 2.1): the closed forms' tangential term A = l th'' - g sin th, friction / normal ratio
and lift-off capacity against the simulator's Lagrangian swing (sim.manipulators.phases), at
link lengths other than 1 m, where a friction term written without its 1 / l showed."""

import math

import numpy as np
import pytest

from pdm_design.scenes.manipulators import physics as phys
from pdm_design.scenes.manipulators.sim.phases import Swing, stuck_contact_force, swing_acceleration


def _case(rng):
    l = float(rng.uniform(0.05, 5.0))
    m, M, link = (float(x) for x in rng.uniform(0.05, 2.0, 3))
    tau = float(rng.uniform(0.0, 2.0))
    g = 9.81
    q_e, g_e, f = phys.carry_terms(m / M, object_mass=m, gravity=g, link_length=l,
                                   link_mass=link, friction_torque=tau)
    swing = Swing(inertia=m + M + link / 3, weight=m + M + link / 2, torque=tau, damping=0.0,
                  gravity=g, link_length=l)
    return l, g, g_e, f, swing


@pytest.mark.parametrize("seed", range(5))
def test_contact_force_matches_the_simulators_swing(seed):
    rng = np.random.default_rng(seed)
    for _ in range(40):
        l, g, g_e, f, swing = _case(rng)
        th = float(rng.uniform(-0.6, 1.2))
        v2 = float(rng.uniform(0.0, 0.9)) * g * l * math.cos(th)
        omega = math.sqrt(v2) / l  # forward: the friction torque opposes it
        thdd = swing_acceleration(th, omega, swing)
        friction, normal = stuck_contact_force(th, omega, thdd, gravity=g, link_length=l)
        along = phys.carry_along(th, gravity=g, carry_gravity=g_e, friction=f, link_length=l)
        assert along == pytest.approx(l * thdd - g * math.sin(th), rel=1e-12, abs=1e-12)
        ratio = phys.carry_force_ratio(th, v2, gravity=g, link_length=l, along=along)
        assert ratio == pytest.approx(friction / normal, rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_lift_off_capacity_is_where_the_simulators_normal_force_vanishes(seed):
    rng = np.random.default_rng(10 + seed)
    for _ in range(40):
        l, g, g_e, f, swing = _case(rng)
        th = float(rng.uniform(0.05, 1.2))
        along = phys.carry_along(th, gravity=g, carry_gravity=g_e, friction=f, link_length=l)
        held = phys.lift_off_capacity(th, gravity=g, link_length=l, along=along)
        if held <= 0.0:
            continue
        omega = math.sqrt(held) / l
        _, normal = stuck_contact_force(th, omega, swing_acceleration(th, omega, swing),
                                        gravity=g, link_length=l)
        assert abs(normal) <= 1e-9 * g
