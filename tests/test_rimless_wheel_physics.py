"""The rimless wheel's closed forms against independent sources: Tedrake's textbook fixed point
and rolling condition, the energy balance of the orbit, angular momentum computed by vectors."""

import math

import numpy as np
import pytest

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    Wheel,
)
from pdm_design.scenes.rimless_wheel import physics as phys
from pdm_design.scenes.rimless_wheel.analysis import analyse_rimless_wheel

G = 9.81


POINT = Wheel()


def ramp(n, slope, *, leg=1.0, speed=1.5, wheel=POINT, friction=1.0, gravity=G):
    scene = RimlessWheelScene(initial=RimlessWheelInitial(speed=speed), wheel=wheel,
                              friction=friction, gravity=gravity)
    return scene, RimlessWheelDesign(spokes=n, leg_length=leg, slope=slope)


@pytest.mark.parametrize("n,slope,leg", [(8, 0.08, 1.0), (6, 0.2, 0.5), (12, 0.05, 2.0),
                                         (100, 0.01, 1.0)])
def test_tedrake_fixed_point_of_a_point_mass(n, slope, leg):
    """Tedrake (Underactuated Robotics, the rimless wheel): omega*_roll = cot(2 alpha)
    sqrt(4 (g / l) sin alpha sin gamma)."""
    alpha = math.pi / n
    expected = math.sqrt(4 * G / leg * math.sin(alpha) * math.sin(slope)) / math.tan(2 * alpha)
    a = analyse_rimless_wheel(*ramp(n, slope, leg=leg))
    assert a.periodic["post_impact_speed"] == pytest.approx(expected, rel=1e-12)
    assert a.periodic["contraction"] == pytest.approx(math.cos(2 * alpha) ** 2, rel=1e-12)


def test_tedrake_rolling_condition():
    """The orbit rolls iff omega* > omega_1 = sqrt(2 g / l (1 - cos(gamma - alpha))) (over the
    top), and the margin is 1 - omega_1^2 / omega*^2 (-(1 - omega*^2 / omega_1^2) when it
    fails: analysis.result.margin)."""
    n, leg = 8, 1.0
    alpha = math.pi / n
    for slope in np.linspace(0.005, 0.3, 40):
        w1 = 2 * G / leg * (1 - math.cos(slope - alpha)) if slope < alpha else 0.0
        ws = 4 * G / leg * math.sin(alpha) * math.sin(slope) / math.tan(2 * alpha) ** 2
        # start on the orbit, so the approach adds nothing
        a = analyse_rimless_wheel(*ramp(n, float(slope), leg=leg, speed=math.sqrt(ws)))
        expected = 1 - w1 / ws if ws >= w1 else -(1 - ws / w1)
        assert a.margins["over_the_top"] == pytest.approx(expected, abs=1e-9)
        assert (a.margins["over_the_top"] > 0) == (ws > w1)


def inertia_about_tip(wheel, n, leg):
    """I_p by parts: the hub, n rods about the hub (m l^2 / 3), the whole mass moved to the tip."""
    mass = wheel.mass + n * wheel.spoke_mass
    return wheel.mass * wheel.gyration**2 + n * wheel.spoke_mass * leg**2 / 3 + mass * leg**2, mass


@pytest.mark.parametrize("wheel", [Wheel(), Wheel(mass=2.0, gyration=0.4),
                                   Wheel(mass=1.0, gyration=0.2, spoke_mass=0.1)])
def test_orbit_loses_at_impact_what_the_step_drops(wheel):
    """On the orbit the kinetic energy an impact takes equals m g times the height of a step
    (2 l sin alpha sin gamma)."""
    n, slope, leg = 10, 0.07, 0.8
    a = analyse_rimless_wheel(*ramp(n, slope, leg=leg, wheel=wheel))
    ip, mass = inertia_about_tip(wheel, n, leg)
    before, after = a.periodic["pre_impact_speed"], a.periodic["post_impact_speed"]
    lost = 0.5 * ip * (before**2 - after**2)
    drop = mass * G * 2 * leg * math.sin(math.pi / n) * math.sin(slope)
    assert lost == pytest.approx(drop, rel=1e-12)


