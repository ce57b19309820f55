"""SI units to the workshop's, one table for every layer: the tolerance quantities' build units
(tolerance_model), the build sheet and the report (sheet.parts.workshop_value)."""

from __future__ import annotations

import math

# SI unit -> (the workshop's unit, the factor from SI to it); other units are shown as they are
WORKSHOP = {
    "m": ("mm", 1e3),
    "m/s": ("mm/s", 1e3),
    "rad": ("deg", 180.0 / math.pi),
    "kg": ("g", 1e3),
    "N m": ("N mm", 1e3),
}


def workshop(value: float, unit: str) -> tuple[float, str]:
    """(value, unit) in the workshop's units: m -> mm, m/s -> mm/s, rad -> degrees, kg -> g,
    N m -> N mm; others as given."""
    to, factor = WORKSHOP.get(unit, (unit, 1.0))
    return value * factor, to


def counted(count: int, noun: str) -> str:
    """'1 build', '2 builds', '0 builds': a count with its noun, plural unless it is 1."""
    return f"{count} {noun}" if count == 1 else f"{count} {noun}s"
