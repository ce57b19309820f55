"""The manipulators event simulator against independent numbers.

Every expected value here comes from a closed form written out in the test, an elliptic
integral, a sympy derivation or a separate integration - never from the simulator's output.
Frame: origin at pivot 1, x along the row, y up; theta clockwise from the vertical.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipkinc

from pdm_design.scenes.manipulators import physics as phys
from pdm_design.scenes.manipulators.model import (
    Body,
    ManipulatorsDesign,
    ManipulatorsInitial,
    ManipulatorsScene,
    Palm,
)
from pdm_design.scenes.manipulators.sim import (
    EVENT_KINDS,
    FAILURE_KINDS,
    handover_angle,
    handover_map,
    simulate_manipulators,
)
from pdm_design.scenes.manipulators.sim import phases as ph
from pdm_design.spec.loader import load_spec

ROOT = Path(__file__).resolve().parents[1]
G = 9.81
# Paper example 3 (eqs. 37-40) with our object and palm sizes (problems/paper_manipulators.toml)
ALPHA, BETA, L, Q, MU = 0.2, 0.6, 2.0, 10.0, 0.8
X0, Y0, VX0, VY0 = -1.25, 3.05, 3.0, 0.0
# Tolerance on times, angles and speeds per accuracy preset (event_tol plus integration error)
TOL = {"fast": 1e-6, "default": 1e-9, "precise": 1e-11}


def offset(manipulator, dx=0.0, dy=0.0):
    return SimpleNamespace(manipulator=manipulator, dx=dx, dy=dy)


def make(*, width=0.4, height=0.2, palm_width=1.6, mu=MU, eps=0.0, front_stop=math.pi / 2,
         position=(X0, Y0), velocity=(VX0, VY0), alpha=ALPHA, beta=BETA, mass_ratio=Q,
         first_pivot_x=0.0):
    scene = ManipulatorsScene(
        body=Body(mass=1.0, width=width, height=height),
        palm=Palm(width=palm_width, thickness=0.05, friction=mu, restitution=eps,
                  front_stop=front_stop),
        initial=ManipulatorsInitial(position=position, velocity=velocity), gravity=G)
    design = ManipulatorsDesign(alpha=alpha, beta=beta, link_length=L, mass_ratio=mass_ratio,
                                first_pivot_x=first_pivot_x)
    return scene, design


def first_landing(x0=X0, y0=Y0, vx=VX0, vy=VY0, alpha=ALPHA):
    """Ballistic flight onto palm 1 resting at -alpha (top surface at y = l cos alpha)."""
    drop = y0 - L * math.cos(alpha)
    t = (vy + math.sqrt(vy * vy + 2 * G * drop)) / G
    return t, x0 + vx * t, vx, vy - G * t


def momentum_speed(vx, vy, alpha=ALPHA, q=Q):
    """u = m/(m+M) V.t(-alpha), t(-alpha) = (cos a, sin a)."""
    return q / (1 + q) * (vx * math.cos(alpha) + vy * math.sin(alpha))


def elliptic_swing_time(theta_a, theta_b, theta0, v0):
    """Time for l th'' = g sin th to go from theta_a to theta_b over the top (energy from
    (theta0, v0), C = cos th0 + v0^2/(2 g l) > 1). With psi = pi - th the motion is a pendulum
    rotating through its top: (psi/2)'^2 = g (C+1)/(2l) (1 - k^2 sin^2(psi/2)), k^2 = 2/(C+1),
    so t = [F((pi - th_a)/2 | k^2) - F((pi - th_b)/2 | k^2)] / sqrt(g (C+1) / (2 l))."""
    c = math.cos(theta0) + v0 * v0 / (2 * G * L)
    assert c > 1.0
    k2 = 2.0 / (c + 1.0)
    rate = math.sqrt(G * (c + 1.0) / (2.0 * L))
    return (ellipkinc((math.pi - theta_a) / 2, k2) - ellipkinc((math.pi - theta_b) / 2, k2)) / rate


def fixed_point_speed(alpha=ALPHA, beta=BETA, q=Q):
    """s*^2 = D / (1 - c), D = 2 g l (cos a - cos b), c = (m/(m+M))^2 cos^2(a + b)."""
    c = (q / (1 + q) * math.cos(alpha + beta)) ** 2
    return math.sqrt(2 * G * L * (math.cos(alpha) - math.cos(beta)) / (1 - c)), c


def events(result, kind):
    return [e for e in result.events if e.kind == kind]


def paper():
    spec = load_spec(ROOT / "problems" / "paper_manipulators.toml")
    return spec.scene, spec.design_at()


# ---------------------------------------------------------------- flight and landing

def test_first_landing_is_the_ballistic_closed_form():
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=1)
    t, x, vx, vy = first_landing()
    landing = events(result, "landing")[0]
    assert landing.time == pytest.approx(t, abs=1e-12)
    assert landing.before["x"] == pytest.approx(x, abs=1e-12)
    assert landing.before["y"] == pytest.approx(L * math.cos(ALPHA), abs=1e-12)
    assert landing.before["vy"] == pytest.approx(vy, abs=1e-12)
    stage = result.stages[0]
    assert stage["landing_offset"] == pytest.approx(x + L * math.sin(ALPHA), abs=1e-12)
    assert stage["landing_speed"] == pytest.approx(momentum_speed(vx, vy), abs=1e-12)
    # object and palm leave together along t(-alpha)
    u = momentum_speed(vx, vy)
    assert landing.after["vx"] == pytest.approx(u * math.cos(ALPHA), abs=1e-12)
    assert landing.after["vy"] == pytest.approx(u * math.sin(ALPHA), abs=1e-12)


def delassus(theta, m, inv_m):
    """W with (Delta g_t, Delta g_n) = W (p_t, p_n) for a palm at theta (derived in the docs)."""
    s, c = math.sin(theta), math.cos(theta)
    return np.array([[1 / m + c * c * inv_m, -s * c * inv_m],
                     [-s * c * inv_m, 1 / m + s * s * inv_m]])


def keller_by_steps(vx, vy, w, theta, m, inv_m, mu, eps, steps=20000):
    """Darboux-Keller impact by small steps in the normal impulse P (a second method for
    phases.impact): Coulomb friction at each step, compression until g_n = 0, then
    restitution until the normal impulse has given back eps^2 of its compression work."""
    wm = delassus(theta, m, inv_m)
    s, c = math.sin(theta), math.cos(theta)
    g = np.array([vx - w * c, vy + w * s])
    # a step size from the compression impulse of the frictionless problem
    dp = -g[1] / wm[1, 1] / steps
    p = np.zeros(2)
    work_c, work_r, compressing = 0.0, 0.0, True
    for _ in range(50 * steps):
        ratio = -wm[0, 1] / wm[0, 0]
        if abs(g[0]) < 1e-12 and abs(ratio) <= mu:
            rate = ratio
        else:
            sigma = math.copysign(1.0, g[0]) if abs(g[0]) >= 1e-12 else math.copysign(1.0, wm[0, 1])
            rate = -sigma * mu
        dg = wm @ np.array([rate, 1.0]) * dp
        if abs(g[0]) >= 1e-12 and g[0] * (g[0] + dg[0]) < 0:  # slip stops inside this step
            frac = -g[0] / dg[0]
            g, p = g + frac * dg, p + frac * np.array([rate, 1.0]) * dp
            work = g[1] * frac * dp
            g[0] = 0.0
        else:
            work = (g[1] + 0.5 * dg[1]) * dp
            g, p = g + dg, p + np.array([rate, 1.0]) * dp
        if compressing:
            work_c += work
            if g[1] >= 0:
                compressing = False
                if eps == 0:
                    break
        else:
            work_r += work
            if work_r >= -eps * eps * work_c:
                break
    return vx + p[0] / m, vy + p[1] / m, w - (p[0] * c - p[1] * s) * inv_m


def test_restitution_bounce_keeps_momentum_and_matches_a_stepped_impact():
    eps = 0.5
    scene, design = make(eps=eps)
    result = simulate_manipulators(scene, design, stages=1)
    landing = events(result, "landing")[0]
    assert events(result, "bounce")[0].time == landing.time
    w = L * landing.after["omega"]  # palm speed along t(-alpha) = (cos a, sin a)
    assert landing.after["vx"] - w * math.cos(ALPHA) == pytest.approx(0.0, abs=1e-12)  # sticks
    vt_before = landing.before["vx"] * math.cos(ALPHA) + landing.before["vy"] * math.sin(ALPHA)
    vt_after = landing.after["vx"] * math.cos(ALPHA) + landing.after["vy"] * math.sin(ALPHA)
    assert vt_after + w / Q == pytest.approx(vt_before, rel=1e-12)  # links: radial impulse only
    vx, vy, w2 = keller_by_steps(landing.before["vx"], landing.before["vy"], 0.0, -ALPHA, 1.0, Q,
                                 MU, eps)
    assert landing.after["vx"] == pytest.approx(vx, rel=1e-3)
    assert landing.after["vy"] == pytest.approx(vy, rel=1e-3)
    assert w == pytest.approx(w2, rel=1e-3)
    # the object slid, then stuck, in compression: the separation is not Newton's eps |g_n|
    gn_after = landing.after["vy"] - w * math.sin(ALPHA)
    assert abs(gn_after + eps * landing.before["vy"]) > 0.05


def test_side_hit_in_flight_is_followed_from_where_the_faces_meet():
    # manipulator 2 raised 0.5 m: its palm's rear end stands in the flight path
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=3, offsets=[offset(2, dy=0.5)])
    pitch_x, pitch_y = phys.pitch(ALPHA, BETA, L)
    rear_end = pitch_x - L * math.sin(ALPHA) - 0.8  # palm 2 at -alpha, half width 0.8
    t = (rear_end - 0.2 - X0) / VX0  # object's front face (half width 0.2) reaches it
    y = Y0 - 0.5 * G * t * t
    top2 = -pitch_y + 0.5 + L * math.cos(ALPHA)
    assert top2 - 0.05 - 0.2 < y < top2  # the object's side overlaps the slab's end then
    hit = result.events[0]  # from there the time stepping follows it (sim/stepped.py)
    assert hit.kind == "stepped" and "hit the side of palm 2" in hit.detail
    assert hit.time == pytest.approx(t, abs=1e-12)
    # it falls back onto palm 1 (which it had not reached) and palm 2, struck, swings forward
    assert any(e.kind == "stepped" and "lies on palm 1" in e.detail for e in result.events)
    assert any(e.kind == "front_stop" and e.stage == 2 for e in result.events)


def test_carried_object_meeting_the_next_palm_rear_end_pushes_it():
    # palm 1 centred under the landing point, narrow palms, manipulator 2 raised 0.4 m: the
    # object's front face meets palm 2's rear end above its base and pushes it off its back
    # stop (sim/pushing.py), at the angle where the face reaches that end
    t_land, x_land, _, _ = first_landing()
    px1 = x_land + L * math.sin(ALPHA)
    scene, design = make(palm_width=1.0, first_pivot_x=px1)
    result = simulate_manipulators(scene, design, stages=3, offsets=[offset(2, dy=0.4)])
    pitch_x, pitch_y = phys.pitch(ALPHA, BETA, L)
    rear_end = px1 + pitch_x - L * math.sin(ALPHA) - 0.5
    theta = math.asin((rear_end - 0.2 - px1) / L)  # object centred on palm 1 (offset 0)
    top2 = -pitch_y + 0.4 + L * math.cos(ALPHA)
    assert top2 - 0.05 - 0.2 < L * math.cos(theta) < top2
    push = next(e for e in result.events if e.kind == "push")
    assert push.stage == 1 and "palm 2" in push.detail
    assert push.before["theta"] == pytest.approx(theta, abs=1e-12)
    assert push.after["omega"] < push.before["omega"]  # the push slows the carry
    assert push.after["palm_omega"] > 0.0


def algebraic_plastic_impact(vx, vy, w, theta, m, inv_m, mu):
    """The plastic impact by the model's rule (docs/manipulators_model.md 2.2): the sticking
    impulse if it is inside the friction cone, else Coulomb sliding throughout (|p_t| = mu p_n,
    g_n ends at 0)."""
    wm = delassus(theta, m, inv_m)
    s, c = math.sin(theta), math.cos(theta)
    g = np.array([vx - w * c, vy + w * s])
    pt, pn = np.linalg.solve(wm, -g)
    if not (pn >= 0 and abs(pt) <= mu * pn):
        sigma = -math.copysign(1.0, pt)
        pn = -g[1] / (wm[1, 1] - sigma * mu * wm[0, 1])
        pt = -sigma * mu * pn
    return vx + pt / m, vy + pn / m, w - (pt * c - pn * s) * inv_m


def test_impacts_keep_momentum_obey_coulomb_dissipate_and_match_second_methods():
    """Random impacts on a moving palm: m V.t + M w is kept (the links take radial impulse only),
    the impulse lies in the friction cone, kinetic energy never grows; plastic impacts equal the
    algebraic stick-or-slide rule wherever friction can hold a stuck contact during the impact
    (|W_tn| <= mu W_tt); the rest (restitution, slip reversal) equal a stepped Keller
    integration."""
    rng = np.random.default_rng(1)
    seen = {"stick": 0, "slide": 0}
    stepped = 0
    for i in range(3000):
        theta, w = rng.uniform(-1.4, 1.4), rng.uniform(-4, 4)
        vx, vy = rng.uniform(-5, 5), rng.uniform(-5, 5)
        m, big_m, mu = 1.0, 10 ** rng.uniform(-2, 2), rng.uniform(0, 2)
        eps = 0.0 if i % 2 else rng.uniform(0, 1)
        gn = vy + w * math.sin(theta)
        if gn >= 0:
            continue
        imp = ph.impact(vx, vy, w, theta, m=m, inv_M=1 / big_m, mu=mu, eps=eps)
        assert not imp.jam
        t = (math.cos(theta), -math.sin(theta))
        before = m * (vx * t[0] + vy * t[1]) + big_m * w
        after = m * (imp.vx * t[0] + imp.vy * t[1]) + big_m * imp.w
        assert after == pytest.approx(before, abs=1e-9 * (1 + abs(before)))
        assert imp.pn >= 0 and abs(imp.pt) <= mu * imp.pn * (1 + 1e-12) + 1e-12
        ke_before = 0.5 * m * (vx * vx + vy * vy) + 0.5 * big_m * w * w
        ke_after = 0.5 * m * (imp.vx ** 2 + imp.vy ** 2) + 0.5 * big_m * imp.w ** 2
        assert ke_after <= ke_before * (1 + 1e-12) + 1e-12
        # the impulse ratio that keeps a stuck contact stuck during the impact
        s, c = math.sin(theta), math.cos(theta)
        holds = abs(s * c / big_m) / (1 / m + c * c / big_m) <= mu
        if eps == 0.0 and holds:
            expected = algebraic_plastic_impact(vx, vy, w, theta, m, 1 / big_m, mu)
            np.testing.assert_allclose((imp.vx, imp.vy, imp.w), expected, rtol=1e-9, atol=1e-9)
            seen["stick" if imp.stick else "slide"] += 1
        elif stepped < 40:  # restitution, or a slip that reverses during the impact
            stepped += 1
            expected = keller_by_steps(vx, vy, w, theta, m, 1 / big_m, mu, eps, steps=4000)
            np.testing.assert_allclose((imp.vx, imp.vy, imp.w), expected, rtol=2e-3, atol=2e-3)
    assert min(seen.values()) > 100


# ---------------------------------------------------------------- stuck carry

@pytest.mark.parametrize("preset", ["fast", "default", "precise"])
def test_carry_time_is_the_elliptic_integral(preset):
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=2, accuracy=preset)
    _, _, vx, vy = first_landing()
    u = momentum_speed(vx, vy)
    stage = result.stages[0]
    expected = elliptic_swing_time(-ALPHA, BETA, -ALPHA, u)
    assert stage["handover_time"] - stage["landing_time"] == pytest.approx(expected,
                                                                          abs=TOL[preset])
    assert stage["handover_angle"] == pytest.approx(BETA, abs=TOL[preset])


def test_swing_time_to_a_turning_point_matches_an_ode():
    # the quadrature with the 1/sqrt singularity at the turning point, against solve_ivp
    theta0, v0 = -0.3, 1.0
    turn = ph.turning_angle(theta0, v0, gravity=G, link_length=L)
    assert turn == pytest.approx(-math.acos(math.cos(theta0) + v0 ** 2 / (2 * G * L)), abs=1e-15)
    t = ph.swing_time(theta0, turn, theta0, v0, gravity=G, link_length=L, turn=turn)

    def stop(t, y):
        return y[1]

    stop.terminal, stop.direction = True, -1
    sol = solve_ivp(lambda t, y: [y[1], G / L * math.sin(y[0])], (0, 10), [theta0, v0 / L],
                    method="DOP853", rtol=1e-13, atol=1e-15, events=stop)
    assert t == pytest.approx(sol.t_events[0][0], abs=1e-10)


@pytest.mark.parametrize("preset", ["fast", "default", "precise"])
def test_lift_off_where_v_squared_reaches_g_l_cos_theta(preset):
    # beta pushed to 1.0 with enough friction not to slip: the palm's push vanishes first
    scene, design = make(beta=1.0, mu=2.0)
    result = simulate_manipulators(scene, design, stages=2, accuracy=preset)
    _, _, vx, vy = first_landing()
    u = momentum_speed(vx, vy)
    # v^2 = u^2 + 2 g l (cos a - cos th) = g l cos th
    theta = math.acos((u * u + 2 * G * L * math.cos(ALPHA)) / (3 * G * L))
    assert theta < 1.0
    assert u * u + 2 * G * L * (math.cos(ALPHA) - math.cos(1.0)) > G * L * math.cos(1.0)
    # a lift-off is an event, not a failure: the object flies on (tests/test_lift_off_flight.py)
    lift = next(e for e in result.events if e.kind == "lift_off" or e.failure)
    assert lift.kind == "lift_off" and lift.stage == 1 and not lift.failure
    assert lift.before["theta"] == pytest.approx(theta, abs=TOL[preset])
    t_land, _, _, _ = first_landing()
    assert lift.time == pytest.approx(t_land + elliptic_swing_time(-ALPHA, theta, -ALPHA, u),
                                      abs=TOL[preset])


def test_slip_where_tan_theta_reaches_mu():
    mu = 0.5
    assert math.tan(BETA) > mu
    scene, design = make(mu=mu)
    result = simulate_manipulators(scene, design, stages=2)
    slip = events(result, "slip")[0]
    assert slip.stage == 1
    assert slip.before["theta"] == pytest.approx(math.atan(mu), abs=1e-10)
    assert result.stages[0]["slipped"] is True


def test_tip_in_the_carry_for_a_tall_object():
    # force crosses the base (h/2) tan th behind the centre: leaves a w-wide base at tan th = w/h
    w, h = 0.4, 0.7
    scene, design = make(width=w, height=h)
    result = simulate_manipulators(scene, design, stages=2)
    theta = math.atan(w / h)
    assert theta < min(BETA, math.atan(MU))
    # the onset: the object turns about its rear corner from there (tests/test_rocking.py)
    rock = events(result, "rock")[0]
    assert rock.stage == 1 and "rear edge" in rock.detail
    assert rock.before["theta"] == pytest.approx(theta, abs=1e-10)


def test_tip_at_the_landing_for_a_tall_narrow_object():
    w, h = 0.2, 2.0
    scene, design = make(width=w, height=h)
    result = simulate_manipulators(scene, design, stages=2)
    t, _, vx, vy = first_landing()
    u = momentum_speed(vx, vy)
    px, py = u * math.cos(ALPHA) - vx, u * math.sin(ALPHA) - vy
    assert abs(h / 2 * px / py) > w / 2  # the impulse line leaves the base
    # the onset at the landing: the object turns forward about its front corner from there
    rock = events(result, "rock")[0]
    assert rock.time == pytest.approx(t, abs=1e-12) and rock.after["spin"] > 0.0
    assert "front edge" in rock.detail


def test_stall_when_too_slow_to_pass_the_top():
    position, velocity = (-0.5, 2.0), (0.8, 0.0)
    scene, design = make(position=position, velocity=velocity)
    result = simulate_manipulators(scene, design, stages=2)
    _, _, vx, vy = first_landing(*position, *velocity)
    u = momentum_speed(vx, vy)
    assert 0 < u * u < 2 * G * L * (1 - math.cos(ALPHA))
    turn = -math.acos(math.cos(ALPHA) + u * u / (2 * G * L))
    failure = result.outcome.failure
    assert failure.kind == "stall" and failure.stage == 1
    assert failure.before["theta"] == pytest.approx(turn, abs=1e-12)
    assert failure.before["omega"] == pytest.approx(0.0, abs=1e-6)


# ---------------------------------------------------------------- the periodic orbit

def test_handover_speed_contracts_to_the_fixed_point_by_c():
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=10)
    assert result.outcome.completed
    s_star, c = fixed_point_speed()
    speeds = [st["handover_speed"] for st in result.stages[:-1]]
    # exact: s'^2 - s*^2 = c (s^2 - s*^2)
    for a, b in zip(speeds, speeds[1:]):
        assert (b * b - s_star ** 2) / (a * a - s_star ** 2) == pytest.approx(c, rel=1e-7)
    # and the speed errors shrink by a ratio tending to c
    ratios = [(b - s_star) / (a - s_star) for a, b in zip(speeds, speeds[1:])]
    assert abs(ratios[-1] - c) < 1e-4 < abs(ratios[0] - c)
    # not to the paper's eq. 29 (cos(beta - alpha))
    paper_s = math.sqrt(float(phys.paper_handover_speed_squared(ALPHA, BETA, Q, gravity=G,
                                                                link_length=L)))
    assert abs(speeds[-1] - paper_s) > 1.0


def periodic_start(tau=0.1):
    """Initial state that lands on palm 1's centre at s* along t(beta), tau seconds later."""
    s_star, _ = fixed_point_speed()
    vx, vy = s_star * math.cos(BETA), -s_star * math.sin(BETA)
    xl, yl = -L * math.sin(ALPHA), L * math.cos(ALPHA)
    return (xl - vx * tau, yl - vy * tau - 0.5 * G * tau * tau), (vx, vy + G * tau)


