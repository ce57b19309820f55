"""The scene and the design: frozen dataclasses that validate themselves (pydantic), as every
pdm-design scene's are; the spec loader turns their errors into the spec's key paths."""

from __future__ import annotations

from pydantic.dataclasses import dataclass

from pdm_design.scenes.common import (
    CONFIG,
    STANDARD_GRAVITY,
    Fraction,
    Positive,
    PositiveQuarterTurn,
)


@dataclass(frozen=True, config=CONFIG)
class Puck:
    """The puck: its mass (kg) and its coefficient of restitution against a bob."""

    mass: Positive = 1.0
    restitution: Fraction = 0.5


@dataclass(frozen=True, config=CONFIG)
class PendulumInitial:
    """The puck's speed (m/s) as it reaches the first bob, moving along the row."""

    speed: Positive


@dataclass(frozen=True, config=CONFIG)
class PendulumRowScene:
    """What the designer does not choose: the puck, the ramps' slope (rad), gravity."""

    initial: PendulumInitial
    puck: Puck = Puck()
    ramp_angle: PositiveQuarterTurn = 0.3
    gravity: Positive = STANDARD_GRAVITY

    kind = "pendulum_row"


@dataclass(frozen=True, config=CONFIG)
class PendulumRowDesign:
    """One design: every bob's mass (kg), the drop of every ramp (m), every rod's length (m)."""

    bob_mass: Positive
    drop: Positive
    rod_length: Positive

    VARIABLES = ("bob_mass", "drop", "rod_length")
