"""Typed, self-validating building blocks shared by the scenes.

Scenes are frozen pydantic dataclasses: constructing one validates it, whether from a spec file
or from Python. Numbers are strict (no strings, no booleans) and finite; unknown fields are errors.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import ConfigDict, Field, Strict
from pydantic.dataclasses import dataclass

CONFIG = ConfigDict(extra="forbid", allow_inf_nan=False)

# Every physical magnitude is bounded: from micrometres, milligrams and mm/s to a thousand
# kilometres, a thousand tonnes and 1000 km/s. Outside that, squares and products in the closed
# forms would overflow or underflow long before a design could mean anything, so such input is
# refused at the spec's key rather than answered with inf or NaN.
LARGEST = 1e6
SMALLEST = 1e-6
Number = Annotated[float, Strict(), Field(ge=-LARGEST, le=LARGEST)]
Positive = Annotated[float, Strict(), Field(ge=SMALLEST, le=LARGEST)]
NonNegative = Annotated[float, Strict(), Field(ge=0, le=LARGEST)]
Fraction = Annotated[float, Strict(), Field(ge=0, le=1)]
# Angles of a manipulator measured from the vertical: the palm must stay above its pivot.
QuarterTurn = Annotated[float, Strict(), Field(ge=0, lt=math.pi / 2)]
PositiveQuarterTurn = Annotated[float, Strict(), Field(gt=0, lt=math.pi / 2)]
Point = tuple[Number, Number]


def is_number(value) -> bool:
    """A TOML number (int or float; TOML's booleans are not numbers here)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)

STANDARD_GRAVITY = 9.81


@dataclass(frozen=True, config=CONFIG)
class StepError:
    """Construction error of one step (numbered from 1): rise and tread errors in m (the items
    of the `[verification] step_errors` a stepping scene takes)."""

    step: Annotated[int, Strict(), Field(ge=1)]
    rise: Number = 0.0
    tread: Number = 0.0


@dataclass(frozen=True, config=CONFIG)
class SlopeStepError(StepError):
    """A walker's ground error at one step (numbered from 1): the step's slope error in rad on a
    ramp; on stairs its rise and tread errors in m."""

    slope: Number = 0.0


@dataclass(frozen=True, config=CONFIG)
class SlopeError:
    """The slope error of one step (numbered from 1) in rad, of a ground made of ramps."""

    step: Annotated[int, Strict(), Field(ge=1)]
    slope: Number = 0.0


# The random streams of the first scenes' toleranced quantities, in the order that
# SeedSequence(seed).spawn gave them before the streams were keyed by name (tolerances/draw.py):
# closed, never extended, so that those quantities' builds stay the same.
FIRST_STREAMS = ("pivot_x", "pivot_y", "link_length", "back_stop", "palm_mass", "friction",
                 "object_mass", "object_width", "feed_x", "feed_speed", "rise", "tread",
                 "restitution", "launch_speed", "launch_x", "link_mass", "pivot_friction")


def first_stream_keys(*names: str) -> dict[str, int]:
    """{quantity: its place in FIRST_STREAMS}: the Scene.stream_keys of a scene's quantities
    that are among them."""
    return {name: FIRST_STREAMS.index(name) for name in names}
