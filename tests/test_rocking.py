"""The rocking object (sim/rocking.py, docs/physics.md section 2.2): its equations against a
sympy Lagrangian, and the simulator's rocking that settles, is caught and tips over against
independent integrations and closed forms written here."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from test_sim_manipulators import ALPHA, G, L, make, offset

from pdm_design.accuracy import accuracy
from pdm_design.scenes.manipulators.sim import rocking as rk
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.scenes.manipulators.sim.run import Run

W_BODY, H_BODY, M_BODY = 0.4, 0.2, 1.0
I_C = M_BODY * (W_BODY**2 + H_BODY**2) / 12


def lagrangian_accelerations():
    """(th'', phi'') of the pinned object on its palm from T - V (sympy), and the pin force."""
    th, ph_, thd, phd, thdd, phdd = sp.symbols("th phi thd phd thdd phdd")
    m, felt, weight, ic, d, h, l, g, tau, c = sp.symbols("m felt weight ic d h l g tau c")
    # the pin on the palm's top, the centre of mass: (-d, h/2) from the pin, turned clockwise
    pin = sp.Matrix([l * sp.sin(th), l * sp.cos(th)])
    cm = pin + sp.Matrix([-d * sp.cos(ph_) + h / 2 * sp.sin(ph_),
                          d * sp.sin(ph_) + h / 2 * sp.cos(ph_)])
    q, qd = [th, ph_], [thd, phd]

    def rate(expr):
        return sum(sp.diff(expr, a) * b for a, b in zip(q, qd))

    v = cm.applyfunc(rate)
    T = (felt * l**2 * thd**2 + m * (v[0]**2 + v[1]**2) + ic * phd**2) / 2
    V = weight * g * l * sp.cos(th) + m * g * cm[1]
    Lag = T - V
    forces = [-tau - c * thd, 0]  # Coulomb torque (forward swing) and damping on the palm
    eqs = []
    for a, ad, f in zip(q, qd, forces):
        p = sp.diff(Lag, ad)
        dp = sum(sp.diff(p, x) * y for x, y in zip(q + qd, qd + [thdd, phdd]))
        eqs.append(dp - sp.diff(Lag, a) - f)
    # the equations are linear in (th'', phi''): their matrix and right-hand side, solved
    # numerically (sympy's solve simplifies for minutes)
    mat = sp.Matrix(eqs).jacobian([thdd, phdd])
    rhs = -sp.Matrix(eqs).subs({thdd: 0, phdd: 0})
    vel = cm.applyfunc(rate)
    accel = vel.applyfunc(lambda e: sum(sp.diff(e, x) * y for x, y in
                                        zip(q + qd, qd + [thdd, phdd])))
    force = m * (accel + sp.Matrix([0, g]))
    args = (th, thd, ph_, phd, m, felt, weight, ic, d, h, l, g, tau, c)
    f_mat, f_rhs = sp.lambdify(args, mat), sp.lambdify(args, rhs)

    def f_acc(*a):
        return list(np.linalg.solve(np.array(f_mat(*a), float),
                                    np.array(f_rhs(*a), float).ravel()))

    f_force = sp.lambdify(args + (thdd, phdd), list(force))
    return f_acc, f_force


def test_rocking_equations_are_lagrange_equations():
    f_acc, f_force = lagrangian_accelerations()
    rng = np.random.default_rng(5)
    for _ in range(20):
        th, thd, phi, phd = rng.uniform(-1, 1, 4)
        d, e = rng.uniform(-0.2, 0.2), rng.uniform(-0.8, 0.8)
        felt, weight, tau, c = rng.uniform(0.05, 2), rng.uniform(0.05, 2), rng.uniform(0, 1), \
            rng.uniform(0, 1)
        r = rk.Rocker(M_BODY, I_C, d, H_BODY, e, felt, weight, tau, c, G, L, (0.0, 0.0), True)
        got = rk.accelerations(th, thd, phi, phd, r, direction=1.0)
        want = f_acc(th, thd, phi, phd, M_BODY, felt, weight, I_C, d, H_BODY, L, G, tau, c)
        assert got == pytest.approx(want, rel=1e-10, abs=1e-10)
        fx, fy = f_force(th, thd, phi, phd, M_BODY, felt, weight, I_C, d, H_BODY, L, G, tau, c,
                         *want)
        tangential, normal = rk.pin_force(th, thd, phi, phd, *got, r)
        n = (math.sin(phi), math.cos(phi))
        assert normal == pytest.approx(fx * n[0] + fy * n[1], rel=1e-9, abs=1e-9)
        assert tangential == pytest.approx(fx * n[1] - fy * n[0], rel=1e-9, abs=1e-9)


# ------------------------------------------------------------------ a fixed edge

S_EDGE = 0.75  # the object's centre 0.75 m ahead of palm 1's centre: 0.05 m of base beyond it
D_EDGE = 0.8 - S_EDGE  # the palm's front edge, from the base's centre (0.05 m)
I_P = I_C + M_BODY * (D_EDGE**2 + (H_BODY / 2) ** 2)


def centre_height(phi, d=D_EDGE):
    """The centre of mass above the pin, the object turned clockwise by phi about it."""
    return d * math.sin(phi) + H_BODY / 2 * math.cos(phi)


def fixed_edge(phid0, t_end, events):
    """The inverted pendulum about the fixed pin, I_P phi'' = -m g dy/dphi, integrated here."""
    def rhs(t, z):
        dy = D_EDGE * math.cos(z[0]) - H_BODY / 2 * math.sin(z[0])
        return [z[1], -M_BODY * G * dy / I_P]

    return solve_ivp(rhs, (0.0, t_end), [0.0, phid0], rtol=1e-12, atol=1e-13, events=events)


def rocking_run(phid0, offsets=(), mu=0.8):
    """Run the simulator's rocking phase on palm 1 held by its back stop (a palm of 10 kg:
    gravity keeps it on its stop), from phi = 0 at phi' = phid0 about its front edge."""
    scene, design = make(mass_ratio=0.1, mu=mu)
    run = Run(scene, design, 2, offsets, accuracy("precise"), False)
    run.at = 0
    run.stages.append({"manipulator": 1, "bounces": 0})
    step = run._rock(0.0, 0, S_EDGE, D_EDGE, (-ALPHA, 0.0, 0.0, phid0), True)
    while step is not None:
        step = step()
    return run


