"""Typed, self-validating building blocks shared by the scenes.

Scenes are frozen pydantic dataclasses: constructing one validates it, whether from a spec file
or from Python. Numbers are strict (no strings, no booleans) and finite; unknown fields are errors.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import ConfigDict, Field, Strict

CONFIG = ConfigDict(extra="forbid", allow_inf_nan=False)

Number = Annotated[float, Strict()]
Positive = Annotated[float, Strict(), Field(gt=0)]
NonNegative = Annotated[float, Strict(), Field(ge=0)]
Fraction = Annotated[float, Strict(), Field(ge=0, le=1)]
# Angles of a manipulator measured from the vertical: the palm must stay above its pivot.
QuarterTurn = Annotated[float, Strict(), Field(ge=0, lt=math.pi / 2)]
PositiveQuarterTurn = Annotated[float, Strict(), Field(gt=0, lt=math.pi / 2)]
Point = tuple[Number, Number]

STANDARD_GRAVITY = 9.81
