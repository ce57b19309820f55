"""After a lift-off on real links and pivots: the empty palm swings by Lagrange's equation of
palm + links with the Coulomb torque and damping, and the object lands back on it (or
elsewhere). Checked against a separate solve_ivp of the same equations written out here."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from pdm_design.scenes.manipulators.model import (
    Body,
    Links,
    ManipulatorsDesign,
    ManipulatorsInitial,
    ManipulatorsScene,
    Palm,
    Pivots,
)
from pdm_design.scenes.manipulators.sim import FAILURE_KINDS, simulate_manipulators

G, L, Q, M_OBJ = 9.81, 2.0, 10.0, 1.0
PALM = M_OBJ / Q
N_LINKS = 2
TIGHT = dict(method="DOP853", rtol=1e-13, atol=1e-14, dense_output=True)


def real_scene(link, torque, damping, *, ratio=1.05, alpha=0.5, beta=0.9, drop=0.2):
    """The object lands on palm 1's centre so fast that the palm no longer pushes it: on real
    links the landing keeps m V.t = (m + M + J) u, and the push m (g cos a - u^2 / l) cos a -
    m A sin a (A = l th'' - g sin th at -a) vanishes when u^2 = g l cos a - l A tan a; u^2 is
    `ratio` times that."""
    j = N_LINKS * link / 3.0
    inertia, weight = M_OBJ + PALM + j, M_OBJ + PALM + N_LINKS * link / 2.0
    thdd = (weight * G * L * math.sin(-alpha) - torque) / (inertia * L * L)  # (u: forward)
    along = L * thdd - G * math.sin(-alpha)
    u2 = ratio * (G * L * math.cos(alpha) - L * along * math.tan(-alpha))
    # damping at the landing takes c u / l more torque: ignored in `along`, ratio covers it
    u = math.sqrt(u2)
    vy = -math.sqrt(2 * G * drop)
    v_t = u * inertia / M_OBJ  # V . t(-a) = vx cos a + vy sin a
    vx = (v_t - vy * math.sin(alpha)) / math.cos(alpha)
    t1 = math.sqrt(2 * drop / G)
    x_land = -L * math.sin(alpha)
    scene = ManipulatorsScene(
        body=Body(mass=M_OBJ, width=0.2, height=0.05),
        palm=Palm(width=1.0, thickness=0.05, friction=5.0, restitution=0.0),
        initial=ManipulatorsInitial(position=(x_land - vx * t1, L * math.cos(alpha) + drop),
                                    velocity=(vx, 0.0)),
        gravity=G, links=Links(mass=link, count=N_LINKS),
        pivots=Pivots(friction_torque=torque, damping=damping))
    design = ManipulatorsDesign(alpha=alpha, beta=beta, link_length=L, mass_ratio=Q)
    return scene, design, t1


def empty_palm(theta0, omega0, link, torque, damping, t_end):
    """(M + J) l^2 th'' = (M + n m_l / 2) g l sin th - tau sgn(th') - c th', palm alone, by
    solve_ivp; split where th' = 0 (sgn changes: the palm turns or friction holds it)."""
    inertia = (PALM + N_LINKS * link / 3.0) * L * L
    weight = (PALM + N_LINKS * link / 2.0) * G * L
    pieces, t, y = [], 0.0, [theta0, omega0]
    while t < t_end:
        way = math.copysign(1.0, y[1]) if y[1] != 0.0 else math.copysign(1.0, y[0])
        if y[1] == 0.0 and abs(weight * math.sin(y[0])) <= torque:
            pieces.append((t, t_end, lambda s, th=y[0]: (th, 0.0)))  # held
            break

        def turn(s, z):
            return z[1]

        turn.terminal, turn.direction = True, -way
        sol = solve_ivp(lambda s, z, way=way: [z[1], (weight * math.sin(z[0]) - torque * way
                                             - damping * z[1]) / inertia],
                        (t, t_end), y, events=[turn], **TIGHT)
        pieces.append((t, sol.t[-1], sol.sol))
        t, y = sol.t[-1], [sol.y[0, -1], 0.0]
    return lambda s: next(f(s) for a, b, f in pieces if a <= s <= b)


@pytest.mark.parametrize("link,torque,damping", [(0.3, 0.0, 0.0), (0.3, 0.15, 0.0),
                                                  (0.05, 0.1, 0.05)])
def test_lift_off_on_real_links_lands_back_where_an_independent_solve_says(link, torque,
                                                                            damping):
    scene, design, t1 = real_scene(link, torque, damping)
    result = simulate_manipulators(scene, design, stages=3, accuracy="precise")
    kinds = [e.kind for e in result.events]
    assert "lift_off" in kinds
    lift = next(e for e in result.events if e.kind == "lift_off")
    assert lift.time == pytest.approx(t1, abs=1e-9)
    st = lift.after
    palm = empty_palm(st["theta"], st["omega"], link, torque, damping, 2.0)

    def gap(s):  # object's base over the palm's top, s after the lift-off
        return st["y"] + st["vy"] * s - 0.5 * G * s * s - L * math.cos(palm(s)[0])

    grid = np.linspace(1e-3, 2.0, 4000)
    values = [gap(s) for s in grid]
    i = next(i for i in range(len(grid) - 1) if values[i] > 0.0 >= values[i + 1])
    s_c = brentq(gap, grid[i], grid[i + 1], xtol=1e-15)
    th_c, w_c = palm(s_c)
    x_c = st["x"] + st["vx"] * s_c
    assert abs(x_c - L * math.sin(th_c)) < 0.5 * (0.2 + 1.0)  # over the palm's top
    landing = next(e for e in result.events if e.time > lift.time)
    assert landing.kind == "landing" and landing.after["palm"] == 1
    assert landing.time == pytest.approx(t1 + s_c, abs=1e-9)
    assert landing.before["theta"] == pytest.approx(th_c, abs=1e-9)
    assert landing.before["omega"] == pytest.approx(w_c, abs=1e-9)
    # the plastic impact on the moving palm keeps m V.t + (M + J) l w (links: radial impulse)
    v_t = st["vx"] * math.cos(th_c) - (st["vy"] - G * s_c) * math.sin(th_c)
    felt = PALM + N_LINKS * link / 3.0
    assert landing.after["omega"] * L == pytest.approx(
        (M_OBJ * v_t + felt * L * w_c) / (M_OBJ + felt), abs=1e-8)
    assert "lift_off_on_links" not in FAILURE_KINDS


def test_lift_off_on_real_links_off_the_last_palm_can_miss():
    """One manipulator whose front stop lies beyond the horizontal, a landing three times too
    fast: the object lifts off at once and flies over its palm, which swings on to its front
    stop (when the independent solve says) while the object falls 3 link lengths below the
    pivot: `missed`, when its ballistic path says."""
    import dataclasses

    scene, design, t1 = real_scene(0.3, 0.05, 0.0, ratio=3.0, alpha=0.3)
    scene = dataclasses.replace(scene, palm=dataclasses.replace(scene.palm, front_stop=1.8))
    result = simulate_manipulators(scene, design, stages=1, accuracy="precise")
    lift = next(e for e in result.events if e.kind == "lift_off")
    st = lift.after
    failure = result.outcome.failure
    assert failure.kind == "missed" and failure.stage == 1
    # y(s) = y0 + vy s - g s^2 / 2 = -3 L
    a, b, c = -0.5 * G, st["vy"], st["y"] + 3 * L
    s_fall = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    assert failure.time == pytest.approx(lift.time + s_fall, abs=1e-9)
    inertia = (PALM + N_LINKS * 0.3 / 3.0) * L * L
    weight = (PALM + N_LINKS * 0.3 / 2.0) * G * L

    def stop(s, z):
        return z[0] - 1.8

    stop.terminal, stop.direction = True, 1
    sol = solve_ivp(lambda s, z: [z[1], (weight * math.sin(z[0]) - 0.05) / inertia],
                    (0.0, 5.0), [st["theta"], st["omega"]], events=[stop], **TIGHT)
    (front,) = [e for e in result.events if e.kind == "front_stop"]
    assert front.time == pytest.approx(lift.time + sol.t_events[0][0], abs=1e-9)
