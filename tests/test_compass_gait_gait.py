"""Periodic gaits of the compass gait against independent sources: the energy balance of every
periodic gait, the simplest walker's small-slope asymptotics (derived below, as Garcia et al.
1998), Goswami, Thuilot & Espiau (1996)'s classic walker, and the gait the event simulator
settles into."""

import math

import numpy as np
import pytest

from pdm_design.scenes.compass_gait import (
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    Walker,
)
from pdm_design.scenes.compass_gait import physics as phys
from pdm_design.scenes.compass_gait.gait import find_gait, fixed_point, period_two
from pdm_design.scenes.compass_gait.ground import ground_of, params_for
from pdm_design.scenes.compass_gait.simulate import simulate_compass_gait

GOSWAMI = Walker(hip_mass=10.0, leg_mass=5.0, leg_length=1.0, leg_com=0.5)
SIMPLEST = Walker(leg_length=1.0, leg_com=1.0, model="simplest")


def scene(walker=GOSWAMI, gravity=9.81, start=(-0.22, 0.32, 1.1, 0.4)):
    return CompassGaitScene(initial=CompassGaitInitial(*start), walker=walker, gravity=gravity)


def kinetic_loss_and_drop(sc, design, x_after, period=1):
    """(kinetic energy the heel strikes take, potential energy the walker's weight releases)
    over `period` steps, per hip mass: the centre of mass goes down the ramp one step length a
    step, so the drop is the weight x the step length x sin(slope)."""
    params, ground = params_for(sc, design), ground_of(design, params_for(sc, design))
    from pdm_design.scenes.compass_gait import stepmap

    x, loss, drop = np.asarray(x_after), 0.0, 0.0
    for _ in range(period):
        gait = find_gait(sc, design, x) if period == 1 else None
        T = gait.step_period if gait else _step_time(params, ground, x)
        end, after, _ = stepmap.step(params, ground, x, T)
        loss += phys.kinetic_energy(*end, params) - phys.kinetic_energy(*after, params)
        length = phys.step_length(end[0], end[1], params)
        drop += (1 + 2 * params.beta) * params.g * length * math.sin(ground.slope)
        x = after
    return loss, drop


def _step_time(params, ground, x):
    from pdm_design.accuracy import accuracy
    from pdm_design.scenes.compass_gait.simulate import one_step

    return one_step(params, ground, x, math.inf, accuracy("precise")).time


@pytest.mark.parametrize("walker,gravity,slope,start", [
    (GOSWAMI, 9.81, math.radians(3.0), (-0.22, 0.32, 1.1, 0.4)),
    (GOSWAMI, 9.81, math.radians(4.0), (-0.23, 0.37, 1.14, 0.22)),
    (SIMPLEST, 1.0, 0.009, (-0.19, 0.21, 0.2, 0.18)),
])
def test_heel_strikes_take_what_the_slope_gives(walker, gravity, slope, start):
    sc, design = scene(walker, gravity, start), CompassGaitDesign(slope=slope)
    gait = find_gait(sc, design)
    loss, drop = kinetic_loss_and_drop(sc, design, gait.state)
    assert loss == pytest.approx(drop, rel=1e-8)


def test_the_period_two_gait_balances_its_energy_over_two_steps():
    sc, design = scene(start=(-0.23, 0.39, 1.15, 0.13)), CompassGaitDesign(slope=math.radians(4.5))
    gait = find_gait(sc, design)
    params = params_for(sc, design)
    two = period_two(params, ground_of(design, params), gait)
    assert two is not None and two.period == 2
    loss, drop = kinetic_loss_and_drop(sc, design, two.state, period=2)
    assert loss == pytest.approx(drop, rel=1e-8)


def asymptotic_gait(slope):
    """The simplest walker's leading-order gait (g = l = 1): linearised stance theta'' = theta
    and swing phi'' = theta - phi from theta(0) = -theta0, phi(0) = -2 theta0 with the impact's
    leading order (rates unchanged); symmetry theta(tau) = theta0 gives theta'(0) = theta0
    coth(tau/2), the heel strike phi(tau) = 2 theta(tau) gives 3 cos tau + coth(tau/2) sin tau
    + 3 = 2 cos(tau/2) (3 cos(tau/2) + coth(tau/2) sin(tau/2)) = 0: tau = pi (the short-period
    gait) or the long period's tan(tau/2) = -3 tanh(tau/2), and the energy lost at the strike,
    2 theta0^2 theta'^2, equal to the drop 2 theta0 slope, gives theta0^3 coth^2(tau/2) = slope:
    theta0 = tanh^(2/3)(tau/2) slope^(1/3) (Garcia et al. 1998: 0.970 slope^(1/3), tau = 3.812)."""
    from scipy.optimize import brentq

    half = brentq(lambda x: 3 * math.cos(x) + math.sin(x) / math.tanh(x), 1.6, 2.3)
    tau = 2 * half
    theta0 = math.tanh(tau / 2) ** (2 / 3) * slope ** (1 / 3)
    return tau, theta0, theta0 / math.tanh(tau / 2)