def test_periodic_start_repeats_the_fixed_point():
    position, velocity = periodic_start()
    scene, design = make(position=position, velocity=velocity)
    result = simulate_manipulators(scene, design, stages=5)
    s_star, _ = fixed_point_speed()
    assert result.outcome.completed
    for st in result.stages[:-1]:
        assert st["handover_speed"] == pytest.approx(s_star, abs=1e-9)
        assert st["landing_offset"] == pytest.approx(0.0, abs=1e-9)


def test_energy_per_periodic_stage():
    """Object + palm k from landing to release: the object loses m g p (p = pitch_y) of
    mechanical energy per periodic stage; it goes into the impact loss
    L = m s^2/2 - (m+M) u^2/2 and the released palm's mechanical energy M s^2/2 - M g p (it
    leaves at speed s, p lower than where it rested): L + M s^2/2 - M g p = m g p."""
    position, velocity = periodic_start()
    scene, design = make(position=position, velocity=velocity)
    result = simulate_manipulators(scene, design, stages=4)
    # every stage run: a spurious failure would leave the loop below nothing to check
    assert result.outcome.completed and result.outcome.failure is None, result.outcome
    assert result.outcome.stages_passed == len(result.stages) == 4
    m, big_m = 1.0, 1.0 / Q
    _, p = phys.pitch(ALPHA, BETA, L)
    checked = 0
    for st in result.stages[:-1]:
        v2 = st["landing_vx"] ** 2 + st["landing_vy"] ** 2
        loss = 0.5 * m * v2 - 0.5 * (m + big_m) * st["landing_speed"] ** 2
        palm = 0.5 * big_m * st["release_speed"] ** 2 - big_m * G * p
        assert loss + palm == pytest.approx(m * G * p, rel=1e-9)
        checked += 1
    assert checked == 3


