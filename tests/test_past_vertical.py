"""Palms whose back stop is past the vertical (alpha_k < 0) swing forward from rest as soon as
the row is built: their motion against an independent integration of their own pendulum, the
unstable rest of a stop exactly vertical, pivot friction that holds such a palm, the object
that reaches a palm still swinging (handed onto it), and the vectorised map that hands such
builds over."""

import dataclasses
import math
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from pdm_design.accuracy import accuracy
from pdm_design.scenes.manipulators.model import Links, Pivots
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.scenes.manipulators.sim.geometry import Parts
from pdm_design.scenes.manipulators.sim.run import Run
from pdm_design.scenes.manipulators.tolerances import run_builds
from pdm_design.spec.loader import load_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
STAGES = 4


def _paper():
    spec = load_spec(PROBLEMS / "paper_manipulators.toml")
    return spec.scene, spec.design_at()


def _run(scene, design, back_stops):
    parts = Parts(back_stop=tuple(back_stops))
    return Run(scene, design, STAGES, (), accuracy("precise"), False, parts)


def _pendulum_arrival(theta0, inertia, weight, torque, g, l, front_stop):
    """Time and speed (m/s) at which a palm released at rest at theta0 > 0 reaches its front
    stop: (I) l^2 th'' = (Wt) g l sin th - tau, integrated by scipy on its own."""
    def rhs(t, y):
        return [y[1], (weight * g * l * math.sin(y[0]) - torque) / (inertia * l * l)]

    def stop(t, y):
        return y[0] - front_stop

    stop.terminal = True
    sol = solve_ivp(rhs, (0.0, 60.0), [theta0, 0.0], events=stop, method="DOP853",
                    rtol=1e-12, atol=1e-14)
    return float(sol.t_events[0][0]), float(sol.y_events[0][0][1]) * l


def test_a_palm_past_the_vertical_swings_to_its_front_stop_as_its_pendulum():
    scene, design = _paper()
    theta0 = 0.05  # palm 3 rests 0.05 rad past the vertical
    run = _run(scene, design, [design.alpha, design.alpha, -theta0, design.alpha])
    t_ref, v_ref = _pendulum_arrival(theta0, 1.0, 1.0, 0.0, scene.gravity,
                                     design.link_length, scene.palm.front_stop)
    assert run.from_rest == (2,)
    assert run.rest_angle[2] == scene.palm.front_stop
    assert math.isclose(run.rest_since[2], t_ref, rel_tol=1e-9)
    arrival = [e for e in run.palm_events if e.stage == 3]
    assert arrival[0].kind == "front_stop"
    assert math.isclose(arrival[0].before["omega"] * design.link_length, v_ref, rel_tol=1e-9)
    # the palms resting behind the vertical stay where they are
    assert run.rest_since[:2] == [-math.inf, -math.inf] and run.rest_since[3] == -math.inf


def test_on_real_links_the_swing_counts_the_links_and_pivot_friction_may_hold_it():
    scene, design = _paper()
    m_link, n, tau = 0.5, 2, 0.2
    scene = dataclasses.replace(scene, links=Links(mass=m_link, count=n),
                                pivots=Pivots(friction_torque=tau))
    M, l, g = scene.body.mass / design.mass_ratio, design.link_length, scene.gravity
    theta0 = 0.1
    run = _run(scene, design, [design.alpha, -theta0, design.alpha, design.alpha])
    # uniform rods: inertia n m_l l^2 / 3, weight at half the link
    t_ref, v_ref = _pendulum_arrival(theta0, M + n * m_link / 3.0, M + n * m_link / 2.0, tau,
                                     g, l, scene.palm.front_stop)
    assert run.from_rest == (1,)
    assert math.isclose(run.rest_since[1], t_ref, rel_tol=1e-7)
    # a palm whose weight's torque about the pivot is below the friction torque stays put
    held = 0.5 * math.asin(tau / ((M + n * m_link / 2.0) * g * l))
    run = _run(scene, design, [design.alpha, -held, design.alpha, design.alpha])
    assert run.from_rest == () and run.rest_since[1] == -math.inf


def test_a_back_stop_exactly_vertical_is_a_rest():
    scene, design = _paper()
    run = _run(scene, design, [design.alpha, 0.0, design.alpha, design.alpha])
    assert run.from_rest == () and run.rest_angle[1] == 0.0 and run.rest_since[1] == -math.inf


def test_the_object_reaching_a_palm_still_swinging_lands_on_it_and_a_parked_one_is_an_obstacle():
    scene, design = _paper()
    g, l = scene.gravity, design.link_length
    nominal = simulate_manipulators(scene, design, stages=STAGES)
    reach = nominal.stages[1]["landing_time"]  # the object reaches palm 2 here
    # palm 2 barely past the vertical: it is still swinging when the object gets there
    slow = 1e-6
    t_slow, _ = _pendulum_arrival(slow, 1.0, 1.0, 0.0, g, l, scene.palm.front_stop)
    assert t_slow > reach + 1.0
    result = simulate_manipulators(scene, design, stages=STAGES,
                                   parts=Parts(back_stop=(design.alpha, -slow, design.alpha,
                                                          design.alpha)))
    # palm 2 is met while it swings (barely moved yet): the object is handed onto it there and
    # carried on (tests/test_swinging_palm.py checks the impact and the carry)
    onto = next(e for e in result.events if e.kind == "handover" and e.stage == 1)
    assert onto.time < t_slow and onto.after["palm"] == 2 and result.outcome.completed
    assert 0.0 < onto.after["theta"] < 1e-3
    # palm 2 well past the vertical is parked at its front stop (horizontal, pointing ahead,
    # at its pivot's height) long before: the object never meets a palm at its old rest
    fast = 0.3
    t_fast, _ = _pendulum_arrival(fast, 1.0, 1.0, 0.0, g, l, scene.palm.front_stop)
    assert t_fast < reach
    result = simulate_manipulators(scene, design, stages=STAGES,
                                   parts=Parts(back_stop=(design.alpha, -fast, design.alpha,
                                                          design.alpha)))
    parked = [e for e in result.events if e.kind == "front_stop" and e.stage == 2]
    assert math.isclose(parked[0].time, t_fast, rel_tol=1e-9)
    assert all(e.after.get("palm") != 2 or e.after["theta"] == scene.palm.front_stop
               for e in result.events if e.kind in ("landing", "handover"))


def test_the_map_hands_builds_with_a_palm_past_the_vertical_to_the_simulator():
    scene, design = _paper()
    back = np.zeros((3, STAGES))
    back[1, 2] = -design.alpha - 0.01  # build 1, palm 3: alpha_3 = -0.01
    back[2, 1] = -design.alpha  # build 2, palm 2: exactly vertical
    out = run_builds(scene, design, {"back_stop": back}, STAGES)
    assert out.closed_form[0] and not out.closed_form[1] and out.closed_form[2]
