"""The device as built: link mass and inertia, pivot friction (docs/physics.md, section 2.1).

Independent derivations: a sympy Lagrangian of palm + links (rods integrated over their length)
+ stuck object gives the carry's equation, the landing's generalized momentum and the energy
balance with the Coulomb pivot torque; its periodic handover speed is compared with the closed
form, and the closed forms with the event simulator."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from pdm_design.accuracy import accuracy
from pdm_design.scenes.manipulators import physics as phys
from pdm_design.scenes.manipulators.analysis import analyse_manipulators
from pdm_design.scenes.manipulators.model import Links, Pivots
from pdm_design.scenes.manipulators.sim import phases as ph
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.scenes.manipulators.sim.run import Run
from pdm_design.spec.loader import load_spec

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "problems" / "paper_manipulators.toml"
REAL = ROOT / "problems" / "manipulators_real_links.toml"


def scene_with(spec, *, link_mass=0.0, inertia=None, count=2, torque=0.0, damping=0.0, mu=None):
    scene = dataclasses.replace(spec.scene, links=Links(mass=link_mass, inertia=inertia,
                                                        count=count),
                                pivots=Pivots(friction_torque=torque, damping=damping))
    if mu is not None:
        scene = dataclasses.replace(scene, palm=dataclasses.replace(scene.palm, friction=mu))
    return scene


# ---------------------------------------------------------------- the sympy Lagrangian
th, w, r = sp.symbols("theta omega r", real=True)
m, M, ml, l, g, tau, c = sp.symbols("m M m_l l g tau c", positive=True)
N_LINKS = 2
# palm and object translate on the circle (every point at speed l w); each link is a rod of
# mass m_l over [0, l] turning about its pivot: a point at r moves at r w, r cos(th) high
T = (sp.Rational(1, 2) * (m + M) * l**2 * w**2
     + N_LINKS * sp.integrate(sp.Rational(1, 2) * (ml / l) * r**2 * w**2, (r, 0, l)))
V = (m + M) * g * l * sp.cos(th) + N_LINKS * sp.integrate((ml / l) * g * r * sp.cos(th),
                                                          (r, 0, l))
# Lagrange: d/dt dT/dw - dL/dth = Q, Q = -tau sgn(w) - c w (a forward swing: sgn = 1); T
# depends on w only (the palm translates), so d/dt dT/dw = d2T/dw2 th'' (th'' = a below)
THDD = sp.solve(sp.Eq(sp.diff(T, w, 2) * sp.Symbol("a")
                      + sp.diff(V, th), -tau - c * w), sp.Symbol("a"))[0]
THDD_F = sp.lambdify((th, w, m, M, ml, l, g, tau, c), THDD)
P_W = sp.lambdify((m, M, ml, l), sp.diff(T, w) / w)  # generalized momentum per unit w
E_F = sp.lambdify((th, w, m, M, ml, l, g), T + V)


def sympy_handover_speed(a, b, mo, Mp, mlink, L, G, torque):
    """Fixed point of the stage map from the Lagrangian: the landing keeps the generalized
    momentum m l V . t(-a) (the links take the rest), the carry loses tau (a + b) of energy."""
    s = 3.0
    for _ in range(400):
        vx, vy = s * math.cos(b), -s * math.sin(b)
        p = mo * L * (vx * math.cos(a) + vy * math.sin(a))
        w0 = p / P_W(mo, Mp, mlink, L)
        e_b = E_F(-a, w0, mo, Mp, mlink, L, G) - torque * (a + b)
        # solve E(b, w) = e_b for w > 0: T is quadratic in w
        w_b = math.sqrt((e_b - E_F(b, 0.0, mo, Mp, mlink, L, G)) * 2.0 / P_W(mo, Mp, mlink, L))
        s = L * w_b
    return s


@pytest.mark.parametrize("mlink,torque,damping", [(0.5, 0.0, 0.0), (0.5, 0.3, 0.0),
                                                   (3.0, 1.0, 0.2), (1e-3, 0.0, 0.05)])
def test_carry_equation_is_the_lagrangian_of_palm_links_and_object(mlink, torque, damping):
    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=mlink, torque=torque, damping=damping)
    design = spec.design_at()
    run = Run(scene, design, 3, (), accuracy("default"), False)
    mo, L, G = scene.body.mass, design.link_length, scene.gravity
    Mp = mo / design.mass_ratio
    q_e, g_e, f = phys.carry_terms(design.mass_ratio, object_mass=mo, gravity=G, link_length=L,
                                   **scene.mechanism())
    for theta, omega in [(-0.3, 0.4), (0.1, 1.3), (0.7, 2.0)]:
        expected = THDD_F(theta, omega, mo, Mp, mlink, L, G, torque, damping)
        sim = ph.swing_acceleration(theta, omega, run.swings_loaded[0])
        assert sim == pytest.approx(expected, rel=1e-13)
        if damping == 0.0:  # the closed form's: l^2 th'' = g_e l sin th - f
            assert (g_e * L * math.sin(theta) - f) / L**2 == pytest.approx(expected, rel=1e-13)
    # the landing's momentum fraction is m / (m + M + J): m l^2 over the generalized mass
    assert phys.momentum_fraction(q_e) == pytest.approx(mo * L**2 / P_W(mo, Mp, mlink, L),
                                                        rel=1e-14)


@pytest.mark.parametrize("mlink,torque", [(0.5, 0.0), (0.5, 0.3), (2.0, 1.5), (0.05, 0.0)])
def test_periodic_handover_speed_is_the_lagrangian_fixed_point(mlink, torque):
    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=mlink, torque=torque)
    design = spec.design_at()
    got = analyse_manipulators(scene, design).periodic["handover_speed"]
    want = sympy_handover_speed(design.alpha, design.beta, scene.body.mass,
                                scene.body.mass / design.mass_ratio, mlink,
                                design.link_length, scene.gravity, torque)
    assert got == pytest.approx(want, rel=1e-12)


def test_one_kilogram_of_links_matches_the_rigid_body_engine_on_the_robust_design():
    """Measured with an independent 2-D rigid-body engine on the optimised manipulators_robust
    design (alpha 0.0613, beta 0.4928): 3.37 m/s with massless links, 2.81 m/s with 1 kg of
    links in all (two uniform 0.5 kg rods of 2 m), both to the engine's two decimals."""
    spec = load_spec(ROOT / "problems" / "manipulators_robust.toml")
    design = spec.design_at({"alpha": 0.061301573899771804, "beta": 0.49275976036525393})
    plain = analyse_manipulators(spec.scene, design).periodic["handover_speed"]
    heavy = analyse_manipulators(scene_with(spec, link_mass=0.5), design)
    assert round(plain, 2) == 3.38 and abs(plain - 3.37) < 0.01
    assert abs(heavy.periodic["handover_speed"] - 2.81) < 0.005
    assert heavy.periodic["effective_mass"] == pytest.approx(0.1 + 1.0 / 3.0, rel=1e-15)


