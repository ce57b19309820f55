"""The spoke count, an integer design variable: the counts a spec asks for, and the spec with one
of them fixed (imports nothing heavy: the search objectives and the scene object use it)."""

from __future__ import annotations

import dataclasses
import math

from ...errors import SpecError
from ...spec.model import Bounds


def spoke_counts(spec) -> list[int]:
    """The spoke counts a spec asks for: its fixed count, or every integer in its bounds."""
    entry = spec.design["spokes"]
    if isinstance(entry, Bounds):
        low, high = math.ceil(entry.min - 1e-9), math.floor(entry.max + 1e-9)
        counts = [n for n in range(max(low, 3), high + 1)]
        if not counts:
            raise SpecError(spec.source or "<spec>", "design.spokes",
                            "an integer range holding a count >= 3",
                            found=f"[{entry.min:g}, {entry.max:g}]")
        return counts
    return [int(entry)]


def with_spokes(spec, count: int):
    """The spec with its spoke count fixed to `count`."""
    return dataclasses.replace(spec, design={**spec.design, "spokes": int(count)})
