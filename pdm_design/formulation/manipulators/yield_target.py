"""Tolerances allocated for a yield target, with the design (docs/optimizer.md section 10).

A manipulators spec whose `[tolerances]` has a `yield_target` and quantities marked
`allocate = true`, and whose `[objective]` does not ask for the worst-case box
(`max_offset_tolerance`), asks `optimize` for the design and the largest common scale s of the
allocated tolerances (t_q = s * w_min / w_q: tolerances.model.allocation_shares) at which the
row's linearised yield (formulation/manipulators/statistical.py: the union bound 1 - sum_i
Phi(-beta_i)) reaches the target. One NLP:

    maximise  log s
    subject to  the design's nominal rows (every condition at zero tolerance, as for any spec)
                -log10(sum_i Phi(-beta_i(x, s))) >= -log10(1 - target)      (the nines row)

s an auxiliary variable (`yield_scale`), the allocated quantities' sigmas s times their shares
(given tolerances at their values). The nines row is well scaled (2.57 for 99.73 %) where the
yield itself is within 3e-3 of 1; log s makes the objective free of the units s is in (a
length, an angle, a mass: whichever quantity has the smallest weight).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

AUX = "yield_scale"
SCALE_BOUNDS = (1e-9, 1e3)  # s within these (SI units of the smallest-weight quantity)
START_GRID = 49  # scales tried at the spec's guess for the start of s (evenly in log s)
CONDITION = "yield_target"  # the nines row's name (a validity row: no margin, no requirement)


def active(spec) -> bool:
    """Whether `optimize(spec)` allocates tolerances for a yield target (module docstring)."""
    tolerances = getattr(spec, "tolerances", ())
    return (spec.kind == "manipulators"
            and getattr(tolerances, "yield_target", None) is not None
            and any(t.allocate for t in tolerances)
            and not float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0)


def check(spec) -> None:
    """Refuse (SpecError, exit 2) what the linearised yield cannot size: another objective
    (the scale is the objective), a quantity it does not model, links or pivot friction."""
    from ...errors import SpecError
    from .statistical import LOTS, PARTS

    source = spec.source or "<spec>"
    for name, weight in spec.objective.items():
        if float(weight) > 0.0:
            raise SpecError(source, f"objective.{name}", "no objective with "
                            "tolerances.yield_target and allocated tolerances (the optimizer "
                            "maximises the allocated tolerances' scale at the target; "
                            "max_offset_tolerance asks for the worst-case box instead)",
                            found=f"{name} = {weight:g}")
    for tol in spec.tolerances:
        if tol.quantity not in PARTS and tol.quantity not in LOTS:
            key = "allocate" if tol.allocate else "value"
            raise SpecError(source, f"tolerances.{tol.quantity}.{key}", "a quantity the "
                            "linearised yield models with tolerances.yield_target: "
                            + ", ".join(PARTS + LOTS[:5]), found=tol.quantity)
    if not spec.scene.plain_mechanism:
        raise SpecError(source, "tolerances.yield_target", "the paper's device (massless links, "
                        "frictionless pivots): the linearised yield does not model links or "
                        "pivot friction", found="scene.links or scene.pivots")


def needed_nines(target: float) -> float:
    """-log10(1 - target): 2.57 for 99.73 %."""
    return -math.log10(1.0 - target)


@dataclass(frozen=True)
class TargetRows:
    """What the yield target adds to the NLP: the scale variable, its bounds and start, the
    nines row and the objective term (log s, maximised)."""

    scale: object
    bounds: tuple[float, float]
    start: float
    condition: object
    objective: object


def target_rows(spec, values: dict, symbols: dict, bounds: dict) -> TargetRows:
    """The yield target's variable, row and objective on the design `values` (SX where free)."""
    import casadi as ca

    from ..common import VALIDITY, Condition
    from .statistical import Chain, design_vector, failure_bound, reliability

    check(spec)
    s = ca.SX.sym(AUX)
    target = spec.tolerances.yield_target
    each, lot = scaled_sigmas(spec.tolerances, s)
    g, sd, names = reliability(Chain(spec.scene), design_vector(values),
                               spec.verification.stages, each, lot)
    # not statistical.nines: its floor hides a NaN (a spread the closed forms cannot follow)
    # as 300 nines; here a NaN stays one, and IPOPT steps back from it
    nines = -ca.log10(failure_bound(g, sd, names) + 1e-300)
    need = needed_nines(target)
    row = Condition((CONDITION,), f"linearised yield >= {target:g}", nines - need, need,
                    kind=VALIDITY)
    xd = ca.vertcat(*symbols.values()) if symbols else ca.SX(0, 1)
    guess = [bounds[n][2] for n in symbols]
    start = start_scale(ca.Function("nines", [xd, s], [nines]), guess, need)
    return TargetRows(s, SCALE_BOUNDS, start, row, ca.log(s))


def scaled_sigmas(tolerances, s):
    """statistical.sigmas with every allocated tolerance at s times its share (w_min / w) and
    the given ones at their values: (part sigmas, lot sigmas), SX where s is."""
    from ...tolerances.model import allocation_shares
    from .statistical import sigmas

    shares = allocation_shares(tolerances)
    given = sigmas([t for t in tolerances if not t.allocate])
    unit = sigmas([replace(t, value=shares[t.quantity]) for t in tolerances if t.allocate], s)
    return tuple([a + b for a, b in zip(x, y)] for x, y in zip(given, unit))


def start_scale(nines, guess, need: float) -> float:
    """The start of s: the largest of START_GRID scales (evenly in log s over SCALE_BOUNDS)
    whose nines at the spec's guess meet the target, refined once on a grid up to the next
    (the smallest scale when none meets it: IPOPT starts from infeasible there)."""
    import numpy as np

    lo, hi = SCALE_BOUNDS
    for _ in range(2):
        grid = np.geomspace(lo, hi, START_GRID)
        xs = np.tile(np.asarray(guess, dtype=float).reshape(-1, 1), (1, START_GRID))
        values = np.asarray(nines.map(START_GRID)(xs, grid[None, :])).ravel()
        meets = np.flatnonzero(values >= need)  # NaN: not met
        if not meets.size:
            return float(lo)
        last = int(meets[-1])
        if last + 1 == START_GRID:
            return float(grid[last])
        lo, hi = grid[last], grid[last + 1]
    return float(lo)