def test_energy_balance_with_the_coulomb_torque_is_the_integrated_swing():
    """v(th)^2 of the carry with pivot friction against an ODE of the sympy equation."""
    from scipy.integrate import solve_ivp

    mo, Mp, mlink, L, G, torque = 1.0, 0.1, 0.7, 1.5, 9.81, 0.4
    a, u = 0.3, 2.5
    q_e, g_e, f = phys.carry_terms(mo / Mp, object_mass=mo, gravity=G, link_length=L,
                                   link_mass=2 * mlink, friction_torque=torque)
    sol = solve_ivp(lambda t, y: [y[1], THDD_F(y[0], y[1], mo, Mp, 2 * mlink / N_LINKS * 1.0,
                                                L, G, torque, 0.0)],
                    (0, 3), [-a, u / L], rtol=1e-12, atol=1e-14, dense_output=True,
                    events=lambda t, y: y[0] - 0.8)
    t_end = sol.t_events[0][0]
    v_end = sol.sol(t_end)[1] * L
    closed = phys.carry_speed_squared(u, a, 0.8, gravity=g_e, link_length=L, friction=f)
    assert v_end**2 == pytest.approx(closed, rel=1e-10)


# ---------------------------------------------------------------- closed forms vs simulator

@pytest.mark.parametrize("mlink,torque,inertia", [(0.5, 0.2, None), (0.5, 0.0, None),
                                                   (0.0, 0.4, None), (1.0, 0.1, 1.6)])
