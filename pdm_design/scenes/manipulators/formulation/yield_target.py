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
    TargetRows,
    active,
    needed_nines,
    refuse_objectives,
)


def check(spec) -> None:
    """Refuse (SpecError, exit 2) what the linearised yield cannot size: another objective
    (the scale is the objective), a quantity it does not model, damped pivots."""
    from ....errors import SpecError

    refuse_objectives(spec)
    modelled_quantities(spec, "tolerances.yield_target")
    if spec.scene.pivots.damping != 0.0:
        raise SpecError(spec.source or "<spec>", "tolerances.yield_target", "undamped pivots "
                        "(the linearised yield takes the closed-form carry, which damping has "
                        "not)", found=f"scene.pivots.damping = {spec.scene.pivots.damping!r}")


def modelled_quantities(spec, what) -> None:
    """Refuse (SpecError, exit 2) a toleranced quantity the linearised yield does not model
    (a link's mass, a pivot's friction: the yield map and `pdm-design yield` do), for `what`
    (tolerances.yield_target or objective.max_yield)."""
    from ....errors import SpecError
    from .statistical import LOTS, PARTS

    for tol in spec.tolerances:
        if tol.quantity not in PARTS and tol.quantity not in LOTS:
            key = "allocate" if tol.allocate else "value"
            raise SpecError(spec.source or "<spec>", f"tolerances.{tol.quantity}.{key}",
                            f"a quantity the linearised yield models with {what}: "
                            + ", ".join(PARTS + LOTS[:5]), found=tol.quantity)


def target_rows(spec, values: dict, symbols: dict, bounds: dict) -> TargetRows:
    """The yield target's variable, row and objective on the design `values` (SX where free)."""

    from ....formulation import yield_target
    from ....formulation.chain_moments import union_nines
    from .statistical import union_bound

    check(spec)

    def nines_of(s):
        each, lot = scaled_sigmas(spec.tolerances, s)
        # in logarithms (finite derivatives far inside, where the bound itself is 0), and
        # a NaN (a spread the closed forms cannot follow) stays one: IPOPT steps back from it
        return union_bound(spec.scene, values, spec.verification.stages, each, lot,
                           reduce=union_nines)

    return yield_target.target_rows(spec, symbols, bounds, nines_of)


def scaled_sigmas(tolerances, s):
    """statistical.sigmas with every allocated tolerance at s times its share (w_min / w) and
    the given ones at their values: (part sigmas, lot sigmas), SX where s is."""
    from ....formulation import yield_target
    from .statistical import sigmas

    return yield_target.scaled_sigmas(tolerances, s, sigmas)