@pytest.mark.parametrize("wheel", [Wheel(), Wheel(mass=2.0, gyration=0.4),
                                   Wheel(mass=1.0, gyration=0.2, spoke_mass=0.3)])
def test_impact_conserves_angular_momentum_about_the_new_tip(wheel):
    """H = I_c omega + m (r_G - r_new) x v_G, by vectors, equal before and after."""
    n, leg = 7, 1.3
    alpha = math.pi / n
    ip, mass = inertia_about_tip(wheel, n, leg)
    ic = ip - mass * leg**2
    k2 = float(phys.gyration_squared(wheel.mass, wheel.gyration, wheel.spoke_mass, n, leg))
    eta = float(phys.impact_ratio(k2, leg, alpha))
    phi = 0.1 + alpha  # any chord
    hub = leg * np.array([math.sin(phi), math.cos(phi)])
    new = hub - leg * np.array([math.sin(phi - 2 * alpha), math.cos(phi - 2 * alpha)])
    w_minus = 2.0

    def momentum(omega, pivot):  # clockwise omega about the pivot
        v = omega * np.array([hub[1] - pivot[1], -(hub[0] - pivot[0])])
        r = hub - new
        return -ic * omega + mass * (r[0] * v[1] - r[1] * v[0])

    before = momentum(w_minus, np.zeros(2))
    after = momentum(eta * w_minus, new)
    assert after == pytest.approx(before, rel=1e-12)


def test_impact_friction_of_a_point_mass_is_tan_alpha():
    """A point mass's impact impulse is m (v+ - v-) with |v+| = cos(2 alpha) |v-|, each velocity
    across its spoke: the impulse points along the new spoke, alpha from the ramp's normal, so
    its tangential over normal part is tan alpha and the margin 1 - tan(alpha) / mu."""
    for n in (4, 8, 30):
        a = analyse_rimless_wheel(*ramp(n, 0.05, friction=1.0))
        assert a.margins["impact_friction"] == pytest.approx(1 - math.tan(math.pi / n), rel=1e-12)


def test_step_time_against_elliptic_integral():
    """T = int dphi / sqrt(E + 2 rate sin^2(phi/2)) = (2 / sqrt(E)) [F(u1 | m) - F(u0 | m)],
    u = phi / 2, m = -2 rate / E (scipy's incomplete elliptic integral)."""
    from scipy.special import ellipkinc

    scene, design = ramp(8, 0.08)
    a = analyse_rimless_wheel(scene, design)
    e, rate = a.periodic["energy"], a.geometry["stance_rate"]
    alpha, slope = math.pi / 8, 0.08
    m = -2 * rate / e
    expected = 2 / math.sqrt(e) * (ellipkinc((slope + alpha) / 2, m)
                                   - ellipkinc((slope - alpha) / 2, m))
    assert a.periodic["step_period"] == pytest.approx(expected, rel=1e-10)


def test_three_spokes_of_a_point_mass_stall_at_every_impact():
    """n = 3, no inertia: eta = cos(120 deg) = -1/2 < 0, the wheel rolls back: a problem."""
    a = analyse_rimless_wheel(*ramp(3, 0.3))
    assert a.geometry["impact_ratio"] == pytest.approx(-0.5)
    assert not a.feasible() and "rolls back" in a.problems[0]
    # with a heavy hub of gyration l: eta = (1 - 1/2) / 2 = 1/4
    a = analyse_rimless_wheel(*ramp(3, 0.3, wheel=Wheel(gyration=1.0)))
    assert a.geometry["impact_ratio"] == pytest.approx(0.25, rel=1e-12)


@pytest.mark.parametrize("scale", [1e-5, 1.0, 1e5])
def test_any_size_gives_the_same_wheel(scale):
    """Lengths x k, speeds x 1/sqrt(k): the same dimensionless orbit and margins."""
    scene, design = ramp(9, 0.06, leg=1.0, speed=1.4, wheel=Wheel(gyration=0.3))
    base = analyse_rimless_wheel(scene, design)
    scene2, design2 = ramp(9, 0.06, leg=scale, speed=1.4 / math.sqrt(scale),
                           wheel=Wheel(gyration=0.3 * scale))
    a = analyse_rimless_wheel(scene2, design2)
    assert a.periodic["post_impact_speed"] * math.sqrt(scale) == pytest.approx(
        base.periodic["post_impact_speed"], rel=1e-10)
    for name, value in base.margins.items():
        assert a.margins[name] == pytest.approx(value, rel=1e-9, abs=1e-12)


