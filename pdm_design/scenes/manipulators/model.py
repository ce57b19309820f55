"""The manipulators scene: an object passed along a row of passive parallelogram manipulators."""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import Field, Strict
from pydantic.dataclasses import dataclass

from ..common import (
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
class Links:
    """The parallelogram's links (docs/physics.md, section 2.1): mass of each link (kg), its
    moment of inertia about its pivot (kg m^2; None: a uniform rod of the link length l,
    mass l^2 / 3) and how many links move with the palm. Each link's centre of mass is at
    half its length (a link symmetric end to end). mass = 0: massless links (the paper's)."""

    mass: NonNegative = 0.0
    inertia: NonNegative | None = None
    count: Annotated[int, Strict(), Field(ge=1, le=1000)] = 2


@dataclass(frozen=True, config=CONFIG)
class Pivots:
    """The joints of a manipulator, all together: a Coulomb friction torque (N m, opposing the
    swing) and a viscous damping coefficient (N m s / rad). Zero: frictionless (the paper's)."""

    friction_torque: NonNegative = 0.0
    damping: NonNegative = 0.0


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
    links: Links = Links()
    pivots: Pivots = Pivots()

    kind = "manipulators"

    def mechanism(self, link_mass=None, friction_torque=None, length_scale=None) -> dict:
        """Keyword arguments of physics.manipulators.carry_terms and palm_terms: the links' and
        the pivots' totals (all links together).

        One manipulator as built: link_mass (kg, each of its links), friction_torque (N m,
        its joints together) and length_scale (its link length over the design's; None: 1) in
        place of the scene's; floats or numpy arrays. A given link inertia scales as the link does
        (same shape): I mass / links.mass (length_scale)^2 (a uniform rod's m l^2 / 3 does)."""
        links = self.links
        mass = links.mass if link_mass is None else link_mass
        inertia = links.inertia
        if inertia is not None and link_mass is not None and links.mass > 0.0:
            inertia = inertia * (mass / links.mass)
        if inertia is not None and length_scale is not None:
            inertia = inertia * length_scale * length_scale
        torque = self.pivots.friction_torque if friction_torque is None else friction_torque
        return {"link_mass": links.count * mass,
                "link_inertia": None if inertia is None else links.count * inertia,
                "friction_torque": torque}

    @property
    def plain_mechanism(self) -> bool:
        """Massless links and frictionless, undamped pivots: the paper's device."""
        return (self.links.mass == 0.0 and not self.links.inertia
                and self.pivots.friction_torque == 0.0 and self.pivots.damping == 0.0)


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


@dataclass(frozen=True, config=CONFIG)
class ManipulatorOffset:
    """Assembly offset of one stage's pivot (the stage numbered from 1), in m, y up: the items
    of `[verification] offsets`."""

    manipulator: Annotated[int, Strict(), Field(ge=1)]
    dx: Number = 0.0
    dy: Number = 0.0
