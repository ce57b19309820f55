"""The compass gait's closed forms against independent derivations: the equations of motion
against Lagrange's equations derived here by sympy, the heel strike against the impulse method
in the walker's free-floating coordinates, Garcia et al. (1998)'s simplest-walker impact, and the
ground force of a walker at rest."""

import math

import numpy as np
import pytest

from pdm_design.scenes.compass_gait import physics as phys

sympy = pytest.importorskip("sympy")

RNG = np.random.default_rng(7)


def random_params(simplest=False):
    if simplest:
        return phys.Params(0.0, 0.0, 1.3, 1.3, 0.0, 9.81)
    l = RNG.uniform(0.5, 1.5)
    b = RNG.uniform(0.1, 1.0) * l
    return phys.Params(RNG.uniform(0.1, 2.0), l - b, b, l, RNG.uniform(0.0, 0.05), 9.81)


def lagrange_accelerations():
    """Lagrange's equations of the walker with a hip mass 1, legs of mass beta: a function of
    (state, params) -> (a1, a2), from T - V written in positions (not the module's forms)."""
    t = sympy.symbols("t")
    beta, a, b, l, k2, g = sympy.symbols("beta a b l k2 g", positive=True)
    q1, q2 = sympy.Function("q1")(t), sympy.Function("q2")(t)
    u = lambda q: sympy.Matrix([sympy.sin(q), sympy.cos(q)])  # noqa: E731
    hip = l * u(q1)
    stance_com = a * u(q1)
    swing_com = hip - b * u(q2)
    v2 = lambda r: (r.diff(t).T * r.diff(t))[0]  # noqa: E731
    kinetic = (v2(hip) + beta * (v2(stance_com) + v2(swing_com))) / 2 \
        + beta * k2 * (q1.diff(t) ** 2 + q2.diff(t) ** 2) / 2
    potential = g * (hip[1] + beta * (stance_com[1] + swing_com[1]))
    L = kinetic - potential
    eqs = [sympy.diff(L.diff(q.diff(t)), t) - L.diff(q) for q in (q1, q2)]
    acc = sympy.symbols("acc1 acc2")
    rates = sympy.symbols("w1 w2")
    angles = sympy.symbols("x1 x2")
    subs = {q1.diff(t, 2): acc[0], q2.diff(t, 2): acc[1]}
    eqs = [e.subs(subs) for e in eqs]
    subs = {q1.diff(t): rates[0], q2.diff(t): rates[1]}
    eqs = [e.subs(subs).subs({q1: angles[0], q2: angles[1]}) for e in eqs]
    # the swing leg's row is per leg mass in the module, so divide by beta for beta -> 0 limits
    sol = sympy.solve([eqs[0], eqs[1] / beta], acc, dict=True)[0]
    return sympy.lambdify([angles, rates, (beta, a, b, l, k2, g)], [sol[acc[0]], sol[acc[1]]])


def test_equations_of_motion_match_lagrange():
    reference = lagrange_accelerations()
    for _ in range(20):
        p = random_params()
        q = RNG.uniform(-0.8, 0.8, 2)
        w = RNG.uniform(-3, 3, 2)
        expected = reference(q, w, tuple(p))
        got = phys.accelerations(q[0], q[1], w[0], w[1], p)
        assert got == pytest.approx(expected, rel=1e-10, abs=1e-10)


def floating_heel_strike(q1, q2, w1, w2, p):
    """The impact by the impulse method: coordinates (hip x, hip y, q1, q2), an impulse at the
    swing foot that brings it to rest, none at the trailing foot (it leaves the ground)."""
    def u(q):
        return np.array([math.sin(q), math.cos(q)])

    def du(q):
        return np.array([math.cos(q), -math.sin(q)])

    # velocity Jacobians of the hip, the legs' centres (hip - b u) and the swing foot (hip - l u)
    def J_point(dist, leg):
        J = np.zeros((2, 4))
        J[:, :2] = np.eye(2)
        J[:, 2 + leg] = -dist * du((q1, q2)[leg])
        return J

    mass = [(1.0, J_point(0.0, 0)), (p.beta, J_point(p.b, 0)), (p.beta, J_point(p.b, 1))]
    D = sum(m * J.T @ J for m, J in mass)
    D[2, 2] += p.beta * p.k2
    D[3, 3] += p.beta * p.k2
    # before: stance foot at rest, hip velocity l w1 u'(q1)
    v = np.array([*(p.l * w1 * du(q1)), w1, w2])
    Jf = J_point(p.l, 1)
    # after: D (v+ - v) = Jf^T P, Jf v+ = 0
    K = np.block([[D, -Jf.T], [Jf, np.zeros((2, 2))]])
    sol = np.linalg.solve(K, np.concatenate([D @ v, np.zeros(2)]))
    return sol[3], sol[2]  # legs swap: the new stance rate is the old swing leg's


@pytest.mark.parametrize("simplest", [False, True])
def test_heel_strike_matches_impulse_method(simplest):
    for _ in range(20):
        p = random_params(simplest)
        slope = RNG.uniform(0.0, 0.1)
        half = RNG.uniform(0.1, 0.4)
        q1, q2 = slope + half, slope - half  # on the guard, swing foot ahead
        w1, w2 = RNG.uniform(0.5, 2.0), RNG.uniform(-2.0, 2.0)
        after = phys.heel_strike(q1, q2, w1, w2, p)
        assert after[:2] == (q2, q1)
        # the simplest walker is the limit of light legs: legs of 1e-9 hip masses
        light = p._replace(beta=1e-9) if simplest else p
        expected = floating_heel_strike(q1, q2, w1, w2, light)
        assert after[2:] == pytest.approx(expected, rel=1e-7 if simplest else 1e-10)


def test_simplest_walker_impact_is_garcias():
    """Garcia et al. (1998), eq. 4: theta+ = -theta-, theta_dot+ = cos(2 theta) theta_dot-,
    phi_dot+ = cos(2 theta) (1 - cos(2 theta)) theta_dot-, phi the angle between the legs."""
    p = phys.Params(0.0, 0.0, 1.0, 1.0, 0.0, 1.0)
    slope, theta, rate = 0.01, 0.2, 0.9  # theta: stance angle from the slope normal
    q1, q2 = slope + theta, slope - theta
    _, _, w1, w2 = phys.heel_strike(q1, q2, rate, -0.4, p)
    c = math.cos(2 * theta)
    assert w1 == pytest.approx(c * rate, rel=1e-14)
    assert w1 - w2 == pytest.approx(c * (1 - c) * rate, rel=1e-13)


def test_ground_force_of_a_walker_at_rest_upright():
    p = random_params()
    slope = 0.07
    normal, downhill = phys.ground_reaction(0.0, 0.0, 0.0, 0.0, slope, p)
    weight = (1 + 2 * p.beta) * p.g
    assert normal == pytest.approx(weight * math.cos(slope), rel=1e-14)
    assert downhill == pytest.approx(-weight * math.sin(slope), rel=1e-14)


def test_strike_guard_is_the_swing_foot_on_the_ramp():
    """At the guard's zero the swing foot's height above the ramp (from positions) is zero."""
    p = random_params()
    slope, half = 0.05, 0.3
    q1, q2 = slope + half, slope - half
    assert phys.strike_guard(q1, q2, slope, 0.0) == pytest.approx(0.0, abs=1e-15)
    foot = np.array([p.l * (math.sin(q1) - math.sin(q2)), p.l * (math.cos(q1) - math.cos(q2))])
    assert foot[1] + foot[0] * math.tan(slope) == pytest.approx(0.0, abs=1e-14)
