"""A wheel whose periodic speed cannot vault its spoke has no rolling orbit, said in words.

Six spokes of 0.5 m, a 2 kg hub of gyration 0.1 m and 50 g spokes: an independent derivation
(the impact ratio eta = 1 - 2 rho sin^2(alpha), the orbit's post-impact speed against the
energy to vault the spoke from -alpha + slope) puts the least slope that rolls at 0.1614 rad.
"""

import pytest

from pdm_design.scenes.rimless_wheel.analysis import analyse_rimless_wheel
from pdm_design.scenes.rimless_wheel.model import (
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    Wheel,
)

SCENE = RimlessWheelScene(initial=RimlessWheelInitial(speed=2.0), ground="ramp",
                          wheel=Wheel(mass=2.0, gyration=0.1, spoke_mass=0.05))


@pytest.mark.parametrize("slope, rolls", [(0.10, False), (0.160, False), (0.163, True),
                                          (0.20, True)])
def test_no_rolling_orbit_below_the_least_slope_that_rolls(slope, rolls):
    found = analyse_rimless_wheel(SCENE, RimlessWheelDesign(spokes=6, leg_length=0.5,
                                                            slope=slope))
    said = any(p.startswith("no rolling orbit") for p in found.problems)
    assert said is not rolls
    assert (found.periodic["step_period"] is not None) is rolls
