"""The compass-gait scene: a two-legged passive walker (a hip and two straight legs) on a ramp.

Angles are of each leg's axis from the vertical, from its foot to the hip, positive when the hip
is downhill (ahead) of that foot: just after a heel strike the new stance leg leans back
(stance < 0) and the trailing swing leg forward (swing > 0). Rates are their time derivatives.
docs/compass_gait.md holds the derivations.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, Strict
from pydantic.dataclasses import dataclass

from ..common import CONFIG, STANDARD_GRAVITY, NonNegative, Number, Positive

PositiveHalfTurn = Annotated[float, Strict(), Field(gt=0, lt=3.141592653589793)]

MODELS = ("compass", "simplest")


@dataclass(frozen=True, config=CONFIG)
class Walker:
    """The walker. leg_com: the leg's centre of mass from the hip (m, in (0, leg_length]);
    leg_inertia: each leg's moment of inertia about its centre of mass (kg m^2; 0: point
    masses). model "simplest": Garcia's simplest walker, the limit leg_mass / hip_mass -> 0 with
    each leg's mass at its foot (leg_com = leg_length, no inertia); the masses are then unused."""

    hip_mass: Positive = 10.0
    leg_mass: Positive = 5.0
    leg_length: Positive = 1.0
    leg_com: Positive = 0.5
    leg_inertia: NonNegative = 0.0
    model: Literal["compass", "simplest"] = "compass"
    hip_limit: PositiveHalfTurn | None = None

    def __post_init__(self):
        if self.leg_com > self.leg_length:
            raise ValueError(f"leg_com {self.leg_com:g} m is beyond the foot: it must be at most "
                             f"leg_length {self.leg_length:g} m")


@dataclass(frozen=True, config=CONFIG)
class CompassGaitInitial:
    """The state just after a heel strike: leg angles from the vertical (rad) and their rates
    (rad/s); swing is the trailing leg, about to swing forward."""

    stance: Number
    swing: Number
    stance_rate: Number
    swing_rate: Number

    def state(self) -> tuple[float, float, float, float]:
        return (self.stance, self.swing, self.stance_rate, self.swing_rate)


@dataclass(frozen=True, config=CONFIG)
class CompassGaitScene:
    """Everything about a compass-gait scene that the designer does not choose."""

    initial: CompassGaitInitial
    walker: Walker = Walker()
    friction: NonNegative = 1.0
    gravity: Positive = STANDARD_GRAVITY

    kind = "compass_gait"


@dataclass(frozen=True, config=CONFIG)
class CompassGaitDesign:
    """One design: the ground (a ramp of `slope` rad, or stairs of `rise` and `tread` m) and any
    walker parameter the designer chooses (None: the scene's)."""

    slope: Number | None = None
    rise: NonNegative | None = None
    tread: Positive | None = None
    hip_mass: Positive | None = None
    leg_mass: Positive | None = None
    leg_length: Positive | None = None
    leg_com: Positive | None = None
    leg_inertia: NonNegative | None = None

    VARIABLES = ("slope", "rise", "tread", "hip_mass", "leg_mass", "leg_length", "leg_com",
                 "leg_inertia")
    WALKER = ("hip_mass", "leg_mass", "leg_length", "leg_com", "leg_inertia")

    def __post_init__(self):
        stairs = self.rise is not None or self.tread is not None
        if self.slope is None and not stairs:
            raise ValueError("give the ground: slope (a ramp) or rise and tread (stairs)")
        if self.slope is not None and stairs:
            raise ValueError("give slope (a ramp) or rise and tread (stairs), not both")
        if stairs and (self.rise is None or self.tread is None):
            raise ValueError("stairs need both rise and tread")

    def walker(self, scene: CompassGaitScene) -> Walker:
        """The scene's walker with this design's parameters in place of its own."""
        base = scene.walker
        values = {k: getattr(base, k) for k in self.WALKER}
        values.update({k: v for k in self.WALKER if (v := getattr(self, k)) is not None})
        return Walker(**values, model=base.model, hip_limit=base.hip_limit)
