"""Steps before failure on rough stairs (every step's rise and tread drawn): the Markov chain on
(stance energy, nose distance) against Monte Carlo on the step map."""

import math

import numpy as np
import pytest

from pdm_design.scenes.rimless_wheel import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
)
from pdm_design.scenes.rimless_wheel.builds import build_outcome
from pdm_design.scenes.rimless_wheel.rough_stairs import mfpt_interval, stairs_mfpt

SCENE = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.3), ground="stairs")
DESIGN = RimlessWheelDesign(spokes=8, leg_length=1.0, rise=0.0697, landing_offset=0.3836)


@pytest.mark.parametrize("rise,tread", [(0.06, 0.06), (0.08, 0.02)])
def test_chain_against_monte_carlo(rise, tread):
    """The chain (40 x 40 bins) against 4000 builds run until they fall (none lasts 400
    steps): within 4 standard errors and the chain's discretisation (its interval)."""
    rng = np.random.default_rng(0)
    builds, steps = 4000, 400
    rises = rng.normal(0, rise / 3, (builds, steps))
    treads = rng.normal(0, tread / 3, (builds, steps))
    # a thousand builds at a time (each build its own: the same runs, a quarter the memory)
    made = np.concatenate([
        build_outcome(SCENE, DESIGN, {"rise": rises[i:i + 1000], "tread": treads[i:i + 1000]},
                      steps).stages_passed for i in range(0, builds, 1000)])
    assert (made >= steps).sum() == 0
    mc, se = made.mean(), made.std(ddof=1) / math.sqrt(builds)
    found = mfpt_interval(SCENE, DESIGN, rise, tread)
    assert found["ci_low"] - 4 * se <= mc <= found["ci_high"] + 4 * se
    assert found["estimate"] == pytest.approx(mc, rel=0.05)


def test_the_nose_distance_matters():
    """Exact treads (a tolerance far below the rise's): the footholds barely drift and the
    wheel lasts longer than with treads as rough as the rises."""
    rough = stairs_mfpt(SCENE, DESIGN, 0.06, 0.06, bins=(30, 30))
    smooth = stairs_mfpt(SCENE, DESIGN, 0.06, 0.006, bins=(30, 30))
    assert smooth > rough


def test_a_ramp_is_refused():
    with pytest.raises(ValueError, match="stairs"):
        stairs_mfpt(RimlessWheelScene(initial=RimlessWheelInitial(speed=1.3)),
                    RimlessWheelDesign(spokes=8, leg_length=1.0, slope=0.08), 0.01, 0.01)
