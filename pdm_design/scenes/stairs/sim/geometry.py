"""The staircase a stairs design describes, as built (with per-step construction errors).

Global frame: x downhill, y up, nominal tread 1 at y = 0, the launch at x = 0. Step k (k >= 1)
has a tread of length ``tread + tread_error_k`` and a riser of height ``rise + rise_error_k`` at
the back of its tread; every step is built on the one before, so a step's error shifts all later
steps. Step 0 is the top landing, running back without end. See `pdm_design.scenes.stairs.sim`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ....sim.core import SimulationRefused
from .. import physics as phys
from ..model import StairsDesign, StairsScene
from .maps import impact_once


@dataclass(frozen=True)
class StairsGeometry:
    """The staircase as built, plus the launch. Global frame: nominal tread 1 at y = 0, launch
    at x = 0. rise, tread: nominal; landing_offset: where the first landing is designed to be
    (from the back of tread 1); x_back_1: the back of tread 1 (= nose of step 0)."""

    rise: float
    tread: float
    landing_offset: float
    x_back_1: float
    launch_height: float
    rise_errors: dict[int, float] = field(default_factory=dict)
    tread_errors: dict[int, float] = field(default_factory=dict)

    def tread_length(self, j: int) -> float:
        return math.inf if j == 0 else self.tread + self.tread_errors.get(j, 0.0)

    def rise_height(self, j: int) -> float:
        return self.rise + self.rise_errors.get(j, 0.0)

    def nose_x(self, j: int) -> float:
        """Global x of step j's nose (j >= 0)."""
        return self.x_back_1 + j * self.tread + _error_sum(self.tread_errors, 0, j)

    def back_x(self, j: int) -> float:
        return -math.inf if j == 0 else self.nose_x(j - 1)

    def level(self, j: int) -> float:
        """Global height of step j's tread surface."""
        return (1 - j) * self.rise - _error_sum(self.rise_errors, 0, j)

    def relative(self, k: int, j: int) -> tuple[float, float, float]:
        """(back, nose, level) of step j in the frame at step k's nose and level."""
        if not self.tread_errors and not self.rise_errors and j > 0:
            nose = (j - k) * self.tread
            return nose - self.tread, nose, -(j - k) * self.rise
        nose = (j - k) * self.tread + _error_diff(self.tread_errors, k, j)
        level = -(j - k) * self.rise - _error_diff(self.rise_errors, k, j)
        if j == 0:
            back = -math.inf
        else:
            back = nose - self.tread_length(j)
        return back, nose, level


def _error_sum(errors: dict[int, float], k: int, j: int) -> float:
    """Sum of errors of steps k < i <= j (k <= j)."""
    if not errors:
        return 0.0
    return math.fsum(v for i, v in errors.items() if k < i <= j)


def _error_diff(errors: dict[int, float], k: int, j: int) -> float:
    """sum_{i<=j} - sum_{i<=k} of the errors."""
    if not errors or j == k:
        return 0.0
    return _error_sum(errors, k, j) if j > k else -_error_sum(errors, j, k)


def stairs_geometry(scene: StairsScene, design: StairsDesign, step_errors=()) -> StairsGeometry:
    """The staircase a design describes (rise, tread, landing offset derived where left out).

    rise = (1 - eps^2) h0 and tread = vx1 (1 + eps) v*/g, with vx1 the horizontal speed after
    the first impact (the impact map applied to the launch state) and v* the periodic vertical
    impact speed: sqrt(2 g h0) for a derived rise, sqrt(2 g rise / (1 - eps^2)) for a given one.
    landing_offset defaults to tread / 2. Raises SimulationRefused (a ValueError) when no tread
    can be derived or an error makes a step's tread non-positive or its rise negative.
    """
    g, h0 = scene.gravity, scene.initial.drop_height
    eps, v0 = design.restitution, design.launch_speed
    rise = (1.0 - eps**2) * h0 if design.rise is None else design.rise
    tread = design.tread
    if tread is None:
        if design.rise is None or (rise == 0.0 and eps == 1.0):
            v_star = math.sqrt(2.0 * g * h0)
        elif eps < 1.0:
            v_star = float(phys.periodic_vertical_speed(g, rise, eps))
        else:
            raise SimulationRefused("restitution 1 with a rise > 0 has no periodic orbit: give "
                                    "the tread")
        ball = scene.ball
        vx1 = impact_once(v0, -math.sqrt(2.0 * g * h0), scene.initial.spin, eps, scene.friction,
                      ball.radius, ball.mass, ball.inertia)[0]
        tread = float(phys.periodic_tread(vx1, g, v_star**2 / (2.0 * g), eps))
        if not vx1 > 0.0:
            raise SimulationRefused(f"the ball moves at {vx1:g} m/s along the stairs after the "
                                    "first impact (its spin sends it back): it does not go down "
                                    "them, so no tread follows from its flight")
        if not tread > 0.0:
            raise SimulationRefused(f"the derived tread is {tread:g} m (restitution {eps:g}, "
                                    f"horizontal speed after the first impact {vx1:g} m/s): "
                                    "give the tread")
    landing = tread / 2.0 if design.landing_offset is None else design.landing_offset
    t1 = math.sqrt(2.0 * h0 / g)
    rise_errors: dict[int, float] = {}
    tread_errors: dict[int, float] = {}
    for e in step_errors:
        step, d_rise, d_tread = _step_error_fields(e)
        if step in rise_errors:
            raise ValueError(f"step errors: step {step} is listed twice")
        rise_errors[step], tread_errors[step] = d_rise, d_tread
    for step, d in tread_errors.items():
        if not tread + d > 0.0:
            raise SimulationRefused(f"step {step}: tread error {d:g} m leaves no tread "
                             f"(nominal tread {tread:g} m)")
    for step, d in rise_errors.items():
        if rise + d < 0.0:
            raise SimulationRefused(f"step {step}: rise error {d:g} m makes the step go up "
                             f"(nominal rise {rise:g} m)")
    return StairsGeometry(
        rise=float(rise), tread=float(tread), landing_offset=float(landing),
        x_back_1=v0 * t1 - landing, launch_height=float(h0),
        rise_errors={k: v for k, v in rise_errors.items() if v != 0.0},
        tread_errors={k: v for k, v in tread_errors.items() if v != 0.0},
    )


def _step_error_fields(e):
    if isinstance(e, dict):  # as a spec's [verification] table takes it: checked alike
        from ...common import StepError

        e = StepError(**e)
    step = int(e.step)
    if step < 1:
        raise SimulationRefused(f"step errors are numbered from 1, not {step}")
    return step, float(getattr(e, "rise", 0.0)), float(getattr(e, "tread", 0.0))
