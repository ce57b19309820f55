"""Continuation over the slope: the period doubling the sweep reports, checked against the
multipliers of the event simulator's return map (central differences) on either side of it."""

import math

import numpy as np
import pytest

from pdm_design.accuracy import accuracy
from pdm_design.scenes.compass_gait import (
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    Walker,
)
from pdm_design.scenes.compass_gait.bifurcation import plot_sweep, sweep
from pdm_design.scenes.compass_gait.gait import find_gait
from pdm_design.scenes.compass_gait.ground import ground_of, params_for
from pdm_design.scenes.compass_gait.simulate import one_step
from pdm_design.scenes.compass_gait.stepmap import multipliers_of

SCENE = CompassGaitScene(initial=CompassGaitInitial(-0.22, 0.32, 1.1, 0.4),
                         walker=Walker(hip_mass=10.0, leg_mass=5.0, leg_com=0.5))


def simulator_multipliers(slope, near):
    design = CompassGaitDesign(slope=slope)
    gait = find_gait(SCENE, design, near)
    params = params_for(SCENE, design)
    ground = ground_of(design, params)

    def step(x):
        return one_step(params, ground, x, math.inf, accuracy("precise")).after

    x, h = np.asarray(gait.state), 1e-5
    fd = np.column_stack([(step(x + h * e) - step(x - h * e)) / (2 * h) for e in np.eye(4)])
    return multipliers_of(fd), gait.state


@pytest.fixture(scope="module")
def swept():
    return sweep(SCENE, CompassGaitDesign(slope=0.05), np.radians(np.linspace(3.0, 5.0, 21)))


def test_the_period_doubling_is_where_the_simulators_multiplier_passes_minus_one(swept):
    doublings = [b for b in swept["bifurcations"] if b["kind"] == "period_doubling"]
    assert len(doublings) == 1
    value = doublings[0]["value"]
    assert math.radians(4.0) < value < math.radians(4.5)
    state = swept["points"][10]["fixed_point"]
    near = [state[k] for k in ("stance", "swing", "stance_rate", "swing_rate")]
    # the multiplier moves ~55 per rad here: 2e-5 rad moves it 1e-3, 1000 times the
    # differences' error
    before, _ = simulator_multipliers(value - 2e-5, near)
    after, _ = simulator_multipliers(value + 2e-5, near)
    assert min(m.real for m in before) > -1.0
    assert min(m.real for m in after) < -1.0


def test_stability_and_period_two_beyond_the_doubling(swept):
    value = swept["bifurcations"][0]["value"]
    for point in swept["points"]:
        assert point["stable"] == (point["slope"] < value)
    two = swept["period_two"]
    assert two and all(p["slope"] > value for p in two)
    # the two steps of a period-2 gait straddle the period-1 step length
    p1 = {p["slope"]: p["step_length"] for p in swept["points"]}
    for p in two:
        short, long_ = sorted(p["step_lengths"])
        assert short < p1[p["slope"]] < long_


def test_plot_is_written(swept, tmp_path):
    pytest.importorskip("matplotlib")
    path = tmp_path / "sweep.png"
    plot_sweep(swept, path)
    assert path.stat().st_size > 1000


def test_simplest_walker_period_doubles_where_garcia_found():
    """Garcia et al. (1998): the simplest walker's stable gait period-doubles at slope
    0.0151 (three digits)."""
    scene = CompassGaitScene(initial=CompassGaitInitial(-0.1913, 0.2093, 0.1998, 0.1840),
                             walker=Walker(leg_length=1.0, leg_com=1.0, model="simplest"),
                             gravity=1.0)
    result = sweep(scene, CompassGaitDesign(slope=0.009), np.linspace(0.009, 0.02, 23),
                   period_two_gaits=False)
    kinds = [(b["kind"], b["value"]) for b in result["bifurcations"]]
    assert len(kinds) == 1 and kinds[0][0] == "period_doubling"
    assert kinds[0][1] == pytest.approx(0.0151, abs=5e-5)
