"""Tolerances allocated for a yield target, with the design, on a row of manipulators
(docs/optimizer.md section 10; the NLP's shape: formulation/yield_target.py).

The nines row is the row's linearised yield (formulation/manipulators/statistical.py: the
union bound 1 - sum_i Phi(-beta_i)), -log10(sum_i Phi(-beta_i(x, s))).
"""

from __future__ import annotations

from ....formulation.yield_target import (  # noqa: F401 (the names callers read here)
    AUX,
    CONDITION,
    SCALE_BOUNDS,
    START_GRID,
    TargetRows,
    active,
    needed_nines,
    refuse_objectives,
    start_scale,
)


def check(spec) -> None:
    """Refuse (SpecError, exit 2) what the linearised yield cannot size: another objective
    (the scale is the objective), a quantity it does not model, links or pivot friction."""
    from ....errors import SpecError
    from .statistical import LOTS, PARTS

    source = spec.source or "<spec>"
    refuse_objectives(spec)
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


def target_rows(spec, values: dict, symbols: dict, bounds: dict) -> TargetRows:
    """The yield target's variable, row and objective on the design `values` (SX where free)."""
    import casadi as ca

    from ....formulation import yield_target
    from .statistical import union_bound

    check(spec)

    def nines_of(s):
        each, lot = scaled_sigmas(spec.tolerances, s)
        bound = union_bound(spec.scene, values, spec.verification.stages, each, lot)
        # not statistical.nines: its floor hides a NaN (a spread the closed forms cannot
        # follow) as 300 nines; here a NaN stays one, and IPOPT steps back from it
        return -ca.log10(bound + 1e-300)

    return yield_target.target_rows(spec, symbols, bounds, nines_of)


def scaled_sigmas(tolerances, s):
    """statistical.sigmas with every allocated tolerance at s times its share (w_min / w) and
    the given ones at their values: (part sigmas, lot sigmas), SX where s is."""
    from ....formulation import yield_target
    from .statistical import sigmas

    return yield_target.scaled_sigmas(tolerances, s, sigmas)
