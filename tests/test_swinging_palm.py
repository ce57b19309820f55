"""The object meeting a palm that still swings (a back stop past the vertical releases it as the
row is built): the impact with the moving palm against a hand-derived impulse solve (the
swing's generalised momentum conserved, no energy created), the carry after it against scipy's
integration of the pendulum started at the post-impact state, and a row whose palm is met
swinging that now completes."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pdm_design.scenes.manipulators.sim import phases as ph
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.scenes.manipulators.sim.geometry import Parts
from pdm_design.spec.loader import load_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def _energy(m, M, vx, vy, w):
    return 0.5 * m * (vx * vx + vy * vy) + 0.5 * M * w * w


def _stick_by_hand(m, M, vx, vy, w, theta):
    """Plastic sticking impact on a palm moving at w along t = (cos th, -sin th): the object
    leaves with the palm, v' = w' t; the link's impulse is radial, so m v.t + M w (the swing's
    generalised momentum over l) is conserved: w' = (m v.t + M w) / (m + M)."""
    c, s = math.cos(theta), math.sin(theta)
    w1 = (m * (vx * c - vy * s) + M * w) / (m + M)
    return w1 * c, -w1 * s, w1


def _slide_by_hand(m, M, vx, vy, w, theta, mu):
    """Plastic impact sliding throughout: impulse (px, py) on the object with px = -sig mu py,
    the palm's M dw = -(px c - py s), and no normal approach after: vy' + w' s = 0. Solved as
    a 3 x 3 linear system (unknowns py, vy', w')."""
    c, s = math.cos(theta), math.sin(theta)
    sig = math.copysign(1.0, vx - w * c)
    a = np.array([[1.0, -m, 0.0],                    # py = m (vy' - vy)
                  [sig * mu * c + s, 0.0, -M],       # M (w' - w) = sig mu py c + py s
                  [0.0, 1.0, s]])                    # vy' + w' s = 0
    b = np.array([-m * vy, -M * w, 0.0])
    py, vy1, w1 = np.linalg.solve(a, b)
    return vx - sig * mu * py / m, vy1, w1, py


@pytest.mark.parametrize("theta, w, vx, vy", [(0.3, 0.8, 2.0, -1.5), (0.08, 0.3, 1.9, -1.0),
                                              (0.6, 2.0, 2.6, -2.2)])
def test_a_sticking_impact_on_a_moving_palm_is_the_hand_solve(theta, w, vx, vy):
    m, M, mu = 1.0, 0.25, 0.8
    imp = ph.impact(vx, vy, w, theta, m=m, mass_ratio=m / M, mu=mu, eps=0.0)
    hx, hy, hw = _stick_by_hand(m, M, vx, vy, w, theta)
    px, py = m * (hx - vx), m * (hy - vy)
    assert py > 0.0 and abs(px) <= mu * py  # the sticking impulse is in the cone
    assert imp.stick
    assert imp.vx == pytest.approx(hx, abs=1e-12) and imp.vy == pytest.approx(hy, abs=1e-12)
    assert imp.w == pytest.approx(hw, abs=1e-12)
    c, s = math.cos(theta), math.sin(theta)
    assert m * (imp.vx * c - imp.vy * s) + M * imp.w == pytest.approx(
        m * (vx * c - vy * s) + M * w, abs=1e-12)
    assert _energy(m, M, vx, vy, w) - _energy(m, M, imp.vx, imp.vy, imp.w) >= 0.0


def test_a_sliding_impact_on_a_moving_palm_is_the_hand_solve():
    m, M, mu, theta, w, vx, vy = 1.0, 0.25, 0.1, 0.3, 0.8, 2.5, -1.5
    imp = ph.impact(vx, vy, w, theta, m=m, mass_ratio=m / M, mu=mu, eps=0.0)
    hx, hy, hw, py = _slide_by_hand(m, M, vx, vy, w, theta, mu)
    assert py > 0.0 and not imp.stick
    assert (hx - hw * math.cos(theta)) * (vx - w * math.cos(theta)) > 0.0  # still slipping
    assert (imp.vx, imp.vy, imp.w) == pytest.approx((hx, hy, hw), abs=1e-12)
    assert _energy(m, M, vx, vy, w) - _energy(m, M, imp.vx, imp.vy, imp.w) > 0.0


