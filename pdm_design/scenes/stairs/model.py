"""The stairs scene: a ball launched horizontally above a flight of stairs."""

from __future__ import annotations

from pydantic.dataclasses import dataclass

from ..common import CONFIG, STANDARD_GRAVITY, Fraction, NonNegative, Number, Positive


@dataclass(frozen=True, config=CONFIG)
class Ball:
    """The ball. radius 0 is a point ball; inertia is about its centre (kg m^2)."""

    radius: NonNegative = 0.0
    mass: Positive = 1.0
    inertia: NonNegative = 0.0


@dataclass(frozen=True, config=CONFIG)
class StairsInitial:
    """Launch state: lowest point of the ball drop_height above the first tread, moving
    horizontally (launch speed is a design quantity), spinning at spin rad/s (counter-clockwise
    positive, so backspin is positive for a ball moving in +x)."""

    drop_height: Positive
    spin: Number = 0.0


@dataclass(frozen=True, config=CONFIG)
class StairsScene:
    """Everything about a stairs scene that the designer does not choose."""

    initial: StairsInitial
    ball: Ball = Ball()
    friction: NonNegative = 0.0
    gravity: Positive = STANDARD_GRAVITY

    kind = "stairs"

    def __post_init__(self):
        if self.friction > 0 and self.ball.radius == 0:
            raise ValueError("friction > 0 needs ball.radius > 0: a point ball cannot roll")

    @property
    def frictionless(self) -> bool:
        return self.friction == 0.0


@dataclass(frozen=True, config=CONFIG)
class StairsDesign:
    """One stairs design. rise, tread and landing_offset are derived when left out:
    rise and tread from the periodic orbit, landing_offset as the middle of the tread.
    landing_offset is measured from the back (riser) of a tread to where the ball lands."""

    restitution: Fraction
    launch_speed: Positive
    rise: NonNegative | None = None
    tread: Positive | None = None
    landing_offset: NonNegative | None = None

    VARIABLES = ("restitution", "launch_speed", "rise", "tread", "landing_offset")
