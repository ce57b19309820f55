"""The manipulators scene: an object passed along a row of passive parallelogram manipulators."""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import Field, Strict
from pydantic.dataclasses import dataclass

from .common import (
    CONFIG,
    STANDARD_GRAVITY,
    Fraction,
    NonNegative,
    Number,
    Point,
    Positive,
    PositiveQuarterTurn,
    QuarterTurn,
)

PositiveHalfTurn = Annotated[float, Strict(), Field(gt=0, le=math.pi)]


@dataclass(frozen=True, config=CONFIG)
class Body:
    """The manipulated object: a rectangle that translates (it never rotates while modelled).
    width is along the row, height is vertical; its reference point is the bottom centre."""

    mass: Positive
    width: Positive
    height: Positive


@dataclass(frozen=True, config=CONFIG)
class Palm:
    """A palm: a horizontal slab whose top-surface centre is on the link circle.
    Neighbouring palms are interleaved across the row (like comb teeth), so palms pass each other
    but the object, spanning the teeth, cannot pass through one.

    front_stop is the angle (from the vertical, clockwise) where a palm that has handed its
    object over is stopped."""

    width: Positive
    thickness: Positive = 0.05
    friction: NonNegative = 0.8
    restitution: Fraction = 0.0
    front_stop: PositiveHalfTurn = math.pi / 2


@dataclass(frozen=True, config=CONFIG)
class ManipulatorsInitial:
    """Start of the object's flight: bottom-centre position (m) and velocity (m/s), in the frame
    whose origin is the first manipulator's pivot, x along the row, y up."""

    position: Point
    velocity: Point = (0.0, 0.0)


@dataclass(frozen=True, config=CONFIG)
class ManipulatorsScene:
    """Everything about a manipulators scene that the designer does not choose."""

    body: Body
    palm: Palm
    initial: ManipulatorsInitial
    gravity: Positive = STANDARD_GRAVITY

    kind = "manipulators"


@dataclass(frozen=True, config=CONFIG)
class ManipulatorsDesign:
    """One manipulators design: back-stop angle alpha, handover angle beta (rad, from the
    vertical), link length (m), mass ratio m/M of object to palm, and where the first pivot
    stands relative to the frame of the initial state (m)."""

    alpha: QuarterTurn
    beta: PositiveQuarterTurn
    link_length: Positive
    mass_ratio: Positive
    first_pivot_x: Number = 0.0
    first_pivot_y: Number = 0.0

    VARIABLES = ("alpha", "beta", "link_length", "mass_ratio", "first_pivot_x", "first_pivot_y")
