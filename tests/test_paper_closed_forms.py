"""The paper's three examples reproduced from closed forms, and the paper's errors shown.

Expected numbers come from the paper's tables (section 4) or from an independent derivation
written here (vector algebra or sympy), never from the code under test.
"""

import math

import numpy as np
import pytest
import sympy as sp

from pdm_design.scenes.manipulators import physics as manip
from pdm_design.scenes.stairs import physics as stairs

G = 9.81


# --- Example 1: frictionless stairs (h0 = 1, V0 = 2, eps = 0.8) -------------------------------

def test_example1_rise_is_paper_value():
    assert stairs.periodic_rise(1.0, 0.8) == pytest.approx(0.36, abs=1e-12)


@pytest.mark.parametrize("gravity, tolerance", [(9.8, 5e-4), (9.81, 1e-3)])
def test_example1_tread_matches_paper_to_its_rounding(gravity, tolerance):
    # Paper: d = 1.626 m. Its numbers round exactly with g = 9.8; with g = 9.81 they differ
    # in the third decimal (docs/physics.md).
    tread = stairs.periodic_tread(2.0, gravity, 1.0, 0.8)
    assert tread == pytest.approx(1.626, abs=tolerance)


def test_example1_tread_from_independent_kinematics():
    # Rebound at eps*v, fall to a tread `rise` lower: solve y(t) = -rise for t directly.
    v = math.sqrt(2 * G * 1.0)
    rise = 0.36
    t = (0.8 * v + math.sqrt((0.8 * v) ** 2 + 2 * G * rise)) / G
    assert stairs.periodic_tread(2.0, G, 1.0, 0.8) == pytest.approx(2.0 * t, rel=1e-12)


# --- Example 2: stairs with friction and spin --------------------------------------------------

BALL = dict(radius=0.5, mass=0.283, inertia=0.035)


def _rolling_impact_by_sympy(vx, omega, radius, mass, inertia):
    """Impulse-momentum with the contact at (0, -r) and omega counter-clockwise positive."""
    vxp, wp, impulse = sp.symbols("vxp wp P")
    eqs = [
        sp.Eq(mass * (vxp - vx), impulse),                 # linear momentum along x
        sp.Eq(inertia * (wp - omega), radius * impulse),   # (0,-r) x (P,0) = +r P about z
        sp.Eq(vxp + radius * wp, 0),                       # contact point at rest afterwards
    ]
    sol = sp.solve(eqs, [vxp, wp, impulse], dict=True)[0]
    return float(sol[vxp]), float(sol[wp])


def test_rolling_impact_matches_impulse_momentum_solution():
    expected = _rolling_impact_by_sympy(3.0, 0.5, **BALL)
    got = stairs.rolling_impact(3.0, 0.5, **BALL)
    assert got == pytest.approx(expected, rel=1e-12)


def test_paper_eq14_sign_contradicts_its_own_rolling_constraint():
    # Paper eq. 14 gives omega+ = +(m r / (m r^2 + J)) (...) = +vx+/r, but eq. 12 says
    # vx+ = -r omega+. Only the minus sign satisfies both.
    vx_after, _ = stairs.rolling_impact(3.0, 0.5, **BALL)
    m, r, j = BALL["mass"], BALL["radius"], BALL["inertia"]
    paper_omega = (m * r / (m * r**2 + j)) * (3.0 - j / (m * r) * 0.5)
    assert vx_after + r * paper_omega != pytest.approx(0.0, abs=1e-3)
    _, omega_after = _rolling_impact_by_sympy(3.0, 0.5, **BALL)
    assert vx_after + r * omega_after == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("gravity, tolerance", [(9.8, 5e-4), (9.81, 1e-3)])
def test_example2_tread_matches_paper_to_its_rounding(gravity, tolerance):
    vx, _ = stairs.rolling_impact(3.0, 0.5, **BALL)
    assert stairs.periodic_tread(vx, gravity, 1.0, 0.8) == pytest.approx(1.565, abs=tolerance)


def test_example2_friction_suffices_for_rolling():
    ratio = stairs.rolling_impulse_ratio(3.0, 0.5, -math.sqrt(2 * G), 0.8, **BALL)
    # Independent: the impulse the sympy solution needs over the normal impulse m (1+eps) v.
    vx_after, _ = _rolling_impact_by_sympy(3.0, 0.5, **BALL)
    expected = abs(BALL["mass"] * (vx_after - 3.0)) / (BALL["mass"] * 1.8 * math.sqrt(2 * G))
    assert ratio == pytest.approx(expected, rel=1e-12)
    assert ratio < 0.5


# --- Example 3: manipulators (m = 1, M = 0.1, l = 2, alpha = 0.2, beta = 0.6) -----------------

A, B, L, Q = 0.2, 0.6, 2.0, 10.0


def test_example3_pitch_is_paper_value():
    x, y = manip.pitch(A, B, L)
    assert x == pytest.approx(1.5266, abs=5e-5)
    assert y == pytest.approx(0.3095, abs=5e-5)


