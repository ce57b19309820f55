"""Closed-form analysis over wide parameter ranges: finite answers or named refusals, never NaN,
and the invariances physics demands (dimensional analysis, momentum bookkeeping)."""

import math
import warnings

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pdm_design.analysis import analyse
from pdm_design.scenes.manipulators.model import (
    Body,
    ManipulatorsDesign,
    ManipulatorsInitial,
    ManipulatorsScene,
    Palm,
)
from pdm_design.scenes.stairs.model import Ball, StairsDesign, StairsInitial, StairsScene

HALF_PI = math.pi / 2


def manipulators_scene(scale=1.0):
    s, v = scale, math.sqrt(scale)
    return ManipulatorsScene(
        body=Body(mass=1.0, width=0.4 * s, height=0.2 * s),
        palm=Palm(width=1.6 * s, thickness=0.05 * s),
        initial=ManipulatorsInitial(position=(-1.25 * s, 3.05 * s), velocity=(3.0 * v, 0.0)),
    )


def _finite_or_none(analysis):
    values = [*analysis.margins.values(), *analysis.periodic.values(),
              *analysis.geometry.values()]
    return all(v is None or math.isfinite(v) for v in values)


angles = st.floats(0.0, HALF_PI, exclude_max=True)
positive_angles = st.floats(1e-9, HALF_PI, exclude_max=True)


@settings(max_examples=300, deadline=None)
@given(alpha=angles, beta=positive_angles,
       mass_ratio=st.floats(1e-6, 1e6), link_length=st.floats(1e-3, 500.0))
def test_manipulators_analysis_is_finite_everywhere(alpha, beta, mass_ratio, link_length):
    design = ManipulatorsDesign(alpha=alpha, beta=beta, link_length=link_length,
                                mass_ratio=mass_ratio)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        analysis = analyse(manipulators_scene(), design)
    assert _finite_or_none(analysis)
    assert all(-1.0 <= m <= 1.0 for m in analysis.margins.values())
    if abs(alpha + beta - HALF_PI) > 1e-12:  # the sign of cos(alpha + beta) is not rounding's
        assert (analysis.periodic["handover_speed"] is None) == (beta <= alpha
                                                                 or alpha + beta > HALF_PI)


@settings(max_examples=25, deadline=None)
@given(alpha=st.floats(0.05, 1.2), extra=st.floats(0.01, 1.0), speed=st.floats(0.0, 12.0))
def test_no_periodic_handover_beyond_a_right_angle_the_simulator_agrees(alpha, extra, speed):
    """alpha + beta > pi/2: the object handed over moves along t(beta), which points into the
    next palm's back stop, so that palm cannot carry it forward. The analysis says so, predicts
    no handover beyond the ones the simulator makes (it counts the carries that pass the top),
    and the simulator never completes a row of three however fast the object starts."""
    from pdm_design.scenes.manipulators.sim import simulate_manipulators

    scene = manipulators_scene()
    scene = scene.__class__(body=scene.body, palm=scene.palm, initial=ManipulatorsInitial(
        position=scene.initial.position, velocity=(speed, 0.0)))
    beta = min(alpha + extra, HALF_PI - 1e-3)  # beyond alpha: the carry gains height
    design = ManipulatorsDesign(alpha=alpha, beta=beta, link_length=2.0, mass_ratio=10.0)
    analysis = analyse(scene, design, 3)
    run = simulate_manipulators(scene, design, stages=3)
    beyond = alpha + beta > HALF_PI + 1e-9
    assert any("not below pi/2" in p for p in analysis.problems) == beyond
    if beyond:
        assert analysis.periodic["handover_speed"] is None
        assert not run.outcome.completed
        handovers = sum(e.kind == "handover" for e in run.events)
        assert len(analysis.approach.get("handover_speeds", [])) >= handovers


@settings(max_examples=300, deadline=None)
@given(restitution=st.floats(0.0, 1.0), launch_speed=st.floats(1e-6, 1e3),
       drop_height=st.floats(1e-6, 1e4), spin=st.floats(-100, 100))
def test_stairs_analysis_is_finite_or_refused(restitution, launch_speed, drop_height, spin):
    scene = StairsScene(initial=StairsInitial(drop_height=drop_height, spin=spin),
                        ball=Ball(radius=0.05, mass=0.3, inertia=3e-4), friction=0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        analysis = analyse(scene, StairsDesign(restitution=restitution,
                                               launch_speed=launch_speed))
    assert _finite_or_none(analysis)
    if restitution == 0.0:
        assert any("does not bounce" in p for p in analysis.problems)


@pytest.mark.parametrize("scale", [1e-3, 1e-1, 10.0, 300.0])
def test_manipulators_scale_invariance(scale):
    # Lengths times s and speeds times sqrt(s) keep every dimensionless quantity.
    design = dict(alpha=0.2, beta=0.6, mass_ratio=10.0)
    base = analyse(manipulators_scene(), ManipulatorsDesign(link_length=2.0, **design))
    scaled = analyse(manipulators_scene(scale),
                     ManipulatorsDesign(link_length=2.0 * scale, **design))
    for name, value in base.margins.items():
        assert scaled.margins[name] == pytest.approx(value, rel=1e-9, abs=1e-12)
    assert scaled.periodic["contraction"] == pytest.approx(base.periodic["contraction"], rel=1e-12)
    assert scaled.periodic["handover_speed"] == pytest.approx(
        base.periodic["handover_speed"] * math.sqrt(scale), rel=1e-12)
    assert scaled.geometry["pitch_x"] == pytest.approx(base.geometry["pitch_x"] * scale, rel=1e-12)


@pytest.mark.parametrize("mass_ratio", [1e-6, 1e6])
def test_extreme_mass_ratios_approach_their_limits(mass_ratio):
    # m/M -> 0: the palm absorbs all momentum, the map forgets the past (c -> 0).
    # m/M -> inf: the palm is weightless, c -> cos^2(alpha + beta).
    design = ManipulatorsDesign(alpha=0.2, beta=0.6, link_length=2.0, mass_ratio=mass_ratio)
    contraction = analyse(manipulators_scene(), design).periodic["contraction"]
    limit = 0.0 if mass_ratio < 1 else math.cos(0.8) ** 2
    assert contraction == pytest.approx(limit, abs=3e-6)


def test_stairs_restitution_one_gives_flat_floor():
    scene = StairsScene(initial=StairsInitial(drop_height=1.0))
    analysis = analyse(scene, StairsDesign(restitution=1.0, launch_speed=2.0))
    assert analysis.geometry["rise"] == 0.0
    assert analysis.geometry["tread"] == pytest.approx(2 * 2.0 * math.sqrt(2 / 9.81), rel=1e-12)