def test_energy_per_stage_on_the_approach():
    """Off the periodic orbit the same balance reads: impact loss + released palm's energy =
    the object's energy drop between consecutive handovers (m s_k^2/2 - m s_k+1^2/2 + m g p)."""
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=5)
    assert result.outcome.completed and result.outcome.failure is None, result.outcome
    assert result.outcome.stages_passed == len(result.stages) == 5
    m, big_m = 1.0, 1.0 / Q
    _, p = phys.pitch(ALPHA, BETA, L)
    checked = 0
    for prev, st in zip(result.stages, result.stages[1:-1]):
        s_in, s_out = prev["handover_speed"], st["handover_speed"]
        loss = 0.5 * m * s_in ** 2 - 0.5 * (m + big_m) * st["landing_speed"] ** 2
        palm = 0.5 * big_m * st["release_speed"] ** 2 - big_m * G * p
        drop = 0.5 * m * (s_in ** 2 - s_out ** 2) + m * G * p
        assert loss + palm == pytest.approx(drop, rel=1e-9)
        checked += 1
    assert checked == 3


def test_handover_map_is_the_iterated_closed_form():
    s = np.linspace(2.0, 6.0, 101)
    got = handover_map(s, ALPHA, BETA, Q, G, L)
    expected = [float(phys.next_handover_speed(v, ALPHA, BETA, Q, gravity=G, link_length=L))
                for v in s]
    np.testing.assert_allclose(got, expected, rtol=1e-14)
    # iterating it lands on s* = sqrt(D / (1 - c))
    x = np.array([0.5, 3.0, 10.0])
    x = np.where(np.isnan(handover_map(x, ALPHA, BETA, Q, G, L)), 3.0, x)
    for _ in range(60):
        x = handover_map(x, ALPHA, BETA, Q, G, L)
    np.testing.assert_allclose(x, fixed_point_speed()[0], rtol=1e-12)


