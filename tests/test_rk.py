"""sim.rk, the plain-float port of solve_ivp's RK45 and DOP853 with events, against scipy's
solve_ivp itself on the same problems: the same events, their times and states equal up to
rounding (a rounding may flip a step's acceptance where the error estimate is within a few ulps
of the tolerance: the two paths then differ by well under the integration tolerance)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pdm_design.sim.rk import solve


def pendulum(t, y):  # a damped, driven pendulum and a sliding mass: four coupled states
    return [y[1], -9.81 / 2.0 * math.sin(y[0]) - 0.1 * y[1] + 0.3 * math.cos(t),
            y[3], -0.6 * 9.81 * math.copysign(1.0, y[3]) * 0.01 + 0.5 * y[1] ** 2]


def guards():
    """(g, direction, terminal): a terminal guard, and face-like crossings in both ways."""
    return [(lambda t, y: 1.2 - y[0], -1, True),
            (lambda t, y: y[1], 0, False),
            (lambda t, y: y[0] - 0.3, 1, False),
            (lambda t, y: y[2] - 0.05, -1, False)]


def scipy_events():
    out = []
    for g, direction, terminal in guards():
        def ev(t, y, g=g):
            return g(t, y)
        ev.direction, ev.terminal = direction, terminal
        out.append(ev)
    return out


@pytest.mark.parametrize("method,rtol,atol,max_step", [
    ("DOP853", 1e-9, 1e-11, math.inf), ("DOP853", 1e-6, 1e-8, math.inf),
    ("RK45", 1e-8, 1e-10, 0.05), ("RK45", 1e-5, 1e-8, math.inf)])
@pytest.mark.parametrize("start", [(0.2, 1.0, 0.0, 0.3), (-0.4, 2.2, 0.1, -0.2)])
def test_the_same_events_and_end_as_solve_ivp(method, rtol, atol, max_step, start):
    ours = solve(pendulum, 0.0, 6.0, list(start), method=method, rtol=rtol, atol=atol,
                 events=guards(), max_step=max_step)
    theirs = solve_ivp(pendulum, (0.0, 6.0), list(start), method=method, rtol=rtol,
                       atol=atol, events=scipy_events(), max_step=max_step)
    assert ours.status == theirs.status
    assert sum(map(len, theirs.t_events)) >= 2  # the problem does cross guards
    for mine, ref, mine_y, ref_y in zip(ours.t_events, theirs.t_events, ours.y_events,
                                        theirs.y_events):
        assert len(mine) == len(ref)
        np.testing.assert_allclose(mine, ref, rtol=0.0, atol=10 * rtol)
        if len(ref):
            np.testing.assert_allclose(np.array(mine_y), ref_y, rtol=10 * rtol, atol=10 * rtol)
    assert ours.t_last == pytest.approx(theirs.t[-1], rel=0.0, abs=10 * rtol)
    np.testing.assert_allclose(ours.y_last, theirs.y[:, -1], rtol=10 * rtol, atol=10 * rtol)


@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_dense_output_is_solve_ivps(method):
    ours = solve(pendulum, 0.0, 3.0, [0.2, 1.0, 0.0, 0.3], method=method, rtol=1e-8,
                 atol=1e-10, dense_output=True)
    theirs = solve_ivp(pendulum, (0.0, 3.0), [0.2, 1.0, 0.0, 0.3], method=method, rtol=1e-8,
                       atol=1e-10, dense_output=True)
    ts = np.linspace(0.0, 3.0, 37)
    np.testing.assert_allclose(ours.sol(ts), theirs.sol(ts), rtol=1e-11, atol=1e-11)