def barrier_speed():
    """Least phi' at phi = 0 that brings the centre over the pin: the energy integral."""
    top = math.hypot(D_EDGE, H_BODY / 2)
    return math.sqrt(2 * M_BODY * G * (top - H_BODY / 2) / I_P)


def test_a_rocking_object_on_a_fixed_edge_settles_back_when_below_the_barrier():
    phid0 = 0.8 * barrier_speed()
    run = rocking_run(phid0)
    back_down = next(e for e in run.events if e.kind in ("rock", "settle"))

    def back(t, z):
        return z[0] if t > 1e-6 else 1.0

    back.terminal, back.direction = True, -1
    sol = fixed_edge(phid0, 10.0, [back])
    t_back = sol.t_events[0][0]
    assert back_down.time == pytest.approx(t_back, abs=1e-9)
    assert back_down.before["spin"] == pytest.approx(-phid0, rel=1e-9)  # energy: same speed
    # the impact on the rear corner: the angular momentum about it is kept (clockwise +);
    # counter-clockwise after, it lifts the front edge: the object rocks about its rear corner
    dx, dy = W_BODY / 2, H_BODY / 2  # the centre from the rear corner at phi = 0
    v_cm = (-phid0 * H_BODY / 2, -phid0 * D_EDGE)  # phi' (h/2, d) about the pin, phi' = -phid0
    h_rear = I_C * -phid0 + M_BODY * (dy * v_cm[0] - dx * v_cm[1])
    spin = h_rear / (I_C + M_BODY * (dx * dx + dy * dy))
    assert spin < 0.0 and back_down.kind == "rock"
    assert back_down.after["spin"] == pytest.approx(spin, rel=1e-9)
    # and back and forth, slower at every impact, until it lies flat on the held palm
    assert [e.kind for e in run.events][-2:] == ["settle", "stall"]
    spins = [abs(e.after["spin"]) for e in run.events if e.kind == "rock"]
    assert all(b < a for a, b in zip(spins, spins[1:]))


