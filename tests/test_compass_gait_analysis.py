"""The analysis' margins against closed forms: the simplest walker's stance leg is a pendulum
whose force is along the leg, so over its step (energy: l w^2 = l w0^2 + 2 g (cos q0 - cos q))
    normal / weight = (cos q - l w^2 / g) cos(q - slope),  friction needed = |tan(q - slope)|;
the hip limit's margin against the largest angle between the legs of a densely sampled step."""

import math

import numpy as np
import pytest

from pdm_design.analysis.result import margin
from pdm_design.scenes.compass_gait import (
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    Walker,
    stepmap,
)
from pdm_design.scenes.compass_gait.analysis import analyse_compass_gait
from pdm_design.scenes.compass_gait.gait import find_gait
from pdm_design.scenes.compass_gait.ground import ground_of, params_for

SLOPE = 0.009


def test_simplest_walker_margins_are_the_pendulums():
    scene = CompassGaitScene(initial=CompassGaitInitial(-0.1913, 0.2093, 0.1998, 0.1840),
                             walker=Walker(leg_length=1.0, leg_com=1.0, model="simplest"),
                             gravity=1.0, friction=0.5)
    design = CompassGaitDesign(slope=SLOPE)
    result = analyse_compass_gait(scene, design)
    q0, w0 = (result.periodic["fixed_point"][k] for k in ("stance", "stance_rate"))
    q = np.linspace(q0, 2 * SLOPE - q0, 20001)  # the stance leg's sweep over the step
    w2 = w0**2 + 2 * (math.cos(q0) - np.cos(q))
    normal = (np.cos(q) - w2) * np.cos(q - SLOPE)
    assert result.margins["stance_contact"] == pytest.approx(normal.min(), abs=1e-6)
    demand = np.abs(np.tan(q - SLOPE)).max()
    assert result.margins["no_slip"] == pytest.approx(margin(0.5, demand), abs=1e-6)


def test_hip_limit_margin():
    walker = Walker(hip_mass=10.0, leg_mass=5.0, leg_com=0.5, hip_limit=0.6)
    scene = CompassGaitScene(initial=CompassGaitInitial(-0.22, 0.32, 1.1, 0.4), walker=walker)
    design = CompassGaitDesign(slope=math.radians(3.0))
    gait = find_gait(scene, design)
    params = params_for(scene, design)
    ground = ground_of(design, params)
    times = np.linspace(0.0, gait.step_period, 2001)[1:]
    spread = max(abs(stepmap.step(params, ground, gait.state, t)[0][0]
                     - stepmap.step(params, ground, gait.state, t)[0][1]) for t in times)
    result = analyse_compass_gait(scene, design)
    assert result.margins["hip_limit"] == pytest.approx(margin(0.6, spread), abs=2e-4)