def test_asymptotics_reproduce_garcias_constants():
    tau, theta0, rate = asymptotic_gait(1.0)
    assert tau == pytest.approx(3.812, abs=1e-3)
    assert theta0 == pytest.approx(0.970, abs=1e-3)


@pytest.mark.parametrize("slope", [1e-4, 1e-3])
def test_simplest_walker_matches_its_small_slope_asymptotics(slope):
    tau, theta0, rate = asymptotic_gait(slope)
    # a guess 10 % off the asymptotic gait (that still takes a step)
    start = (slope - 1.1 * theta0, slope + 1.1 * theta0, 1.1 * rate, 1.1 * rate)
    sc = CompassGaitScene(initial=CompassGaitInitial(*start), walker=SIMPLEST, gravity=1.0)
    gait = find_gait(sc, CompassGaitDesign(slope=slope))
    q1, _, w1, _ = gait.state
    # the corrections are O(slope^(2/3)) relative: 0.2 % at 1e-4, 1 % at 1e-3
    rel = 3 * slope ** (2 / 3)
    assert slope - q1 == pytest.approx(theta0, rel=rel)
    assert w1 == pytest.approx(rate, rel=rel)
    assert gait.step_period == pytest.approx(tau, rel=rel)


def test_goswamis_classic_gait_at_three_degrees():
    """Goswami, Thuilot & Espiau (1996), a = b = 0.5 m, mH = 10 kg, m = 5 kg, 3 deg, g = 9.8:
    the gait (0.2187, -0.3234, -0.3772, -1.0918) in their convention: the leg leaning back
    0.2187 rad (our stance) moves at 1.0918 rad/s, the trailing leg (0.3234 rad) at 0.3772."""
    sc = scene(gravity=9.8, start=(-0.2, 0.3, 1.0, 0.3))
    gait = fixed_point(sc, CompassGaitDesign(slope=math.radians(3.0)))
    point = gait["fixed_point"]
    assert point["stance"] == pytest.approx(-0.2187, abs=6e-5)
    assert point["swing"] == pytest.approx(0.3234, abs=6e-5)
    assert point["stance_rate"] == pytest.approx(1.0918, abs=6e-5)
    assert point["swing_rate"] == pytest.approx(0.3772, abs=6e-5)
    assert gait["spectral_radius"] < 1.0


def test_the_gait_found_is_the_one_the_simulator_settles_into():
    sc, design = scene(start=(-0.23, 0.33, 1.15, 0.3)), CompassGaitDesign(slope=math.radians(3.5))
    gait = find_gait(sc, design, (-0.2, 0.3, 1.0, 0.3))
    run = simulate_compass_gait(sc, design, stages=80, accuracy="precise")
    assert run.outcome.completed
    last = run.stages[-1]
    settled = [last[k] for k in ("stance", "swing", "stance_rate", "swing_rate")]
    assert settled == pytest.approx(gait.state, abs=1e-7)
    assert last["step_period"] == pytest.approx(gait.step_period, abs=1e-7)


def test_goswamis_walker_doubles_its_period_as_the_slope_grows():
    """Stable at 4 deg; at 4.5 deg a multiplier is below -1 and the simulator, from the unstable
    period-1 gait's neighbourhood, settles into the two-step gait the two-step map finds."""
    sc = scene(start=(-0.23, 0.37, 1.14, 0.22))
    at4 = find_gait(sc, CompassGaitDesign(slope=math.radians(4.0)))
    assert at4.spectral_radius < 1.0
    design = CompassGaitDesign(slope=math.radians(4.5))
    one = find_gait(sc, design, at4.state)
    assert min(m.real for m in one.multipliers) < -1.0
    params = params_for(sc, design)
    two = period_two(params, ground_of(design, params), one)
    assert two.spectral_radius < 1.0
    run = simulate_compass_gait(sc, design, stages=120, accuracy="precise",
                                start=np.asarray(one.state) + 1e-4)
    names = ("stance", "swing", "stance_rate", "swing_rate")
    ends = [np.array([run.stages[k][n] for n in names]) for k in (-2, -1)]
    nearest = min(np.max(np.abs(e - np.asarray(two.state))) for e in ends)
    assert nearest < 1e-6


def test_on_stairs_each_strike_takes_one_rise_of_potential_energy():
    from pdm_design.scenes.compass_gait import stepmap

    sc, design = scene(), CompassGaitDesign(rise=0.028, tread=0.53)
    gait = find_gait(sc, design)
    params = params_for(sc, design)
    end, after, _ = stepmap.step(params, ground_of(design, params), gait.state,
                                 gait.step_period)
    loss = phys.kinetic_energy(*end, params) - phys.kinetic_energy(*after, params)
    assert loss == pytest.approx((1 + 2 * params.beta) * params.g * 0.028, rel=1e-8)
    # the swing foot lands one rise below the stance foot
    assert params.l * (math.cos(end[0]) - math.cos(end[1])) == pytest.approx(-0.028, abs=1e-12)
