"""The hybrid-simulation vocabulary shared by every scene: accuracy, events, outcomes.

A run is a sequence of phases. Each phase has its dynamics (closed form where the physics
allows, numerical integration otherwise), guard functions with a crossing direction, and a
reset map applied at the event that ends it. Every event goes into one log.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from scipy.optimize import brentq

_BRENT_RTOL = 4 * 2.220446049250313e-16  # brentq's smallest accepted rtol: 4 machine epsilons


@dataclass(frozen=True)
class Accuracy:
    """Tolerances of a simulation run.

    rtol, atol: integration tolerances where a phase is integrated numerically.
    event_tol: absolute tolerance on the located event time (s) and angle (rad).
    """

    name: str
    rtol: float
    atol: float
    event_tol: float


ACCURACY_PRESETS = {
    "fast": Accuracy("fast", rtol=1e-6, atol=1e-8, event_tol=1e-7),
    "default": Accuracy("default", rtol=1e-9, atol=1e-11, event_tol=1e-11),
    "precise": Accuracy("precise", rtol=1e-12, atol=1e-14, event_tol=1e-14),
}


def accuracy(preset: str | Accuracy = "default") -> Accuracy:
    """An Accuracy from a preset name (or an Accuracy passed through)."""
    if isinstance(preset, Accuracy):
        return preset
    try:
        return ACCURACY_PRESETS[preset]
    except KeyError:
        raise ValueError(f"accuracy must be one of {', '.join(ACCURACY_PRESETS)}, "
                         f"not {preset!r}") from None


@dataclass(frozen=True)
class Event:
    """One event of a run. stage numbers the manipulator carrying the object (from 1) or the
    step the ball is over (from 1). before/after: the state just before and after the reset,
    by name (SI units). A failure event ends the run."""

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
        }


def locate(fun, a: float, b: float, tol: float) -> float:
    """Root of a guard that changes sign on [a, b], to absolute tolerance tol (Brent's method)."""
    return brentq(fun, a, b, xtol=tol, rtol=_BRENT_RTOL, maxiter=200)
