"""What a built staircase's treads are made of, step by step, and how its launcher is set.

Materials vary: each tread may have its own restitution and friction against the ball (a lot of
boards, a coating applied by hand), and the launcher throws at its own speed from its own place.
`BuildVariation` holds those values for one build, checked, for the event simulator; the design
and the scene keep their nominal values (the staircase is built from the design's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ....sim.core import SimulationRefused


@dataclass(frozen=True)
class BuildVariation:
    """restitution[i], friction[i]: of the impact on step i + 1's tread (steps beyond the
    sequence have the design's restitution and the scene's friction); launch_speed: the ball's
    launch speed (None: the design's); launch_x: metres the launch point lies further down the
    stairs than designed."""

    restitution: tuple[float, ...] = ()
    friction: tuple[float, ...] = ()
    launch_speed: float | None = None
    launch_x: float = 0.0

    def restitution_at(self, step: int, nominal: float) -> float:
        return self.restitution[step - 1] if 0 < step <= len(self.restitution) else nominal

    def friction_at(self, step: int, nominal: float) -> float:
        return self.friction[step - 1] if 0 < step <= len(self.friction) else nominal


def build_variation(*, restitution=None, friction=None, launch_speed=None, launch_x=0.0,
                    radius: float = 0.0) -> BuildVariation:
    """Check and hold one build's per-step materials and launch (SimulationRefused, a
    ValueError, naming the step and what was expected). restitution and friction: a sequence
    (step 1's first) or None; every restitution in [0, 1], every friction >= 0, and > 0 only for
    a ball of radius > 0 (a point ball cannot roll)."""
    eps = _values("restitution", restitution)
    mu = _values("friction", friction)
    for step, e in enumerate(eps, start=1):
        if not 0.0 <= e <= 1.0:
            raise SimulationRefused(f"step {step}: restitution {e:g} is not in [0, 1]")
    for step, f in enumerate(mu, start=1):
        if not f >= 0.0:
            raise SimulationRefused(f"step {step}: friction {f:g} is negative")
        if f > 0.0 and radius == 0.0:
            raise SimulationRefused(f"step {step}: friction {f:g} > 0 needs a ball radius > 0 "
                                    "(a point ball cannot roll)")
    if launch_speed is not None and not math.isfinite(launch_speed):
        raise SimulationRefused(f"launch speed {launch_speed} is not a finite number")
    if not math.isfinite(launch_x):
        raise SimulationRefused(f"launch x {launch_x} is not a finite number")
    return BuildVariation(eps, mu, None if launch_speed is None else float(launch_speed),
                          float(launch_x))


def _values(name, values) -> tuple[float, ...]:
    if values is None:
        return ()
    out = tuple(float(v) for v in values)
    for step, v in enumerate(out, start=1):
        if not math.isfinite(v):
            raise SimulationRefused(f"step {step}: {name} {v} is not a finite number")
    return out