def _paper():
    spec = load_spec(PROBLEMS / "paper_manipulators.toml")
    return spec.scene, spec.design_at()


def _pendulum(theta0, omega0, t0, t1, g, l):
    """(th, th') at t1 of l th'' = g sin th from (theta0, omega0) at t0, scipy on its own."""
    sol = solve_ivp(lambda t, y: [y[1], g * math.sin(y[0]) / l], (t0, t1), [theta0, omega0],
                    method="DOP853", rtol=1e-12, atol=1e-14)
    return float(sol.y[0][-1]), float(sol.y[1][-1])


def test_a_palm_met_swinging_takes_the_object_and_the_row_completes():
    scene, design = _paper()
    g, l, m = scene.gravity, design.link_length, scene.body.mass
    M = m / design.mass_ratio
    past = 0.01  # palm 2's back stop past the vertical: it swings from rest at t = 0
    result = simulate_manipulators(scene, design, stages=4, accuracy="precise",
                                   parts=Parts(back_stop=(design.alpha, -past, design.alpha,
                                                          design.alpha)))
    assert result.outcome.completed and result.outcome.failure is None
    onto = next(e for e in result.events if e.kind == "handover" and e.stage == 1)
    # palm 2 is met while it swings: its angle and rate then, as its own pendulum gives them
    theta, omega = _pendulum(past, 0.0, 0.0, onto.time, g, l)
    assert omega > 0.15 and theta > 4.0 * past
    assert onto.after["theta"] == pytest.approx(theta, abs=1e-7)
    # the impact: the object (its velocity on palm 1) sticks on the moving palm
    _, _, w1 = _stick_by_hand(m, M, onto.before["vx"], onto.before["vy"], l * omega, theta)
    assert onto.after["omega"] * l == pytest.approx(w1, rel=1e-7)
    assert w1 > l * omega  # the object pushes the palm on
    # the carry from the post-impact state to the next handover: scipy's pendulum
    off = next(e for e in result.events if e.kind == "handover" and e.stage == 2)
    assert not [e for e in result.events if onto.time < e.time < off.time and e.stage == 2
                and e.kind in ("slip", "lift_off")]
    th2, om2 = _pendulum(onto.after["theta"], onto.after["omega"], onto.time, off.time, g, l)
    assert off.before["theta"] == pytest.approx(th2, abs=1e-7)
    assert off.before["omega"] == pytest.approx(om2, rel=1e-6)
    # its planned stop from rest is gone: palm 2 stops once, after it has handed the object on
    stops = [e for e in result.events if e.kind == "front_stop" and e.stage == 2]
    assert len(stops) == 1 and stops[0].time > off.time


def test_a_landing_on_a_palm_swinging_after_a_lift_off_is_followed():
    scene, design = _paper()
    g, l = scene.gravity, design.link_length
    past = 0.05
    result = simulate_manipulators(scene, design, stages=4, accuracy="precise",
                                   parts=Parts(back_stop=(design.alpha, -past, design.alpha,
                                                          design.alpha)))
    kinds = [e.kind for e in result.events]
    assert "lift_off" in kinds and result.outcome.completed
    landing = next(e for e in result.events if e.kind == "landing" and e.stage == 2)
    theta, omega = _pendulum(past, 0.0, 0.0, landing.time, g, l)
    assert landing.before["palm_theta"] == pytest.approx(theta, abs=1e-7)
    assert landing.before["palm_omega"] == pytest.approx(omega, rel=1e-6)


