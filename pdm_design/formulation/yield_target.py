"""Tolerances allocated for a yield target, with the design (docs/optimizer.md section 10):
what every scene's NLP shares.

A spec whose `[tolerances]` has a `yield_target` and quantities marked `allocate = true`, and
whose `[objective]` does not ask for the worst-case box (`max_offset_tolerance`), asks
`optimize` for the design and the largest common scale s of the allocated tolerances
(t_q = s * w_min / w_q: tolerance_model.allocation_shares) at which the scene's linearised
yield reaches the target. One NLP:

    maximise  z = log s
    subject to  the design's nominal rows (every condition at zero tolerance, as for any spec)
                log(nines(x, exp z) / need) >= 0,  need = -log10(1 - target)  (the nines row)

z an auxiliary variable (`yield_scale`: log s, so that IPOPT's steps in it are relative steps
in s, as the yield's own dependence on s is), the allocated quantities' sigmas s times their
shares
(given tolerances at their values), nines the scene's -log10 of its bound on the failure
probability (a union bound, or Hunter's bound: the scene's formulation,
scenes/<kind>/formulation). The nines row is well scaled (2.57 for 99.73 %) where
the yield itself is within 3e-3 of 1; log s makes the objective free of the units s is in (a
length, an angle, a mass: whichever quantity has the smallest weight).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

AUX = "yield_scale"
SCALE_BOUNDS = (1e-9, 1e3)  # s within these (SI units of the smallest-weight quantity)
CONDITION = "yield_target"  # the nines row's name (a validity row: no margin, no requirement)


def active(spec) -> bool:
    """Whether `optimize(spec)` allocates tolerances for a yield target (module docstring)."""
    from ..plugin import of

    tolerances = getattr(spec, "tolerances", ())
    return (of(spec).sizes_for_yield_target
            and getattr(tolerances, "yield_target", None) is not None
            and any(t.allocate for t in tolerances)
            and not float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0)


def refuse_objectives(spec) -> None:
    """Refuse (SpecError, exit 2) another objective: the scale is the objective."""
    from ..errors import SpecError

    for name, weight in spec.objective.items():
        if float(weight) > 0.0:
            raise SpecError(spec.source or "<spec>", f"objective.{name}", "no objective with "
                            "tolerances.yield_target and allocated tolerances (the optimizer "
                            "maximises the allocated tolerances' scale at the target; "
                            "max_offset_tolerance asks for the worst-case box instead)",
                            found=f"{name} = {weight:g}")


def needed_nines(target: float) -> float:
    """-log10(1 - target): 2.57 for 99.73 %."""
    return -math.log10(1.0 - target)


@dataclass(frozen=True)
class TargetRows:
    """What the yield target adds to the NLP: the variable z = log s, its bounds and start,
    the nines row and the objective term (z, maximised)."""

    scale: object  # the variable z = log s
    bounds: tuple[float, float]  # of z
    start: float  # a stand-in: every start's own s is set by solve/screen.at_target_scales
    condition: object
    objective: object


def target_rows(spec, symbols: dict, bounds: dict, nines_of) -> TargetRows:
    """The yield target's variable, row and objective: nines_of(s) the scene's nines (SX in s
    and the free design `symbols`). The start of s in every start point is that design's own
    largest s meeting the target (solve/screen.at_target_scales), not a number fixed here."""
    import casadi as ca

    from .common import VALIDITY, Condition

    z = ca.SX.sym(AUX)  # log s
    target = spec.tolerances.yield_target
    nines = nines_of(ca.exp(z))
    need = needed_nines(target)
    row = Condition((CONDITION,), f"linearised yield >= {target:g}",
                    log_ratio(nines / need), kind=VALIDITY)
    bounds = tuple(math.log(b) for b in SCALE_BOUNDS)
    return TargetRows(z, bounds, bounds[0], row, z)


LOG_FLOOR = 0.5  # of nines / need: below it log_ratio goes on along its tangent there


def log_ratio(r):
    """log r, the nines row (r = nines / need; >= 0 where the target is met): nines fall about
    as s^-2 (a reliability index ~ 1 / s), so their logarithm is about linear in z and IPOPT's
    Newton steps in z about exact. Below LOG_FLOOR it goes on along its tangent, a number for
    any r (nines <= 0 at a scale far too large: a row that does not hold, not a NaN)."""
    import casadi as ca

    tangent = math.log(LOG_FLOOR) + (r - LOG_FLOOR) / LOG_FLOOR
    above = r >= LOG_FLOOR
    return ca.if_else(above, ca.log(ca.if_else(above, r, LOG_FLOOR)), tangent)


def scale_of(z: float) -> float:
    """The scale s of the NLP's variable z = log s."""
    return math.exp(z)


def scaled_sigmas(tolerances, s, sigmas):
    """The scene's `sigmas` (tolerances, scale) -> (part sigmas, lot sigmas) with every
    allocated tolerance at s times its share (w_min / w) and the given ones at their values,
    SX where s is."""
    from ..tolerance_model import allocation_shares

    shares = allocation_shares(tolerances)
    given = sigmas([t for t in tolerances if not t.allocate])
    unit = sigmas([replace(t, value=shares[t.quantity]) for t in tolerances if t.allocate], s)
    return tuple([a + b for a, b in zip(x, y)] for x, y in zip(given, unit))
