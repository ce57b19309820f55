"""Whether the design's bounds leave any periodic handover (manipulators).

A periodic handover needs beta > alpha (docs/spec.md, docs/physics.md: the carry must descend).
When the largest beta the spec allows is no larger than the smallest alpha, no design the
optimizer may choose has one: the spec contradicts itself (bad input, naming both keys). A
design fixed whole is evaluated instead: its answer says it gains no height (exit 1).
"""

from __future__ import annotations

from ...spec.model import Bounds


def _end(design: dict, name: str, end: str) -> tuple[float, str]:
    """(the value, its key) of `name`'s `end` ("min" or "max") over the bounds."""
    value = design[name]
    if isinstance(value, Bounds):
        return float(getattr(value, end)), f"design.{name}.{end}"
    return float(value), f"design.{name}"


def no_handover(design: dict) -> tuple[str, str, str] | None:
    """(key, expected, found) when some variable is free but beta <= alpha for every design in
    the bounds, else None."""
    if not any(isinstance(v, Bounds) for v in design.values()):
        return None
    alpha, alpha_key = _end(design, "alpha", "min")
    beta, beta_key = _end(design, "beta", "max")
    if beta > alpha:
        return None
    return (f"{alpha_key} and {beta_key}",
            "a handover angle beta above the back-stop angle alpha for some design the "
            "optimizer may choose (a periodic handover needs beta > alpha)",
            f"{alpha_key} = {alpha:g} rad >= {beta_key} = {beta:g} rad")
