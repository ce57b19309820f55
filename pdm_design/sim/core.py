"""The hybrid-simulation vocabulary shared by every scene: events, outcomes, scale checks.

A run is a sequence of phases. Each phase has its dynamics (closed form where the physics
allows, numerical integration otherwise), guard functions with a crossing direction, and a
reset map applied at the event that ends it. Every event goes into one log.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..accuracy import Accuracy
from ..errors import PdmError

# A length, speed or ratio more than SCALE_LIMIT times the scene's own scale (the link length,
# sqrt(g l), 1, ...) is refused: double precision cannot follow a motion spread over more
# orders of magnitude than that (on a 1e13 m flight a 1 m part is below rounding). Quantities
# far *below* the scale are harmless (they round to nothing against it) and pass, as do zeros.
# The scales themselves (g, l, h0, masses) must lie within [1/MAGNITUDE_LIMIT, MAGNITUDE_LIMIT]
# and no value beyond MAGNITUDE_LIMIT, so that squares and products of a few stay finite.
SCALE_LIMIT = 1e12
MAGNITUDE_LIMIT = 1e100


class SimulationRefused(PdmError, ValueError):
    """The simulator refuses a degenerate input; the message says what is degenerate and how to
    fix it. (A ValueError for Python callers; the CLI reports it without a traceback.)"""


def check_scales(reference: tuple[str, float], quantities: dict[str, float]) -> None:
    """Refuse (SimulationRefused) a reference scale outside [1/MAGNITUDE_LIMIT, MAGNITUDE_LIMIT],
    and any quantity that is not finite, beyond MAGNITUDE_LIMIT, or more than SCALE_LIMIT times
    the reference scale. reference: (its description, its value)."""
    what, scale = reference
    if not 1.0 / MAGNITUDE_LIMIT <= scale <= MAGNITUDE_LIMIT:  # (also refuses nan)
        raise SimulationRefused(f"{what} = {scale:g} (SI) is outside the range the simulator "
                                f"computes in ({1 / MAGNITUDE_LIMIT:g} to {MAGNITUDE_LIMIT:g})")
    for name, value in quantities.items():
        if not abs(value) <= MAGNITUDE_LIMIT:
            raise SimulationRefused(f"{name} = {value:g} (SI) is beyond the largest value the "
                                    f"simulator computes with ({MAGNITUDE_LIMIT:g})")
    for name, value in quantities.items():
        ratio = abs(value) / scale
        if ratio > SCALE_LIMIT:
            raise SimulationRefused(
                f"{name} = {value:g} is {ratio:.3g} times {what} ({scale:g}): a scene spread "
                f"over more than {math.log10(SCALE_LIMIT):.0f} orders of magnitude cannot be "
                "simulated in double precision; fix the value")


@dataclass(frozen=True)
class Event:
    """One event of a run. stage numbers the stage it happens in (from 1: the part carrying the
    object, the step it lands on); a failure is in the stage that fails, stages passed + 1
    (a scene's state may say more of where it happens). before/after: the state just
    before and after the reset, by name (SI units). A failure event ends the run."""

    time: float
    kind: str
    stage: int
    before: dict[str, float]
    after: dict[str, float]
    detail: str = ""
    failure: bool = False

    def to_json(self) -> dict:
        return {
            "time": self.time, "kind": self.kind, "stage": self.stage,
            "before": self.before, "after": self.after, "detail": self.detail,
            "failure": self.failure,
        }


@dataclass(frozen=True)
class Outcome:
    """completed: every requested stage was passed; failure: the event that ended the run early."""

    completed: bool
    stages_passed: int
    failure: Event | None = None

    def to_json(self) -> dict:
        failure = None
        if self.failure is not None:
            failure = {"event": self.failure.kind, "stage": self.failure.stage,
                       "time": self.failure.time, "detail": self.failure.detail}
        return {"completed": self.completed, "stages_passed": self.stages_passed,
                "failure": failure}


@dataclass(frozen=True)
class SimulationResult:
    """A whole run: its outcome, one record per stage reached, the event log and, when asked
    for, sampled trajectories for plots (name -> list of values, 'time' among them)."""

    scene: str
    outcome: Outcome
    stages: list[dict]
    events: list[Event]
    accuracy: Accuracy
    trajectory: dict[str, list[float]] = field(default_factory=dict)

    def to_json(self) -> dict:
        return {
            "scene": self.scene,
            "outcome": self.outcome.to_json(),
            "stages": self.stages,
            "events": [e.to_json() for e in self.events],
            "accuracy": self.accuracy.name,
            "accuracy_settings": self.accuracy.settings(),
        }