def test_on_real_links_the_palm_met_swinging_and_the_carry_after_are_their_pendulums():
    """Links of mass m_l (two uniform rods: J = 2 m_l / 3 along the swing, W = m_l of weight)
    and a Coulomb torque tau at the pivots (docs/physics.md, section 2.1): the empty palm
    (M + J) l^2 th'' = (M + W) g l sin th - tau, the impact kept (M + J) w + m v.t, the carry
    (m + M + J) l^2 th'' = (m + M + W) g l sin th - tau, each integrated by scipy here."""
    spec = load_spec(PROBLEMS / "manipulators_all_toleranced.toml")
    scene, design = spec.scene, spec.design_at()
    g, l, m = scene.gravity, design.link_length, scene.body.mass
    M, tau = m / design.mass_ratio, scene.pivots.friction_torque
    J, W = scene.links.count * scene.links.mass / 3.0, scene.links.count * scene.links.mass / 2.0
    past = 0.04
    result = simulate_manipulators(scene, design, stages=4, accuracy="precise",
                                   parts=Parts(back_stop=(design.alpha, -past, design.alpha,
                                                          design.alpha)))
    assert result.outcome.completed

    def swing(inertia, weight, theta0, omega0, t0, t1):
        sol = solve_ivp(lambda t, y: [y[1], (weight * g * l * math.sin(y[0]) - tau)
                                      / (inertia * l * l)],
                        (t0, t1), [theta0, omega0], method="DOP853", rtol=1e-12, atol=1e-14)
        return float(sol.y[0][-1]), float(sol.y[1][-1])

    onto = next(e for e in result.events if e.kind == "handover" and e.stage == 1)
    theta, omega = swing(M + J, M + W, past, 0.0, 0.0, onto.time)
    assert omega > 0.3 and onto.after["theta"] == pytest.approx(theta, abs=1e-7)
    _, _, w1 = _stick_by_hand(m, M + J, onto.before["vx"], onto.before["vy"], l * omega, theta)
    assert onto.after["omega"] * l == pytest.approx(w1, rel=1e-6)
    off = next(e for e in result.events if e.kind == "handover" and e.stage == 2)
    assert not [e for e in result.events if onto.time < e.time < off.time and e.stage == 2
                and e.kind in ("slip", "lift_off")]
    th2, om2 = swing(m + M + J, m + M + W, onto.after["theta"], onto.after["omega"], onto.time,
                     off.time)
    assert off.before["theta"] == pytest.approx(th2, abs=1e-7)
    assert off.before["omega"] == pytest.approx(om2, rel=1e-6)


def test_the_fed_object_lands_on_a_first_palm_still_swinging_where_the_two_paths_meet():
    """Palm 1 swings from rest as the object is fed: the landing is where the object's fall
    meets the palm's top on its own pendulum (found here by Brent's method on scipy's dense
    solution), the impact sticks as the hand solve says, and the row completes."""
    from scipy.optimize import brentq

    scene, design = _paper()
    g, l, m = scene.gravity, design.link_length, scene.body.mass
    M = m / design.mass_ratio
    past = 0.03
    result = simulate_manipulators(scene, design, stages=4, accuracy="precise",
                                   parts=Parts(back_stop=(-past, design.alpha, design.alpha,
                                                          design.alpha)))
    assert result.outcome.completed
    pend = solve_ivp(lambda t, y: [y[1], g * math.sin(y[0]) / l], (0.0, 2.0), [past, 0.0],
                     method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
    (x0, y0), (vx, vy) = scene.initial.position, scene.initial.velocity
    py = design.first_pivot_y

    def gap(t):
        return y0 + vy * t - 0.5 * g * t * t - (py + l * math.cos(pend.sol(t)[0]))

    t_land = brentq(gap, 0.0, 1.0, xtol=1e-14)
    landing = next(e for e in result.events if e.kind == "landing" and e.stage == 1)
    assert landing.time == pytest.approx(t_land, abs=1e-8)
    theta, omega = pend.sol(t_land)
    reach = 0.5 * (scene.palm.width + scene.body.width)  # on the palm's top, not past its end
    assert abs(x0 + vx * t_land - (design.first_pivot_x + l * math.sin(theta))) < reach
    assert landing.before["palm_theta"] == pytest.approx(theta, abs=1e-8)
    _, _, w1 = _stick_by_hand(m, M, vx, vy - g * t_land, l * omega, theta)
    assert landing.after["omega"] * l == pytest.approx(w1, rel=1e-6)