def test_closed_form_handover_speeds_agree_with_the_simulator(mlink, torque, inertia):
    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=mlink, torque=torque, inertia=inertia, mu=1.5)
    design = spec.design_at()
    predicted = analyse_manipulators(scene, design).approach["handover_speeds"]
    result = simulate_manipulators(scene, design, stages=7, accuracy="precise")
    assert result.outcome.completed and not any(st["slipped"] for st in result.stages)
    simulated = [st["handover_speed"] for st in result.stages[:6]]
    assert np.allclose(simulated, predicted, rtol=1e-9, atol=0.0)


def test_the_shipped_real_links_design_is_confirmed_by_the_simulator():
    spec = load_spec(REAL)
    done = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(REAL),
                           "--format", "json"], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["verification"]["passed"] and doc["tolerance"]
    design = spec.design_at({k: doc["design"][k] for k in spec.free_variables})
    predicted = analyse_manipulators(spec.scene, design).approach["handover_speeds"]
    result = simulate_manipulators(spec.scene, design, stages=7, accuracy="precise")
    assert result.outcome.completed
    assert np.allclose([st["handover_speed"] for st in result.stages[:6]], predicted,
                       rtol=1e-9, atol=0.0)
    # the JSON reports the device as built
    assert doc["geometry"]["link_mass"] == 0.5 and doc["geometry"]["link_count"] == 2
    assert doc["geometry"]["link_inertia"] == pytest.approx(0.5 * 4.0 / 3.0, rel=1e-15)
    assert doc["geometry"]["pivot_friction_torque"] == 0.2
    assert doc["periodic"]["effective_mass"] == pytest.approx(0.1 + 1.0 / 3.0, rel=1e-15)


def test_zero_links_and_pivots_written_out_give_the_same_numbers():
    """A spec with [scene.links] mass = 0 and [scene.pivots] zeros is the spec without them."""
    spec = load_spec(PAPER)
    design = spec.design_at()
    plain = analyse_manipulators(spec.scene, design)
    zero = analyse_manipulators(scene_with(spec, count=3), design)
    assert zero.periodic == plain.periodic and zero.margins == plain.margins
    assert zero.approach == plain.approach
    assert zero.geometry == dict(plain.geometry, link_count=3)
    a = simulate_manipulators(spec.scene, design, stages=6)
    b = simulate_manipulators(scene_with(spec, count=3), design, stages=6)
    assert a.stages == b.stages


@pytest.mark.parametrize("what", ["link_mass", "torque"])
def test_the_effect_vanishes_continuously(what):
    spec = load_spec(PAPER)
    design = spec.design_at()
    plain = analyse_manipulators(spec.scene, design)
    for tiny in (1e-4, 1e-7, 1e-10):
        kw = {"link_mass": tiny} if what == "link_mass" else {"torque": tiny}
        got = analyse_manipulators(scene_with(spec, **kw), design)
        s0, s1 = plain.periodic["handover_speed"], got.periodic["handover_speed"]
        assert 0.0 < abs(s1 - s0) / s0 < 10 * tiny
        for key, value in plain.margins.items():
            assert got.margins[key] == pytest.approx(value, abs=10 * tiny)


@pytest.mark.parametrize("factor", [1e-6, 1e-3, 1.0, 10.0, 1e3])
def test_link_mass_extremes_agree_with_the_simulator_or_fail_in_words(factor):
    spec = load_spec(PAPER)
    design = spec.design_at()
    palm = spec.scene.body.mass / design.mass_ratio
    scene = scene_with(spec, link_mass=factor * palm / 2, mu=1.5)
    an = analyse_manipulators(scene, design)
    result = simulate_manipulators(scene, design, stages=4, accuracy="precise")
    speeds = an.approach["handover_speeds"]
    if an.margins["first_over_the_top"] >= 0.0 and len(speeds) >= 3:
        assert result.outcome.completed
        assert np.allclose([st["handover_speed"] for st in result.stages[:3]], speeds[:3],
                           rtol=1e-9, atol=0.0)
    else:  # a heavy mechanism that the first landing cannot carry over the top
        assert not result.outcome.completed
        assert result.outcome.failure.kind == "stall" and "stops" in result.outcome.failure.detail