def test_handover_map_is_nan_where_the_carry_stalls():
    u_top = math.sqrt(2 * G * L * (1 - math.cos(ALPHA)))
    s_top = u_top / (Q / (1 + Q) * math.cos(ALPHA + BETA))
    out = handover_map([0.99 * s_top, 1.01 * s_top], ALPHA, BETA, Q, G, L)
    assert math.isnan(out[0]) and math.isfinite(out[1])


def test_handover_map_with_real_angles_matches_the_simulator():
    # manipulator 3 lowered 5 cm: palm 2 carries past beta, palm 3 hands over early; no slip
    dy = -0.05
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=6, offsets=[offset(3, dy=dy)])
    assert result.outcome.completed
    angles = [BETA, float(handover_angle(BETA, dy, L)), float(handover_angle(BETA, -dy, L)),
              BETA, BETA]
    assert not any(st["slipped"] for st in result.stages)
    speeds = [st["handover_speed"] for st in result.stages[:-1]]
    for k in range(1, 5):
        predicted = handover_map(speeds[k - 1], ALPHA, BETA, Q, G, L,
                                 arrival_angle=angles[k - 1], departure_angle=angles[k])
        assert result.stages[k]["handover_angle"] == pytest.approx(angles[k], abs=1e-10)
        assert speeds[k] == pytest.approx(float(predicted), abs=1e-9)