def test_stairs_matched_to_the_spokes_behave_as_their_chord_ramp():
    """rise h, tread sqrt(c^2 - h^2): the orbit of a ramp of slope asin(h / c)."""
    n, leg, rise = 8, 1.0, 0.12
    chord = 2 * leg * math.sin(math.pi / n)
    scene = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.5), ground="stairs")
    a = analyse_rimless_wheel(scene, RimlessWheelDesign(spokes=n, leg_length=leg, rise=rise))
    assert a.geometry["tread"] == pytest.approx(math.sqrt(chord**2 - rise**2), rel=1e-12)
    r = analyse_rimless_wheel(*ramp(n, math.asin(rise / chord), leg=leg))
    assert a.periodic["post_impact_speed"] == pytest.approx(r.periodic["post_impact_speed"],
                                                            rel=1e-12)


def test_nose_reach_by_geometry():
    """The landing spoke clears the nose iff the nose corner lies on the wheel's side of the
    spoke's line at the impact: by the cross product, against nose_reach."""
    n, leg, rise = 8, 1.0, 0.12
    alpha = math.pi / n
    beta = math.asin(rise / (2 * leg * math.sin(alpha)))
    phi = beta + alpha
    hub = leg * np.array([math.sin(phi), math.cos(phi)])
    tip = hub - leg * np.array([math.sin(phi - 2 * alpha), math.cos(phi - 2 * alpha)])
    reach = float(phys.nose_reach(leg, alpha, beta))
    for a in (0.9 * reach, 1.1 * reach):
        u, w = tip - hub, np.array([a, 0.0]) - hub
        clear = u[0] * w[1] - u[1] * w[0] < 0  # the corner clockwise of the spoke, wheel side
        assert clear == (a < reach)


def test_a_hundred_thousand_spokes_roll_into_flight():
    """Tedrake's orbit still (1 - eta^2 without cancellation), and it is a rolling hoop's:
    l omega*^2 ~ g gamma / alpha grows past g, so the wheel leaves the ground (no_flight < 0,
    every margin in [-1, 1])."""
    n, slope = 100_000, 0.01
    alpha = math.pi / n
    expected = math.sqrt(4 * G * math.sin(alpha) * math.sin(slope)) / math.tan(2 * alpha)
    a = analyse_rimless_wheel(*ramp(n, slope, speed=50.0))
    assert a.periodic["post_impact_speed"] == pytest.approx(expected, rel=1e-9)
    assert expected**2 > G
    assert a.margins["no_flight"] < 0
    assert all(-1.0 <= value <= 1.0 for value in a.margins.values())


def test_written_once_for_floats_arrays_and_casadi():
    """The step map on a float, on a numpy array and on CasADi symbols gives the same numbers,
    and CasADi's derivative through one step is the multiplier eta^2."""
    import casadi as ca

    k2, leg, alpha, g = 0.1, 1.0, math.pi / 9, G
    eta = phys.impact_ratio(k2, leg, alpha)
    rate = phys.stance_rate(g, k2, leg)
    energies = np.array([0.3, 1.0, 2.5])
    betas = np.array([0.05, 0.1, 0.2])
    on_array = phys.step_energy(energies, betas, alpha, eta, rate)
    e, b = ca.SX.sym("e"), ca.SX.sym("b")
    step = ca.Function("step", [e, b], [phys.step_energy(e, b, alpha, eta, rate)])
    slope = ca.Function("slope", [e, b], [ca.jacobian(phys.step_energy(e, b, alpha, eta, rate),
                                                      e)])
    for i in range(3):
        on_float = phys.step_energy(float(energies[i]), float(betas[i]), alpha, eta, rate)
        assert on_array[i] == pytest.approx(on_float, rel=1e-15)
        assert float(step(energies[i], betas[i])) == pytest.approx(on_float, rel=1e-14)
        assert float(slope(energies[i], betas[i])) == pytest.approx(eta**2, rel=1e-14)