def _tangent(theta):
    """Unit velocity direction of a palm at angle theta (clockwise from vertical)."""
    return np.array([math.cos(theta), -math.sin(theta)])


def _iterate_handover_by_vectors(speed, stages):
    """Stage map built from vectors: hand over along t(beta), keep momentum along t(-alpha)."""
    k = Q / (1 + Q)
    for _ in range(stages):
        velocity = speed * _tangent(B)
        u = k * velocity @ _tangent(-A)
        speed = math.sqrt(u**2 + 2 * G * L * (math.cos(A) - math.cos(B)))
    return speed


def test_handover_speed_is_fixed_point_of_vector_map():
    fixed = math.sqrt(manip.handover_speed_squared(A, B, Q, gravity=G, link_length=L))
    assert _iterate_handover_by_vectors(1.0, 200) == pytest.approx(fixed, rel=1e-12)


def test_paper_eq30_is_not_a_fixed_point_of_the_stage_map():
    # Paper's eq. 28 projects with cos(beta - alpha); the vectors give cos(alpha + beta).
    paper = math.sqrt(manip.paper_handover_speed_squared(A, B, Q, gravity=G, link_length=L))
    one_stage_later = _iterate_handover_by_vectors(paper, 1)
    assert abs(one_stage_later - paper) > 0.5  # 4.51 m/s falls to about 3.77 m/s in one stage


def test_projection_identity_behind_the_paper_error():
    a, b = sp.symbols("alpha beta", real=True)
    projected = sp.cos(b) * sp.cos(a) - sp.sin(b) * sp.sin(a)
    assert sp.simplify(projected - sp.cos(a + b)) == 0
    assert sp.simplify(projected - sp.cos(b - a)) != 0


def test_contraction_matches_numerical_derivative_of_vector_map():
    fixed = math.sqrt(manip.handover_speed_squared(A, B, Q, gravity=G, link_length=L))
    h = 1e-6
    slope = (_iterate_handover_by_vectors(fixed + h, 1)
             - _iterate_handover_by_vectors(fixed - h, 1)) / (2 * h)
    assert manip.contraction(A, B, Q) == pytest.approx(slope, rel=1e-7)


def test_corrected_handover_speed_value():
    # Closed form evaluated by hand: 2 g l (cos a - cos b) / (1 - (10/11)^2 cos^2 0.8).
    expected = math.sqrt(39.24 * (math.cos(0.2) - math.cos(0.6))
                         / (1 - (10 / 11) ** 2 * math.cos(0.8) ** 2))
    got = math.sqrt(manip.handover_speed_squared(A, B, Q, gravity=G, link_length=L))
    assert got == pytest.approx(expected, rel=1e-14)
    assert got == pytest.approx(3.1842, abs=5e-5)


def _contact_force_by_newton(theta, speed):
    """Palm force on a stuck object of unit mass: m a - m g, with a of circular motion."""
    radial = np.array([math.sin(theta), math.cos(theta)])
    tangential_accel = G * math.sin(theta)  # l theta'' = g sin theta for the translating palm
    accel = tangential_accel * _tangent(theta) - speed**2 / L * radial
    return accel - np.array([0.0, -G])


@pytest.mark.parametrize("theta, speed", [(0.6, 3.0), (-0.2, 2.0), (0.3, 4.5)])
def test_lift_off_capacity_matches_newton(theta, speed):
    force = _contact_force_by_newton(theta, speed)
    normal_positive = force[1] > 0  # the palm's top is horizontal: its normal is y
    held = manip.lift_off_capacity(theta, gravity=G, link_length=L)
    assert (speed**2 < held) == normal_positive


@pytest.mark.parametrize("theta", [-1.5, -1.2, -0.7, -0.2, 0.0, 0.3, 0.6, 1.0, 1.3, 1.55])
def test_lift_off_capacity_is_the_speed_where_newtons_normal_force_vanishes(theta):
    # Newton's normal force is affine in v^2 (centripetal term - v^2 / l along the radius), so
    # its root in v^2 is f(0) / (f(0) - f(1)), from two evaluations at speeds 0 and 1
    f0 = _contact_force_by_newton(theta, 0.0)[1]
    f1 = _contact_force_by_newton(theta, 1.0)[1]
    root = f0 / (f0 - f1)
    held = manip.lift_off_capacity(theta, gravity=G, link_length=L)
    assert held == pytest.approx(root, rel=1e-12)
    # and the force there is zero, a little slower a push, a little faster a pull
    assert abs(_contact_force_by_newton(theta, math.sqrt(held))[1]) <= 1e-12 * G
    assert _contact_force_by_newton(theta, math.sqrt(0.99 * held))[1] > 0
    assert _contact_force_by_newton(theta, math.sqrt(1.01 * held))[1] < 0


@pytest.mark.parametrize("theta, speed", [(0.6, 3.0), (-0.2, 2.0), (0.5, 1.0)])
def test_friction_demand_matches_newton(theta, speed):
    fx, fy = _contact_force_by_newton(theta, speed)
    assert manip.friction_demand(theta) == pytest.approx(abs(fx / fy), rel=1e-12)
