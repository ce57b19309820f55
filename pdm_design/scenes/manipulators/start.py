"""Where palm 1's top surface can stand against the object's start (manipulators).

Palm 1 rests at -alpha, so its top surface is at y = first_pivot_y + link_length cos(alpha)
(docs/spec.md, section 1). An object that starts below it for every design the bounds allow
cannot land on palm 1 whatever is chosen: the loader refuses such a spec (bad input, naming
initial.position[1] and the height of the palm). When only some designs put palm 1 below the
start, the spec is valid, and an infeasible answer says where the start and the palm are
(`start_words`).
"""

from __future__ import annotations

import math

from ...spec.model import Bounds

DEFAULT_PIVOT_Y = 0.0  # design.first_pivot_y left out


def _range(value) -> tuple[float, float]:
    if isinstance(value, Bounds):
        return value.min, value.max
    return float(value), float(value)


def palm_top(design: dict) -> float:
    """y of palm 1's top-surface centre at a design point (variables by their spec names)."""
    return (float(design.get("first_pivot_y", DEFAULT_PIVOT_Y))
            + design["link_length"] * math.cos(design["alpha"]))


def lowest_palm_top(design: dict) -> tuple[float, dict[str, float]]:
    """The lowest y of palm 1's top surface over the design's bounds (fixed values as they are),
    and the design values that put it there: the lowest pivot, the shortest link and the
    largest alpha (cos is decreasing on [0, pi/2), where alpha lies)."""
    pivot = _range(design.get("first_pivot_y", DEFAULT_PIVOT_Y))[0]
    link = _range(design["link_length"])[0]
    alpha = _range(design["alpha"])[1]
    where = {"first_pivot_y": pivot, "link_length": link, "alpha": alpha}
    return palm_top(where), where


def unreachable_start(start_y: float, design: dict) -> tuple[str, str, str] | None:
    """(key, expected, found) when the object starts below palm 1's top surface for every design
    in the bounds, else None."""
    low, where = lowest_palm_top(design)
    if start_y >= low:
        return None
    free = [n for n in ("alpha", "link_length", "first_pivot_y")
            if isinstance(design.get(n), Bounds)]
    at = (f"at its lowest in the design's bounds ({', '.join(f'{n} = {where[n]:g}' for n in free)})"
          if free else "for this design")
    expected = (f"a start above palm 1's top surface, which is at y = first_pivot_y + "
                f"link_length cos(alpha) = {low:.6g} m {at}")
    return "initial.position[1]", expected, (
        f"{start_y:g} m, {low - start_y:.4g} m below it (`pdm-design init manipulators` writes "
        "a spec whose start lands on palm 1's centre)")


def start_words(start_y: float, design_spec: dict, point: dict) -> str | None:
    """The status in words when the object starts below palm 1 at the design `point` (the
    least-violation design of a spec with free variables), else None."""
    top = palm_top(point)
    if start_y >= top:
        return None
    low, _ = lowest_palm_top(design_spec)
    return (f"The object starts at y = {start_y:.6g} m, below palm 1's top surface at "
            f"y = {top:.6g} m (first_pivot_y + link_length cos(alpha)) in the least-violation "
            f"design. The bounds allow palm 1 as low as y = {low:.6g} m, but no design that low "
            "meets every requirement: raise the start, widen the bounds, or relax the "
            "requirements listed as violated.")