# ---------------------------------------------------------------- sliding carry

def lagrangian_sliding():
    """th'', s'' of the sliding carry from Lagrange's equations in (th, s) (independent of
    manip_phases): object at (l sin th + s, l cos th), palm at (l sin th, l cos th); the
    friction pair does virtual work -f ds only, f = mu sgn N, N = m (y_obj'' + g)."""
    sp = pytest.importorskip("sympy")
    t = sp.symbols("t")
    m, big_m, g, l, mu, sgn = sp.symbols("m M g l mu sgn")
    th, s = sp.Function("th")(t), sp.Function("s")(t)
    xo, yo = l * sp.sin(th) + s, l * sp.cos(th)
    xp, yp = l * sp.sin(th), l * sp.cos(th)
    lag = (m * (xo.diff(t) ** 2 + yo.diff(t) ** 2) / 2 + big_m * (xp.diff(t) ** 2
           + yp.diff(t) ** 2) / 2 - m * g * yo - big_m * g * yp)
    normal = m * (yo.diff(t, 2) + g)
    eqs = [sp.diff(lag.diff(th.diff(t)), t) - lag.diff(th),
           sp.diff(lag.diff(s.diff(t)), t) - lag.diff(s) + mu * sgn * normal]
    a, b, w, q = sp.symbols("a b w q")
    eqs = [e.subs({th.diff(t, 2): a, s.diff(t, 2): b}).subs(th.diff(t), w).subs(th, q)
           for e in eqs]
    sol = sp.solve(eqs, [a, b], dict=True)[0]
    n_expr = normal.subs({th.diff(t, 2): a}).subs(th.diff(t), w).subs(th, q).subs(a, sol[a])
    args = (q, w, m, big_m, g, l, mu, sgn)
    return (sp.lambdify(args, sol[a]), sp.lambdify(args, sol[b]), sp.lambdify(args, n_expr))