def pinned_force(phi, phid):
    """(tangential, normal) force of the fixed edge on the object turning about it, along and
    across its base: F = m (C'' + g y) with C'' = a phi'' - rho phi'^2 of the pendulum."""
    d, h = D_EDGE, H_BODY
    rho = (-d * math.cos(phi) + h / 2 * math.sin(phi), centre_height(phi))
    a = (d * math.sin(phi) + h / 2 * math.cos(phi), d * math.cos(phi) - h / 2 * math.sin(phi))
    phidd = -M_BODY * G * a[1] / I_P
    fx = M_BODY * (a[0] * phidd - rho[0] * phid**2)
    fy = M_BODY * (a[1] * phidd - rho[1] * phid**2 + G)
    return (fx * math.cos(phi) - fy * math.sin(phi), fx * math.sin(phi) + fy * math.cos(phi))


def object_energy(state):
    """Kinetic and potential energy of the object from an event state (its bottom centre's
    place and velocity, its rotation and spin)."""
    phi, spin = state["phi"], state["spin"]
    rx, ry = H_BODY / 2 * math.sin(phi), H_BODY / 2 * math.cos(phi)  # the centre from there
    vx, vy = state["vx"] + spin * ry, state["vy"] - spin * rx
    return (0.5 * M_BODY * (vx * vx + vy * vy) + 0.5 * I_C * spin * spin
            + M_BODY * G * (state["y"] + ry))


def test_a_rocking_object_on_a_fixed_edge_tips_over_above_the_barrier():
    phid0 = 1.05 * barrier_speed()
    run = rocking_run(phid0)
    # (the rocker of the object as it starts: the run's object lies on its side by its end)
    rocker = Run(*make(mass_ratio=0.1), 2, (), accuracy("precise"), False)._rocker(
        0, S_EDGE, D_EDGE)
    assert rk.tips_over_on_fixed_edge(0.0, phid0, rocker)
    assert not rk.tips_over_on_fixed_edge(0.0, 0.95 * barrier_speed(), rocker)

    # its edge holds until the force it needs leaves the friction cone (mu = 0.8)
    def cone(t, z):
        tangential, normal = pinned_force(z[0], z[1])
        return 0.8 * normal - abs(tangential)

    cone.terminal = True
    sol = fixed_edge(phid0, 10.0, [cone])
    slip = run.events[0]
    assert slip.kind == "slip" and slip.stage == 1
    assert slip.time == pytest.approx(sol.t_events[0][0], abs=1e-8)
    phi, phid = sol.y_events[0][0]
    assert slip.before["phi"] == pytest.approx(phi, abs=1e-8)
    assert slip.before["spin"] == pytest.approx(phid, rel=1e-8)
    # by then its centre is past the edge's vertical (tan phi > 2 d / h): it cannot come back;
    # it slides on the edge and leaves palm 1 (friction takes energy, none is gained)
    assert math.tan(phi) > 2 * D_EDGE / H_BODY
    assert not any(e.kind == "settle" for e in run.events if e.stage == 1)
    leave = next(e for e in run.events if e.kind == "leave")
    assert leave.stage == 1 and leave.time > slip.time
    assert object_energy(leave.before) <= object_energy(slip.before) * (1 + 1e-9)


def test_the_barrier_speed_splits_settling_from_tipping_over():
    below, above = rocking_run(0.999 * barrier_speed()), rocking_run(1.001 * barrier_speed())
    # below it the object settles back on palm 1; above it, past the edge's vertical, it
    # slides off palm 1's edge and leaves it (then lands on palm 2: tumbling.py)
    assert any(e.kind == "settle" and e.stage == 1 for e in below.events)
    assert not any(e.kind == "leave" for e in below.events)
    assert any(e.kind == "leave" and e.stage == 1 for e in above.events)
    assert not any(e.kind == "settle" and e.stage == 1 for e in above.events)