def test_friction_that_stops_the_palm_is_a_stall_where_the_closed_form_says():
    """The over-the-top margin with friction changes sign at the torque where the simulated
    palm first fails to carry the object past the balance angle."""
    spec = load_spec(PAPER)
    design = spec.design_at()

    def margin(torque):
        an = analyse_manipulators(scene_with(spec, torque=torque, mu=1.5), design)
        return an.margins["first_over_the_top"]

    lo, hi = 0.0, 50.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if margin(mid) > 0.0 else (lo, mid)
    for torque, works in ((lo * (1 - 1e-6), True), (hi * (1 + 1e-6), False)):
        result = simulate_manipulators(scene_with(spec, torque=torque, mu=1.5), design,
                                       stages=2, accuracy="precise")
        if works:
            assert result.stages[0]["handover_speed"] is not None
        else:
            failure = result.outcome.failure
            assert failure.kind == "stall" and failure.stage == 1
            # it stops just short of the balance angle past the top, where friction holds it
            assert "pivot friction holds it there" in failure.detail
            _, g_e, f = phys.carry_terms(design.mass_ratio, object_mass=spec.scene.body.mass,
                                         gravity=spec.scene.gravity,
                                         link_length=design.link_length, friction_torque=torque)
            star = phys.friction_balance_angle(f, gravity=g_e, link_length=design.link_length)
            assert 0.0 < star - failure.before["theta"] < 2e-3


def test_bad_links_and_pivots_keys_are_refused_in_words(tmp_path):
    text = PAPER.read_text() + "\n[scene.pivots]\nfriction_torque = -0.1\n"
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    done = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(bad)],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 2
    assert "scene.pivots.friction_torque" in done.stderr and "Traceback" not in done.stderr


def test_damped_carry_in_the_simulator_is_the_integrated_lagrangian():
    """With pivot damping (no closed form) the simulator's first handover speed equals an ODE of
    the sympy equation from the closed-form first landing to beta."""
    from scipy.integrate import solve_ivp

    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=0.3, torque=0.1, damping=0.4, mu=1.5)
    design = spec.design_at()
    an = analyse_manipulators(scene, design)
    mo, L, G = scene.body.mass, design.link_length, scene.gravity
    Mp, a, b = mo / design.mass_ratio, design.alpha, design.beta
    q_e = phys.carry_terms(design.mass_ratio, object_mass=mo, gravity=G, link_length=L,
                           **scene.mechanism())[0]
    u = phys.landing_speed(*an.approach["landing_velocity"], a, q_e)
    event = lambda t, y: y[0] - b  # noqa: E731
    event.terminal = True
    sol = solve_ivp(lambda t, y: [y[1], THDD_F(y[0], y[1], mo, Mp, 0.3, L, G, 0.1, 0.4)],
                    (0, 10), [-a, u / L], rtol=1e-12, atol=1e-14, events=event)
    expected = sol.y_events[0][0][1] * L
    result = simulate_manipulators(scene, design, stages=3, accuracy="precise")
    assert result.stages[0]["handover_speed"] == pytest.approx(expected, rel=1e-9)
    # the analysis integrates the same carry (physics.integrated_carry_speed_squared)
    assert an.approach["handover_speeds"][0] == pytest.approx(expected, rel=1e-11)
    plain = analyse_manipulators(scene_with(spec, link_mass=0.3, torque=0.1, mu=1.5), design)
    assert result.stages[0]["handover_speed"] < plain.approach["handover_speeds"][0]