def test_sliding_equations_are_lagrange_equations():
    f_th, f_s, f_n = lagrangian_sliding()
    rng = np.random.default_rng(7)
    for _ in range(50):
        theta, omega = rng.uniform(-1.2, 1.2), rng.uniform(-3, 3)
        m, big_m, mu, sgn = 1.0, 10 ** rng.uniform(-2, 1), rng.uniform(0, 1.5), rng.choice([-1, 1])
        p = ph.SlideParams(m, big_m, mu, G, L, float(sgn))
        thdd, normal, sdd, d = ph.slide_accelerations(theta, omega, p)
        if abs(d) < 1e-3:
            continue
        args = (theta, omega, m, big_m, G, L, mu, sgn)
        assert thdd == pytest.approx(f_th(*args), rel=1e-10, abs=1e-10)
        assert sdd == pytest.approx(f_s(*args), rel=1e-10, abs=1e-10)
        assert normal == pytest.approx(f_n(*args), rel=1e-10, abs=1e-10)


def test_friction_work_equals_the_energy_lost_while_sliding():
    p = ph.SlideParams(1.0, 0.1, 0.8, G, L, -1.0)
    rhs = ph.slide_rhs(p)

    def energy(z):
        theta, omega, s, sd = z
        vx, vy = L * omega * math.cos(theta) + sd, -L * omega * math.sin(theta)
        ke = 0.5 * p.m * (vx * vx + vy * vy) + 0.5 * p.M * (L * omega) ** 2
        return ke + (p.m + p.M) * G * L * math.cos(theta)

    def augmented(t, z):  # last component: work done by kinetic friction, -mu N |s'|
        normal = ph.slide_accelerations(z[0], z[1], p)[1]
        return list(rhs(t, z[:4])) + [-p.mu * normal * abs(z[3])]

    z0 = [math.atan(0.8), 1.7, 0.5, -0.3]
    sol = solve_ivp(augmented, (0, 0.05), z0 + [0.0], method="DOP853", rtol=1e-12, atol=1e-14)
    z1 = sol.y[:, -1]
    assert z1[3] < 0  # still sliding the same way
    assert energy(z1[:4]) - energy(z0) == pytest.approx(z1[4], rel=1e-8)
    assert z1[4] < 0