def test_a_rocking_object_is_caught_by_the_next_palm():
    # palm 2 raised so that its top rests 0.05 m below palm 1's: the front corner, 0.15 m
    # beyond the edge, comes down on it where 0.15 sin phi = 0.05, before the centre passes
    # the edge's vertical (phi = atan(d / (h/2)) = 0.46)
    pitch_y = L * (math.cos(ALPHA) - math.cos(0.6))
    run = rocking_run(3.5, offsets=(offset(2, 0.0, pitch_y - 0.05),))
    catch = next(e for e in run.events if e.kind == "catch")
    phi_c = math.asin(0.05 / (W_BODY / 2 - D_EDGE))

    def reach(t, z):
        return phi_c - z[0]

    reach.terminal = True
    sol = fixed_edge(3.5, 10.0, [reach])
    assert catch.time == pytest.approx(sol.t_events[0][0], abs=1e-9)
    assert catch.before["phi"] == pytest.approx(phi_c, abs=1e-9)
    phid = sol.y_events[0][0][1]
    # the impact on the corner by Newton-Euler with the impulse P at the corner: the object's
    # momentum and spin, palm 2 (M = 10 kg) along its tangent, the corner moving with palm 2
    m, M = M_BODY, 10.0
    s, c = math.sin(phi_c), math.cos(phi_c)
    centre = (-D_EDGE * c + H_BODY / 2 * s, D_EDGE * s + H_BODY / 2 * c)  # from the pin
    corner = ((W_BODY / 2 - D_EDGE) * c, -(W_BODY / 2 - D_EDGE) * s)
    dx, dy = corner[0] - centre[0], corner[1] - centre[1]
    v0 = (phid * centre[1], -phid * centre[0])  # pin fixed: v = phi' (y, -x) of the lever
    t_hat = (math.cos(-ALPHA), -math.sin(-ALPHA))
    # unknowns: Px, Py, vx, vy, spin, w
    A = np.array([[1, 0, -m, 0, 0, 0], [0, 1, 0, -m, 0, 0],
                  [dy, -dx, 0, 0, -I_C, 0],
                  [-t_hat[0], -t_hat[1], 0, 0, 0, -M],
                  [0, 0, 1, 0, dy, -t_hat[0]], [0, 0, 0, 1, -dx, -t_hat[1]]], float)
    b = np.array([-m * v0[0], -m * v0[1], -I_C * phid, 0.0, 0.0, 0.0])
    px, py, vx, vy, spin, w = np.linalg.solve(A, b)
    assert w > 0.0 and py > 0.0 and abs(px) < 0.8 * py  # palm 2 off its stop; it sticks
    assert catch.after["spin"] == pytest.approx(spin, rel=1e-8)
    assert catch.after["omega"] * L == pytest.approx(w, rel=1e-8)
    assert catch.after["palm"] == 2


def test_a_tall_object_rocks_from_the_carry_onset_as_an_independent_integration():
    # a 0.4 x 0.9 object carried on palm 1 reaches its rear edge's onset at tan th = w/h; it
    # turns about its rear corner on the swinging palm until that corner comes down on palm 2
    w, h = 0.4, 0.9
    scene, design = make(width=w, height=h)
    result = simulate_manipulators(scene, design, stages=3, accuracy="precise")
    rock = next(e for e in result.events if e.kind == "rock")
    catch = next(e for e in result.events if e.kind == "catch")
    assert rock.before["theta"] == pytest.approx(math.atan(w / h), abs=1e-10)
    f_acc, _ = lagrangian_accelerations()
    M = 1.0 / 10.0
    ic = (w * w + h * h) / 12

    def rhs(t, z):
        a = f_acc(z[0], z[1], z[2], z[3], 1.0, M, M, ic, -w / 2, h, L, G, 0.0, 0.0)
        return [z[1], a[0], z[3], a[1]]

    theta_h = catch.before["theta"]  # where palm 1's top is palm 2's: closed form in the run

    def meets(t, z):
        return theta_h - z[0]

    meets.terminal = True
    z0 = [rock.before["theta"], rock.before["omega"], 0.0, -rk.START_ATOLS * 1e-14 / h]
    sol = solve_ivp(rhs, (0, 5), z0, rtol=1e-12, atol=1e-14, events=[meets])
    t_meet = rock.time + sol.t_events[0][0]
    assert catch.time == pytest.approx(t_meet, abs=1e-8)
    assert catch.before["phi"] == pytest.approx(sol.y_events[0][0][2], abs=1e-8)
    assert catch.before["spin"] == pytest.approx(sol.y_events[0][0][3], abs=1e-7)
    assert math.cos(theta_h) == pytest.approx(
        (L * math.cos(ALPHA) - L * (math.cos(ALPHA) - math.cos(0.6))) / L, abs=1e-9)
