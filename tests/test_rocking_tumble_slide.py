"""The rocking object sliding on its edge (sim/edgeslide.py) and tumbling in flight onto a
corner (sim/tumbling.py), docs/physics.md section 2.2b: against the pinned equations at the
friction cone's side, closed forms of a frictionless slide (the horizontal momentum, the energy),
and a flight and corner impact computed here from scratch."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from test_sim_manipulators import ALPHA, G, L, make

from pdm_design.accuracy import accuracy
from pdm_design.scenes.manipulators.sim import edgeslide as es
from pdm_design.scenes.manipulators.sim import rocking as rk
from pdm_design.scenes.manipulators.sim.run import Run

W_BODY, H_BODY, M_BODY = 0.4, 0.2, 1.0
I_C = M_BODY * (W_BODY**2 + H_BODY**2) / 12


def rotate(phi, x, y):
    """The clockwise rotation by phi, written here."""
    return x * math.cos(phi) + y * math.sin(phi), -x * math.sin(phi) + y * math.cos(phi)


def new_run(**kw):
    scene, design = make(**kw)
    run = Run(scene, design, 3, (), accuracy("precise"), False)
    run.at = 0
    run.stages.append({"manipulator": 1, "bounces": 0})
    return run


def finish(step):
    while step is not None:
        step = step()


def energy(state, palm_mass):
    """The object's and its palm's energy (the palm's pivot at height 0) from an event state."""
    phi, spin = state["phi"], state["spin"]
    rx, ry = rotate(phi, 0.0, H_BODY / 2)  # the centre from the bottom centre
    vx, vy = state["vx"] + spin * ry, state["vy"] - spin * rx
    obj = (0.5 * M_BODY * (vx * vx + vy * vy) + 0.5 * I_C * spin * spin
           + M_BODY * G * (state["y"] + ry))
    palm = (0.5 * palm_mass * (L * state["omega"]) ** 2
            + palm_mass * G * L * math.cos(state["theta"]))
    return obj + palm


def test_the_sliding_equations_meet_the_pinned_ones_at_the_friction_cone():
    # where mu is exactly |T| / N of the pinned motion, the slide that friction opposes with
    # mu N has no slip acceleration, and the same th'', phi'' and normal force (a second
    # method: Newton-Euler with the contact's force, against rocking.py's Lagrange equations)
    rng = np.random.default_rng(3)
    for _ in range(40):
        edge = bool(rng.integers(2))
        d = rng.uniform(-0.15, 0.15) if edge else W_BODY / 2 * rng.choice([-1.0, 1.0])
        felt, weight = rng.uniform(0.05, 3.0, 2)
        r = rk.Rocker(M_BODY, I_C, d, H_BODY, rng.uniform(-0.7, 0.7), felt, weight, 0.0, 0.0,
                      G, L, (0.0, 0.0), edge)
        th, om, phi, phid = rng.uniform(-0.6, 0.6, 4)
        held = bool(rng.integers(2))
        if held:
            om = 0.0
        a = rk.accelerations(th, om, phi, phid, r, held=held)
        tangential, normal = rk.pin_force(th, om, phi, phid, *a, r)
        if normal <= 0.0:
            continue
        mu, slip = abs(tangential) / normal, -math.copysign(1.0, tangential)
        z = (th, om, phi, phid, d if edge else r.e, 0.0)
        got = es.slide_accelerations(z, d, r, mu, slip, corner=not edge, held=held)
        assert got[:2] == pytest.approx(a, rel=1e-9, abs=1e-9)
        assert got[2] == pytest.approx(0.0, abs=1e-9)
        assert got[3] == pytest.approx(normal, rel=1e-9)
        # and friction short of that lets the contact slide the way slip names
        less = es.slide_accelerations(z, d, r, 0.5 * mu, slip, corner=not edge, held=held)
        assert slip * es.slip_speed((0, 0, 0, 0, 0, less[2]), not edge) > 0.0


def test_a_corner_sliding_on_a_frictionless_held_palm_falls_flat_as_in_closed_form():
    # released at phi0 on its front corner, mu = 0: no horizontal force, so the centre falls
    # straight down; the energy m g (rho_y(phi0) - h/2) = (m d^2 + I_c) phi'^2 / 2 at phi = 0
    # (the centre's speed there is d phi', straight down)
    run = new_run(mu=0.0, mass_ratio=0.1)  # a 10 kg palm: its weight holds it on its stop
    d, phi0 = W_BODY / 2, 0.3
    r = run._rocker(0, 0.0, d)
    assert not r.edge
    z0 = [-ALPHA, 0.0, phi0, 0.0, r.e, 100 * run.acc.atol]
    finish(run._edge_slide(0.0, 0, r, z0, True, 1.0, 1.0, 1.0))
    down = run.events[0]
    assert down.kind in ("settle", "rock") and down.before["phi"] == pytest.approx(0.0, abs=1e-9)
    top_x, top_y = run.row.palm_top(0, -ALPHA)
    centre_x0 = top_x + r.e + rotate(phi0, -d, H_BODY / 2)[0]
    assert down.before["x"] == pytest.approx(centre_x0, abs=1e-8)
    rho_y0 = d * math.sin(phi0) + H_BODY / 2 * math.cos(phi0)
    spin = -math.sqrt(2 * M_BODY * G * (rho_y0 - H_BODY / 2) / (M_BODY * d * d + I_C))
    assert down.before["spin"] == pytest.approx(spin, rel=1e-8)
    assert down.before["y"] == pytest.approx(top_y, abs=1e-9)


def test_a_frictionless_slide_on_a_swinging_palm_keeps_the_energy():
    # the palm's edge under the base, palm 1 swinging (0.1 kg): with mu = 0 the contact does
    # no work, so the energy of palm and object is kept through the slide
    run = new_run(mu=0.0)
    r = run._rocker(0, 0.75, 0.05)
    assert r.edge
    z0 = [0.1, 1.0, 0.2, 1.5, 0.05, -0.3]
    start = run._slide_state(0, z0, 0.05, r, False)
    finish(run._edge_slide(0.0, 0, r, z0, False, 1.0, 1.0, 1.0))
    end = run.events[0]
    assert end.time > 0.05 and end.stage == 1
    assert energy(end.before, 0.1) == pytest.approx(energy(start, 0.1), rel=1e-8)
    # with friction the slide takes energy (here until the slip stops and the edge holds)
    run = new_run(mu=0.4)
    finish(run._edge_slide(0.0, 0, r, z0, False, 1.0, 1.0, 1.0))
    end = run.events[0]
    assert end.kind == "stick" and energy(end.before, 0.1) < energy(start, 0.1) - 1e-3


def newton_euler_corner_impact(v, spin, r, t_hat, M, held, w0=0.0):
    """The plastic sticking impact at a corner r (from the centre) on a palm of mass M moving
    along t_hat at w0 before: unknowns Px, Py, vx, vy, spin, w (the palm's speed after)."""
    m, (dx, dy) = M_BODY, r
    A = np.array([[1, 0, -m, 0, 0, 0], [0, 1, 0, -m, 0, 0],
                  [dy, -dx, 0, 0, -I_C, 0],
                  [-t_hat[0], -t_hat[1], 0, 0, 0, -M],
                  [0, 0, 1, 0, dy, -t_hat[0]], [0, 0, 0, 1, -dx, -t_hat[1]]], float)
    b = np.array([-m * v[0], -m * v[1], -I_C * spin, -M * w0, 0.0, 0.0])
    if held:  # the stop takes the palm's impulse: w = 0
        A[3], b[3] = [0, 0, 0, 0, 0, 1], 0.0
    return np.linalg.solve(A, b)


def test_a_tumbling_object_lands_on_its_corner_where_its_flight_meets_the_palm():
    run = new_run(mass_ratio=0.1)
    top_x, top_y = run.row.palm_top(1, -ALPHA)
    c0, v0 = (top_x - 0.1, top_y + 0.35), (1.2, -0.4)
    phi0, spin0 = 0.25, 2.0
    finish(run._tumble(0.0, 0, (*c0, *v0, phi0, spin0), (), None))
    landing = next(e for e in run.events if e.kind == "landing")

    def corner(t, bx=W_BODY / 2):  # the front base corner, from the flight written here
        dx, dy = rotate(phi0 + spin0 * t, bx, -H_BODY / 2)
        return c0[0] + v0[0] * t + dx, c0[1] + v0[1] * t - G * t * t / 2 + dy

    ts = np.linspace(0.0, 1.0, 20001)
    first = next(t for t in ts if corner(t)[1] < top_y)  # the rear corner stays higher
    assert all(corner(t, -W_BODY / 2)[1] > top_y for t in ts[ts <= first])
    t_land = brentq(lambda t: corner(t)[1] - top_y, first - 1e-4, first, xtol=1e-15)
    assert landing.time == pytest.approx(t_land, abs=1e-9)
    phi = phi0 + spin0 * t_land
    assert landing.before["phi"] == pytest.approx(phi, abs=1e-9)
    assert landing.stage == 2 and abs(corner(t_land)[0] - top_x) < 0.8
    # the impact: Newton-Euler at the corner, palm 2 (10 kg) off its stop or held by it
    r = rotate(phi, W_BODY / 2, -H_BODY / 2)
    v = (v0[0], v0[1] - G * t_land)
    t_hat = (math.cos(-ALPHA), -math.sin(-ALPHA))
    px, py, vx, vy, spin, w = newton_euler_corner_impact(v, spin0, r, t_hat, 10.0, False)
    if w < 0.0:
        px, py, vx, vy, spin, w = newton_euler_corner_impact(v, spin0, r, t_hat, 10.0, True)
    assert py > 0.0 and abs(px) < 0.8 * py
    assert landing.after["spin"] == pytest.approx(spin, rel=1e-8)
    assert landing.after["omega"] * L == pytest.approx(w, abs=1e-10)
    assert landing.after["palm"] == 2


def test_the_sliding_impact_against_newton_euler():
    # slide_impact against the impulse P (n + mu_s tau) at the contact written here: the
    # object's momentum and spin, the palm's momentum along t (the velocities after from the
    # coordinates' rates, which keep the contact: no normal approach after)
    rng = np.random.default_rng(11)
    for _ in range(30):
        edge = bool(rng.integers(2))
        d = rng.uniform(-0.15, 0.15) if edge else W_BODY / 2 * rng.choice([-1.0, 1.0])
        felt = rng.uniform(0.1, 2.0)
        r = rk.Rocker(M_BODY, I_C, d, H_BODY, 0.3, felt, felt, 0.0, 0.0, G, L, (0.0, 0.0), edge)
        th, om, phi = rng.uniform(-0.5, 0.5, 3)
        v, spin = rng.uniform(-2, 2, 2), rng.uniform(-3, 3)
        mu, slip = rng.uniform(0.1, 1.0), rng.choice([-1.0, 1.0])
        th1, phi1, u1, p = es.slide_impact(tuple(v), spin, th, om, phi, d, r, mu, slip,
                                           corner=not edge)
        n = (math.sin(phi), math.cos(phi)) if edge else (0.0, 1.0)
        tau = (math.cos(phi), -math.sin(phi)) if edge else (1.0, 0.0)
        f = (n[0] - mu * slip * tau[0], n[1] - mu * slip * tau[1])
        lever = rotate(phi, -d, H_BODY / 2)  # the centre from the contact
        t_hat = (math.cos(th), -math.sin(th))
        vx, vy = rk.centre_velocity(th, th1, phi, phi1, r)
        if edge:  # the base's point on the edge moves along the base at u'
            vx, vy = vx - u1 * tau[0], vy - u1 * tau[1]
        else:
            vx += u1
        assert M_BODY * (vx - v[0]) == pytest.approx(p * f[0], abs=1e-10)
        assert M_BODY * (vy - v[1]) == pytest.approx(p * f[1], abs=1e-10)
        moment = -lever[1] * f[0] + lever[0] * f[1]  # clockwise, about the centre
        assert I_C * (phi1 - spin) == pytest.approx(p * moment, abs=1e-10)
        assert felt * L * (th1 - om) == pytest.approx(-p * (f[0] * t_hat[0] + f[1] * t_hat[1]),
                                                      abs=1e-10)


def test_an_object_rolling_over_its_front_corner_comes_down_on_its_front_face():
    # a tall object (0.2 x 0.4 m) on a held palm (10 kg; mu = 40: its corner holds, the
    # pinned force needs |T| / N up to 32 on the way) turns about its front base corner from
    # phi = 0 at 1.1 times the speed that brings its centre over the corner, its normal force
    # positive all the way (0.14 N least, at pi/2); at pi/2 (energy: I_P phi'^2 / 2 + m g rho_y
    # const) its front face comes down: a plastic impact about that face's far end, the old
    # front top corner, keeping the angular momentum about it
    w, h = 0.2, 0.4
    run = new_run(mu=40.0, mass_ratio=0.1, width=w, height=h)
    d, i_c = w / 2, M_BODY * (w * w + h * h) / 12
    i_p = i_c + M_BODY * (d * d + h * h / 4)
    barrier = math.sqrt(2 * M_BODY * G * (math.hypot(d, h / 2) - h / 2) / i_p)
    phid0 = 1.1 * barrier
    finish(run._rock(0.0, 0, 0.0, d, (-ALPHA, 0.0, 0.0, phid0), True))
    roll = run.events[0]
    assert roll.kind == "roll" and roll.before["phi"] == pytest.approx(math.pi / 2, abs=1e-9)
    spin = math.sqrt(phid0**2 + 2 * M_BODY * G * (h / 2 - d) / i_p)  # rho_y: h/2 -> d
    assert roll.before["spin"] == pytest.approx(spin, rel=1e-8)
    # about the far end Q of the front face (h ahead of the corner) the centre is at
    # r = (h/2 - h, d) and moves at spin (d, -h/2) (turning about the corner)
    r, v = (h / 2 - h, d), (spin * d, -spin * h / 2)
    moment = i_c * spin + M_BODY * (r[1] * v[0] - r[0] * v[1])
    after = moment / (i_c + M_BODY * (r[0] ** 2 + r[1] ** 2))
    down = run.events[1]
    assert run.face == 1  # its front face is its base now (0.4 wide, 0.2 high)
    assert (run.row.body_width, run.h) == (h, w)
    assert after < 0.0  # (-0.0133 spin / I_Q) that would press the corner down: it lies flat
    assert down.kind == "settle"
    # flat: a plastic sticking landing on palm 1 (10 kg, along t at -alpha; section 2.2a's
    # kept momentum along t, the palm held only if that drives it back), the impulse's moment
    # taking the spin at x_b = (I_c spin - (h'/2) P_x) / P_y on the new base (0.4 m wide,
    # h' = 0.2, centred 0.2 m ahead of the old corner): inside it
    t_hat = (math.cos(-ALPHA), -math.sin(-ALPHA))
    u = max(M_BODY * (v[0] * t_hat[0] + v[1] * t_hat[1]) / (M_BODY + 10.0), 0.0)
    px, py = M_BODY * (u * t_hat[0] - v[0]), M_BODY * (u * t_hat[1] - v[1])
    x_b = (i_c * spin - w / 2 * px) / py
    assert -h / 2 < x_b < h / 2 and abs(px) < 40.0 * py
    assert down.after["vx"] == pytest.approx(u * t_hat[0], rel=1e-9, abs=1e-12)
    assert down.after["vy"] == pytest.approx(u * t_hat[1], rel=1e-9, abs=1e-12)


def test_a_rocking_object_caught_on_the_next_palms_rear_edge():
    # the object (turned nose up, phi = -0.1) comes down with its base on palm 2's rear top
    # corner, 0.1 m ahead of the base's centre, while its contact on palm 1 moves away: a
    # plastic impact about that point, against Newton-Euler at it (palm 2 of 10 kg along t),
    # the impulse inside the friction cone of the base (its normal R(phi) y)
    run = new_run(mass_ratio=0.1)
    top_x, top_y = run.row.palm_top(1, -ALPHA)
    contact, phi, d = (top_x - 0.8, top_y), -0.1, 0.1
    lever = rotate(phi, -d, H_BODY / 2)  # the centre from the contact
    centre = (contact[0] + lever[0], contact[1] + lever[1])
    v, spin = (1.0, -1.5), 0.5
    state = {"x": centre[0], "y": centre[1], "vx": v[0], "vy": v[1], "theta": 0.5,
             "omega": 3.0, "offset": 0.0, "phi": phi, "spin": spin}
    old = ((centre[0] - 0.3, centre[1] - 0.2), (0.0, 1.0), (0.5, 3.0))  # palm 1 moving off
    run._catch(0.0, 0, 1, d, (contact[0], phi, v, spin, centre), old, state, edge=-0.8)
    catch = run.events[-1]
    assert catch.kind == "catch" and catch.after["palm"] == 2
    r = (-lever[0], -lever[1])  # the contact from the centre
    t_hat = (math.cos(-ALPHA), -math.sin(-ALPHA))
    px, py, vx, vy, spin1, w = newton_euler_corner_impact(v, spin, r, t_hat, 10.0, False)
    if w < 0.0:
        px, py, vx, vy, spin1, w = newton_euler_corner_impact(v, spin, r, t_hat, 10.0, True)
    normal = px * math.sin(phi) + py * math.cos(phi)
    along = px * math.cos(phi) - py * math.sin(phi)
    assert normal > 0.0 and abs(along) < 0.8 * normal
    assert catch.after["spin"] == pytest.approx(spin1, rel=1e-9)
    assert catch.after["omega"] * L == pytest.approx(w, abs=1e-12)
    # turned nose down instead, the rest of it would be below palm 2's top: not followed
    run = new_run(mass_ratio=0.1)
    run._catch(0.0, 0, 1, d, (contact[0], 0.1, v, spin, centre), old, state, edge=-0.8)
    assert run.failure.kind == "tip"


def test_a_tumbling_object_comes_back_down_on_the_palm_it_left_while_that_palm_swings():
    # the object leaves palm 1 (0.1 kg, swinging alone from th = -0.1 at th' = 1.5: l th'' =
    # g sin th) with the palm's velocity, 0.5 m/s upwards more and a spin: the palm's top
    # falls slower than g there, so the object comes back down on it. The landing where the
    # lowest corner's path (written here) meets the palm's top (scipy's pendulum), and the
    # impact against Newton-Euler with the palm moving
    from scipy.integrate import solve_ivp

    run = new_run()
    th0, om0 = -0.1, 1.5
    top_x, top_y = run.row.palm_top(0, th0)
    c0 = (top_x + 0.1, top_y + H_BODY / 2 + 1e-3)
    t_hat0 = (math.cos(th0), -math.sin(th0))
    v0 = (L * om0 * t_hat0[0], L * om0 * t_hat0[1] + 0.5)
    phi0, spin0 = 0.0, 0.8
    state = {"x": c0[0], "y": c0[1] - H_BODY / 2, "vx": v0[0], "vy": v0[1]}
    run.rest_since[0] = math.inf  # palm 1 carried the object: it is off its stops
    finish(run._leave(0.0, 0, th0, om0, (*c0, *v0, phi0, spin0), L, state, "(test)"))
    landing = next(e for e in run.events if e.kind == "landing")
    assert landing.stage == 1 and landing.after["palm"] == 1

    def palm(t):
        sol = solve_ivp(lambda t, y: [y[1], G * math.sin(y[0]) / L], (0.0, t), [th0, om0],
                        rtol=1e-12, atol=1e-13)
        return sol.y[0][-1], sol.y[1][-1]

    def gap(t, bx=W_BODY / 2):  # the front base corner above the palm's top (it turns forward)
        dx, dy = rotate(phi0 + spin0 * t, bx, -H_BODY / 2)
        return c0[1] + v0[1] * t - G * t * t / 2 + dy - (L * math.cos(palm(t)[0]))

    ts = np.linspace(1e-4, 1.0, 2001)
    first = next(t for t in ts if gap(t) < 0.0)
    t_land = brentq(gap, first - 5e-4, first, xtol=1e-14)
    assert landing.time == pytest.approx(t_land, abs=1e-8)
    theta, omega = palm(t_land)
    assert landing.after["theta"] == pytest.approx(theta, abs=1e-8)
    phi = phi0 + spin0 * t_land
    r = rotate(phi, W_BODY / 2, -H_BODY / 2)
    v = (v0[0], v0[1] - G * t_land)
    t_hat = (math.cos(theta), -math.sin(theta))
    px, py, vx, vy, spin, w = newton_euler_corner_impact(v, spin0, r, t_hat, 0.1, False,
                                                         L * omega)
    assert py > 0.0 and abs(px) < 0.8 * py
    assert landing.after["spin"] == pytest.approx(spin, rel=1e-8)
    assert landing.after["omega"] * L == pytest.approx(w, rel=1e-8)