def test_sliding_carry_matches_an_independent_integration():
    """Paper run 2 (manipulator 2 at (0.1, -0.2)): palm 1 carries past beta, the object slips at
    atan(mu) and slides until its bottom reaches palm 2's top. Integrate the Lagrangian
    equations from the slip state (closed forms) to that height and compare the handover."""
    f_th, f_s, _ = lagrangian_sliding()
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=3, offsets=[offset(2, 0.1, -0.2)])
    t_land, x_land, vx, vy = first_landing()
    u = momentum_speed(vx, vy)
    th_slip = math.atan(MU)
    v_slip = math.sqrt(u * u + 2 * G * L * (math.cos(ALPHA) - math.cos(th_slip)))
    t_slip = t_land + elliptic_swing_time(-ALPHA, th_slip, -ALPHA, u)
    th_hand = math.acos(math.cos(BETA) - 0.2 / L)  # palm 2's top is 0.2 m lower

    def rhs(t, z):
        args = (z[0], z[1], 1.0, 1.0 / Q, G, L, MU, -1.0)  # object lags: slides backwards
        return [z[1], f_th(*args), z[3], f_s(*args)]

    def reach(t, z):
        return z[0] - th_hand

    reach.terminal = True
    z0 = [th_slip, v_slip / L, x_land + L * math.sin(ALPHA), 0.0]
    sol = solve_ivp(rhs, (t_slip, t_slip + 1), z0, method="DOP853", rtol=1e-12, atol=1e-14,
                    events=reach)
    theta, omega, s, sd = sol.y_events[0][0]
    assert sd < 0  # it is still sliding
    speed = math.hypot(L * omega * math.cos(theta) + sd, L * omega * math.sin(theta))
    stage = result.stages[0]
    assert stage["slipped"]
    assert stage["handover_angle"] == pytest.approx(th_hand, abs=1e-9)
    assert stage["handover_time"] == pytest.approx(sol.t_events[0][0], abs=1e-8)
    assert stage["handover_speed"] == pytest.approx(speed, abs=1e-8)
    assert result.stages[1]["landing_offset"] == pytest.approx(
        s + L * math.sin(theta) - (phys.pitch(ALPHA, BETA, L)[0] + 0.1 - L * math.sin(ALPHA)),
        abs=1e-8)


# ---------------------------------------------------------------- the paper's three runs

def test_paper_run_nominal_completes():
    scene, design = paper()
    result = simulate_manipulators(scene, design, stages=6)
    assert result.outcome.completed and result.outcome.stages_passed == 6
    assert result.outcome.failure is None
    assert [st["manipulator"] for st in result.stages] == [1, 2, 3, 4, 5, 6]
    assert all(st["handover_angle"] == pytest.approx(BETA, abs=1e-10) for st in result.stages)
    assert not any(st["slipped"] for st in result.stages)


def test_paper_run_second_manipulator_offset_continues_back_to_the_fixed_point():
    scene, design = paper()
    result = simulate_manipulators(scene, design, stages=6, offsets=[offset(2, 0.1, -0.2)])
    assert result.outcome.completed and result.outcome.stages_passed == 6
    s_star, c = fixed_point_speed()
    # palm 2 sits 0.2 m low: palm 1 carries to acos(cos b - 0.1); palm 3 is 0.2 m high
    # relative to palm 2: palm 2 hands over early, at acos(cos b + 0.1)
    angles = [st["handover_angle"] for st in result.stages]
    assert angles[0] == pytest.approx(math.acos(math.cos(BETA) - 0.1), abs=1e-9)
    assert angles[1] == pytest.approx(math.acos(math.cos(BETA) + 0.1), abs=1e-9)
    assert angles[2:] == pytest.approx([BETA] * 4, abs=1e-9)
    speeds = [st["handover_speed"] for st in result.stages[:-1]]
    errors = [abs(v - s_star) for v in speeds]
    assert errors[2] > errors[3] > errors[4]  # back towards s*, by about c per stage
    assert errors[4] / errors[3] == pytest.approx(c, rel=0.05)


def test_paper_run_large_offset_lifts_off_and_flies_over_the_low_palm():
    scene, design = paper()
    result = simulate_manipulators(scene, design, stages=6, offsets=[offset(2, 0.0, -0.4)])
    # palm 2 is 0.4 m low: palm 1 must carry to acos(cos b - 0.2) = 0.895 rad, but the object
    # slips at atan(mu) = 0.675 and the palm's push vanishes (v^2 > g l cos th near 0.78) first
    kinds = [e.kind for e in result.events if e.kind not in ("front_stop", "back_stop")]
    assert kinds[:3] == ["landing", "slip", "lift_off"]
    lift = result.events[kinds.index("lift_off")]
    assert lift.stage == 1 and not lift.failure
    assert math.atan(MU) < lift.before["theta"] < math.acos(math.cos(BETA) - 0.2)
    # palm 2, 0.4 m > pitch_y = 0.31 m low, sits below palm 3's top: the object flies over it
    # and comes down on palm 3: palm 2 is skipped, a failure unless the spec allows skips
    failure = result.outcome.failure
    assert failure.kind == "skipped_palm" and failure.stage == 2 and "palm 2" in failure.detail
    # where it comes down: on palm 3's top at rest (pivot 3 two pitches on), within its box
    pitch_x = L * (math.sin(ALPHA) + math.sin(BETA))
    pitch_y = L * (math.cos(ALPHA) - math.cos(BETA))
    top_x = design.first_pivot_x + 2 * pitch_x - L * math.sin(ALPHA)
    top_y = design.first_pivot_y - 2 * pitch_y + L * math.cos(ALPHA)
    assert failure.before["y"] == pytest.approx(top_y, abs=1e-9)
    assert abs(failure.before["x"] - top_x) < 0.5 * (scene.body.width + scene.palm.width)
    assert not result.outcome.completed and result.outcome.stages_passed == 1
    # allowed, it lands on palm 3, which carries it on to the end of the row (the paper's
    # "stopped moving among manipulators" rests on sizes it does not give:
    # docs/manipulators_model.md)
    result = simulate_manipulators(scene, design, stages=6, offsets=[offset(2, 0.0, -0.4)],
                                   allow_skips=True)
    landing = next(e for e in result.events if e.time > lift.time and e.kind == "landing")
    assert landing.after["palm"] == 3
    assert result.outcome.completed and result.outcome.stages_passed == 6


# ---------------------------------------------------------------- vocabulary, extremes, plots

