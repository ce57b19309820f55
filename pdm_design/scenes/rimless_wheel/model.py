"""The rimless wheel scene: spokes on a hub rolling down a ramp or a flight of stairs.

A frozen pydantic dataclass like every scene (scenes/common.py): constructing one validates it.
The wheel is a rigid body: a hub of `mass` (radius of gyration `gyration` about its centre) and
`spokes` uniform rods of `spoke_mass` each and length `leg_length`, evenly spaced, so its centre
of mass is the hub's centre for any number of spokes (>= 3).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BeforeValidator, Field
from pydantic.dataclasses import dataclass

from ..common import CONFIG, STANDARD_GRAVITY, NonNegative, Number, Positive

GROUNDS = ("ramp", "stairs")
# A wheel of more spokes than this is a rim to any tolerance the model can claim (the step's
# height change is below 1e-7 of the leg), and its step map's per-step loss 1 - eta^2 ~ 2 pi^2/n^2
# is below double precision's reach of the speed's square.
MAX_SPOKES = 100_000


def _whole(value):
    """An integer count: a TOML integer, or a float with an integer value (a free count's
    candidate comes back from the solver as a float); booleans and fractions are refused."""
    if isinstance(value, bool):
        raise ValueError("spokes must be an integer, not a boolean")
    if isinstance(value, float):
        if not value.is_integer():
            raise ValueError(f"spokes must be an integer, not {value:g}")
        return int(value)
    return value


SpokeCount = Annotated[int, BeforeValidator(_whole), Field(ge=3, le=MAX_SPOKES)]


@dataclass(frozen=True, config=CONFIG)
class Wheel:
    """The wheel's masses: mass at the hub (kg), its radius of gyration about the hub (m; 0: a
    point mass) and each spoke's mass (kg; uniform rods, 0: massless spokes)."""

    mass: Positive = 1.0
    gyration: NonNegative = 0.0
    spoke_mass: NonNegative = 0.0


@dataclass(frozen=True, config=CONFIG)
class RimlessWheelInitial:
    """The start: angular speed (rad/s, rolling forward) just after an impact on the ground as
    designed; speed_tolerance: the start speed lies anywhere in speed +- it (the robust NLP's
    box; 0: exactly speed)."""

    speed: Positive
    speed_tolerance: NonNegative = 0.0

    def __post_init__(self):
        if self.speed_tolerance >= self.speed:
            raise ValueError(f"speed_tolerance ({self.speed_tolerance:g}) must be below speed "
                             f"({self.speed:g}): the slowest start must still roll forward")


@dataclass(frozen=True, config=CONFIG)
class RimlessWheelScene:
    """Everything about a rimless wheel scene that the designer does not choose. friction:
    Coulomb's coefficient between a spoke's tip and the ground."""

    initial: RimlessWheelInitial
    wheel: Wheel = Wheel()
    ground: Literal["ramp", "stairs"] = "ramp"
    friction: NonNegative = 1.0
    gravity: Positive = STANDARD_GRAVITY

    kind = "rimless_wheel"


@dataclass(frozen=True, config=CONFIG)
class RimlessWheelDesign:
    """One rimless wheel design. slope (rad, downhill positive) is the ramp's; rise and tread
    (m) the stairs'. On stairs, tread is derived when left out as the one a spoke pitch spans
    (sqrt(chord^2 - rise^2), chord = 2 leg_length sin(pi / spokes): the wheel steps one stair per
    impact), and landing_offset (m from the back of a tread to the foothold) as the middle of the
    range the spoke clears the nose and lands on the tread."""

    spokes: SpokeCount
    leg_length: Positive
    slope: Number | None = None
    rise: NonNegative | None = None
    tread: Positive | None = None
    landing_offset: NonNegative | None = None

    VARIABLES = ("spokes", "leg_length", "slope", "rise", "tread", "landing_offset")


def check_ground(scene: RimlessWheelScene, design: RimlessWheelDesign) -> list[str]:
    """What a design lacks or has too much of for its scene's ground, in words (empty: fine)."""
    if scene.ground == "ramp":
        problems = [] if design.slope is not None else ["a ramp needs design.slope"]
        problems += [f"design.{name} is for stairs, not a ramp" for name in
                     ("rise", "tread", "landing_offset") if getattr(design, name) is not None]
        return problems
    problems = [] if design.rise is not None else ["stairs need design.rise"]
    if design.slope is not None:
        problems.append("design.slope is for a ramp; stairs take rise and tread")
    return problems