@pytest.mark.parametrize("preset", ["fast", "default", "precise"])
def test_the_nlp_integrated_rows_agree_with_the_simulator_to_the_preset(preset):
    """With damping the NLP integrates the carry with as many steps as the accuracy asks: its
    stage map (first landing to the first handover, and the periodic fixed point) agrees with
    the simulator to the preset's agreement tolerance."""
    from pdm_design.scenes.manipulators import formulation as form

    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=0.3, torque=0.1, damping=0.4, mu=1.5)
    spec = dataclasses.replace(spec, scene=scene, verification=dataclasses.replace(
        spec.verification, accuracy=accuracy(preset)))
    _, _, m = form.build(spec)
    assert m.steps == phys.carry_steps(accuracy(preset).agreement / 10, spec.design_at().alpha
                                       + spec.design_at().beta)
    u1 = m.first_speed(m.fall_speed(0.0))
    v1 = math.sqrt(float(m.carry_v2(u1, m.b)))
    result = simulate_manipulators(scene, spec.design_at(), stages=30, accuracy="precise")
    tol = accuracy(preset).agreement
    assert v1 == pytest.approx(result.stages[0]["handover_speed"], rel=tol)
    s2 = v1 * v1
    for _ in range(200):  # the NLP's periodic row: S = v(beta)^2 after landing at k sqrt(S)
        s2 = float(m.carry_v2(m.k * math.sqrt(s2) * math.cos(m.a + m.b), m.b))
    assert math.sqrt(s2) == pytest.approx(result.stages[-2]["handover_speed"], rel=tol)


def test_damped_fixed_point_and_contraction_are_the_simulated_ones():
    """With damping the analysis's fixed point and slope of the integrated stage map are those
    the simulated handover speeds converge to, and by which their errors shrink."""
    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=0.5, torque=0.3, damping=0.4, mu=1.5)
    design = spec.design_at()
    periodic = analyse_manipulators(scene, design).periodic
    run = simulate_manipulators(scene, design, stages=30, accuracy="precise")
    speeds = [st["handover_speed"] for st in run.stages[:-1]]
    star2 = periodic["handover_speed"] ** 2
    assert speeds[-1] == pytest.approx(periodic["handover_speed"], rel=1e-11)
    ratio = (speeds[5] ** 2 - star2) / (speeds[4] ** 2 - star2)
    assert ratio == pytest.approx(periodic["contraction"], rel=1e-4)
    undamped = analyse_manipulators(scene_with(spec, link_mass=0.5, torque=0.3, mu=1.5), design)
    assert periodic["handover_speed"] < undamped.periodic["handover_speed"]


def test_vectorised_handover_map_with_carry_terms_is_the_simulated_map():
    from pdm_design.scenes.manipulators.sim import handover_map

    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=0.5, torque=0.2, mu=1.5)
    design = spec.design_at()
    q_e, g_e, f = phys.carry_terms(design.mass_ratio, object_mass=scene.body.mass,
                                   gravity=scene.gravity, link_length=design.link_length,
                                   **scene.mechanism())
    run = simulate_manipulators(scene, design, stages=5, accuracy="precise")
    speeds = np.array([st["handover_speed"] for st in run.stages[:4]])
    mapped = handover_map(speeds[:-1], design.alpha, design.beta, q_e, g_e,
                          design.link_length, friction=f)
    assert np.allclose(mapped, speeds[1:], rtol=1e-9, atol=0.0)


def test_an_empty_palm_that_friction_stops_mid_swing_rests_where_the_energy_runs_out():
    """An empty palm swinging back with pivot friction stops where v^2 = w0^2 + 2 g_p l
    (cos th0 - cos th) - 2 f_p (th0 - th) = 0 (the palm-alone terms, physics.palm_terms), and
    stays there when its weight's torque is within the friction (pivot_friction_stop)."""
    from scipy.optimize import brentq

    spec = load_spec(PAPER)
    scene = scene_with(spec, link_mass=0.5, torque=2.0)
    design = spec.design_at()
    run = Run(scene, design, 3, (), accuracy("precise"), False)
    L = design.link_length
    felt, g_p, _ = phys.palm_terms(design.mass_ratio, object_mass=scene.body.mass,
                                   gravity=scene.gravity, link_length=L, **scene.mechanism())
    f_p = 2.0 / felt
    th0, w0 = -0.05, -0.3
    dt, stop, speed = run._free_swing_arrival(0, th0, w0)

    def v2(th):
        return w0**2 + 2 * g_p * L * (math.cos(th0) - math.cos(th)) - 2 * f_p * (th0 - th)

    expected = brentq(v2, th0 - 0.2, th0 - 1e-9, xtol=1e-15)
    assert stop == pytest.approx(expected, abs=1e-9) and speed == 0.0 and 0.0 < dt < 1.0
    assert (0.1 + 0.5) * scene.gravity * L * abs(math.sin(stop)) <= 2.0  # friction holds it