@pytest.mark.parametrize("changes, offsets", [
    ({}, ()), ({"mu": 0.5}, ()), ({"eps": 0.3}, ()), ({"height": 2.0, "width": 0.2}, ()),
    ({"mu": 0.0}, ()), ({"front_stop": 0.65}, [offset(2, 0.0, -0.4)]),
    ({"mass_ratio": 1e-3}, ()), ({"mass_ratio": 1e3}, ()), ({"alpha": 0.0}, ()),
    ({"alpha": 1.5, "beta": 1.55}, ()), ({"beta": 0.01}, ()),
])
def test_every_run_ends_with_known_events_and_finite_states(changes, offsets):
    scene, design = make(**changes)
    result = simulate_manipulators(scene, design, stages=6, offsets=offsets)
    kinds = set(EVENT_KINDS) | set(FAILURE_KINDS)
    assert all(e.kind in kinds for e in result.events)
    assert all(math.isfinite(v) for e in result.events for v in (*e.before.values(),
                                                                  *e.after.values()))
    assert result.outcome.completed != (result.outcome.failure is not None)
    if result.outcome.failure is not None:
        assert result.outcome.failure.kind in FAILURE_KINDS
        assert result.events[-1] is result.outcome.failure or \
            result.events[-1].time <= result.outcome.failure.time
    times = [e.time for e in result.events]
    assert times == sorted(times)


def test_frictionless_landing_slides_off_the_held_palm():
    # mu = 0: the impulse is vertical, drives the palm into its back stop; the object keeps vx
    scene, design = make(mu=0.0)
    result = simulate_manipulators(scene, design, stages=2)
    t, x, vx, _ = first_landing()
    s0 = x + L * math.sin(ALPHA)
    failure = result.outcome.failure
    assert failure.kind == "slid_off"
    assert failure.time == pytest.approx(t + (0.8 - s0) / vx, abs=1e-12)


def test_offsets_outside_the_row_are_refused():
    scene, design = make()
    with pytest.raises(ValueError, match="manipulator 7"):
        simulate_manipulators(scene, design, stages=6, offsets=[offset(7, 0.1)])


def test_plot_writes_a_png(tmp_path):
    scene, design = paper()
    offs = [offset(2, 0.1, -0.2)]
    result = simulate_manipulators(scene, design, stages=4, offsets=offs, record_trajectory=True)
    assert len(result.trajectory["time"]) == len(result.trajectory["x"]) > 100
    from pdm_design.scenes.manipulators.sim.plot import plot_manipulators

    out = plot_manipulators(result, scene, design, tmp_path / "run.png", offsets=offs)
    assert Path(out).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bare = simulate_manipulators(scene, design, stages=2)
    with pytest.raises(ValueError, match="record_trajectory"):
        plot_manipulators(bare, scene, design, tmp_path / "bare.png")


@pytest.mark.parametrize("eps", [0.5, 0.99])
def test_vertical_drop_bounces_geometrically_on_the_held_palm(eps):
    """Dropped straight down, the object pushes palm 1 into its back stop (V.t(-alpha) < 0), so
    the stop holds the palm: each bounce leaves at eps^k v0, until a bounce slower than the
    Zeno threshold 1e-4 sqrt(g l) ends in contact and the object rests on the held palm."""
    y0 = 2.5
    scene, design = make(eps=eps, position=(-0.4, y0), velocity=(0.0, 0.0))
    result = simulate_manipulators(scene, design, stages=1)
    drop = y0 - L * math.cos(ALPHA)
    v0 = math.sqrt(2 * G * drop)
    bounces = events(result, "bounce")
    n = math.ceil(math.log(1e-4 * math.sqrt(G * L) / v0) / math.log(eps)) - 1
    assert len(bounces) == n
    for k, e in enumerate(bounces):
        assert e.after["vy"] == pytest.approx(v0 * eps ** (k + 1), rel=1e-8)
    failure = result.outcome.failure
    assert failure.kind == "stall"
    airborne = 2 * v0 * eps * (1 - eps ** n) / (G * (1 - eps))
    assert failure.time == pytest.approx(math.sqrt(2 * drop / G) + airborne, rel=1e-9)


@pytest.mark.parametrize("scale", [1e-3, 1e3])
def test_runs_scale_with_length(scale):
    """Lengths x k, times and speeds x sqrt(k): the same run, speeds scaled (g fixed)."""
    k = scale
    scene = ManipulatorsScene(
        body=Body(mass=1.0, width=0.4 * k, height=0.2 * k),
        palm=Palm(width=1.6 * k, thickness=0.05 * k, friction=MU),
        initial=ManipulatorsInitial(position=(X0 * k, Y0 * k),
                                    velocity=(VX0 * math.sqrt(k), VY0 * math.sqrt(k))),
        gravity=G)
    design = ManipulatorsDesign(alpha=ALPHA, beta=BETA, link_length=L * k, mass_ratio=Q)
    result = simulate_manipulators(scene, design, stages=5)
    assert result.outcome.completed
    _, _, vx, vy = first_landing()
    s2 = momentum_speed(vx, vy) ** 2 + 2 * G * L * (math.cos(ALPHA) - math.cos(BETA))
    _, c = fixed_point_speed()
    for st in result.stages[:-1]:
        assert st["handover_speed"] / math.sqrt(k) == pytest.approx(math.sqrt(s2), rel=1e-9)
        s2 = c * s2 + 2 * G * L * (math.cos(ALPHA) - math.cos(BETA))
