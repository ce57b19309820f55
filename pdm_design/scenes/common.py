"""Typed, self-validating building blocks shared by the scenes.

Scenes are frozen pydantic dataclasses: constructing one validates it, whether from a spec file
or from Python. Numbers are strict (no strings, no booleans) and finite; unknown fields are errors.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import ConfigDict, Field, Strict

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
