"""The hybrid-simulation vocabulary shared by every scene: accuracy, events, outcomes.

A run is a sequence of phases. Each phase has its dynamics (closed form where the physics
allows, numerical integration otherwise), guard functions with a crossing direction, and a
reset map applied at the event that ends it. Every event goes into one log.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from ..errors import PdmError
from .numerics import BRENT_RTOL, brentq

# A length, speed or ratio more than SCALE_LIMIT times the scene's own scale (the link length,
# sqrt(g l), 1, ...) is refused: double precision cannot follow a motion spread over more
# orders of magnitude than that (on a 1e13 m flight a 1 m palm is below rounding). Quantities
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
class Accuracy:
    """Tolerances of a simulation run and of its verification.

    rtol, atol: integration tolerances where a phase is integrated numerically (the sliding
        carry and the bouncing phase of the manipulators scene; every other phase is closed form).
    event_tol: absolute tolerance on a located event (s for times, rad for angles, m for the
        stairs' nose contacts).
    agreement: relative difference between simulated and closed-form periodic quantities that
        verification accepts (verify.verify_nominal). The presets' values are 10x or more above
        the errors measured by results/bench_accuracy.py (results/accuracy.md).
    """

    name: str
    rtol: float
    atol: float
    event_tol: float
    agreement: float = 1e-7

    def __post_init__(self):
        for key in ("rtol", "atol", "event_tol", "agreement"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value) or value <= 0.0:
                raise ValueError(f"accuracy {key} must be a positive finite number, "
                                 f"not {value!r}")
        if self.rtol < MIN_RTOL:
            raise ValueError(f"accuracy rtol must be at least {MIN_RTOL:g} (100 machine "
                             f"epsilons, the integrator's floor), not {self.rtol:g}")
        if self.rtol >= 1.0 or self.agreement >= 1.0:
            raise ValueError("accuracy rtol and agreement must be below 1 (they are relative)")


MIN_RTOL = 100 * 2.220446049250313e-16

ACCURACY_PRESETS = {
    "fast": Accuracy("fast", rtol=1e-6, atol=1e-8, event_tol=1e-7, agreement=1e-4),
    "default": Accuracy("default", rtol=1e-9, atol=1e-11, event_tol=1e-11, agreement=1e-7),
    "precise": Accuracy("precise", rtol=1e-12, atol=1e-14, event_tol=1e-14, agreement=1e-9),
}
TOLERANCE_KEYS = ("rtol", "atol", "event_tol", "agreement")


def accuracy(preset: str | Accuracy | Mapping = "default") -> Accuracy:
    """An Accuracy from a preset name, an Accuracy (passed through), or a mapping of tolerances
    for those who want them: {"base": "default", "rtol": 1e-10, ...}; keys left out come from
    the base preset (default "default"), and the result is named "custom". ValueError names
    the offending key."""
    if isinstance(preset, Accuracy):
        return preset
    if isinstance(preset, Mapping):
        values = dict(preset)
        base = accuracy(values.pop("base", "default"))
        unknown = sorted(set(values) - set(TOLERANCE_KEYS), key=str)
        if unknown:
            raise ValueError(f"unknown accuracy key {unknown[0]!r}: the tolerances are "
                             f"{', '.join(TOLERANCE_KEYS)} (and base, a preset name)")
        merged = {k: values.get(k, getattr(base, k)) for k in TOLERANCE_KEYS}
        return Accuracy("custom", **merged)
    try:
        return ACCURACY_PRESETS[preset]
    except (KeyError, TypeError):
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
    """Root of a guard that changes sign on [a, b], to absolute tolerance tol (Brent's method;
    numerics.brentq, the same iteration as scipy.optimize.brentq without its import cost)."""
    return brentq(fun, a, b, xtol=tol, rtol=BRENT_RTOL, maxiter=200)
