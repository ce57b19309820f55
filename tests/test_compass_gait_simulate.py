"""The event simulator's falls against closed forms of the simplest walker (light legs: the hip
is an inverted pendulum on a massless stance leg, whatever the swing leg does):
    over the top   iff l w1^2 / 2 > g (1 - cos q1)   (energy; q1 < 0 from the vertical)
    flight         iff l w1^2 > g cos q1             (the leg's compression; no shear)
    slip           iff |tan(q1 - slope)| > friction  (the leg's force is along the leg)."""

import math

import pytest

from pdm_design.scenes.compass_gait import (
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    Walker,
)
from pdm_design.scenes.compass_gait.simulate import simulate_compass_gait

SIMPLEST = Walker(leg_length=1.0, leg_com=1.0, model="simplest")
SLOPE = 0.009


def run(start, friction=1.0, stages=1, errors=()):
    scene = CompassGaitScene(initial=CompassGaitInitial(*start), walker=SIMPLEST,
                             friction=friction, gravity=1.0)
    return simulate_compass_gait(scene, CompassGaitDesign(slope=SLOPE), stages=stages,
                                 step_errors=errors)


def failure(result):
    return result.outcome.failure.kind if result.outcome.failure else None


@pytest.mark.parametrize("factor,expected", [(0.99, "fell_backward"), (1.01, None)])
def test_over_the_top_or_back(factor, expected):
    q1 = -0.2
    over = math.sqrt(2 * (1 - math.cos(q1)))  # l = g = 1
    w1 = factor * over
    # the swing leg is given the rate that keeps it level with the stance leg's energy (it does
    # not act on the stance leg with light legs)
    result = run((q1, 2 * SLOPE - q1, w1, w1))
    assert (failure(result) == "fell_backward") == (expected == "fell_backward")


@pytest.mark.parametrize("factor", [0.99, 1.01])
def test_flight_when_the_leg_would_pull(factor):
    q1 = -0.2
    w1 = factor * math.sqrt(math.cos(q1))
    result = run((q1, 2 * SLOPE - q1, w1, w1))
    assert (failure(result) == "flight") == (factor > 1)


@pytest.mark.parametrize("factor", [0.99, 1.01])
def test_slip_when_the_leg_leans_beyond_the_friction_cone(factor):
    q1 = -0.2
    friction = factor * abs(math.tan(q1 - SLOPE))
    result = run((q1, 2 * SLOPE - q1, 0.2, 0.18), friction=friction)
    assert (failure(result) == "slip") == (factor < 1)


def test_scuffed_when_the_swing_leg_lags():
    # the swing leg starts swinging back: the stance leg passes it beyond the ramp's normal
    result = run((-0.2, 2 * SLOPE + 0.2, 0.25, 0.3))
    assert failure(result) == "scuffed"


def test_fell_forward_when_the_swing_leg_never_passes():
    # a point-mass pendulum falling forward leaves the ground (at cos q = 2/3 from rest): with
    # the swing leg still behind, that is a fall forward
    result = run((0.3, 0.9, 0.5, 0.5), friction=10.0)
    assert failure(result) == "fell_forward"


def test_a_steeper_step_is_a_longer_one():
    """Per-step slope errors: the same start on a steeper first step strikes later, further."""
    start = (-0.19, 0.21, 0.2, 0.18)
    flat, steep = run(start, errors=[0.0]), run(start, errors=[0.002])
    assert steep.stages[0]["slope"] == pytest.approx(SLOPE + 0.002)
    assert steep.stages[0]["step_length"] > flat.stages[0]["step_length"]
