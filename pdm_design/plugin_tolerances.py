"""What the scene interface's tolerance, yield and verification methods return, and the
small helpers their implementations share (pdm_design.plugin.Scene, section "tolerances,
yield, verification"). Imports nothing heavy."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class BoxAxes:
    """A scene's explicit-offset box.

    axes: the two errors every stage takes, each (its name in the box, the toleranced
    quantity it is): (("dx", "pivot_x"), ("dy", "pivot_y")) for a pivot,
    (("rise", "rise"), ("tread", "tread")) for a step. per_part: the other quantities each part
    holds (a random build draws one value per part; a corner takes them all high or all low).
    alternating: those of per_part whose corners also alternate part by part."""

    axes: tuple[tuple[str, str], ...]  # two (a pivot's, a step's) or one (a ramp's slope)
    per_part: tuple[str, ...] = ()
    alternating: tuple[str, ...] = ()

    @property
    def names(self) -> tuple[str, str]:
        """The two axes' names in the box."""
        return tuple(name for name, _ in self.axes)

    @property
    def quantities(self) -> tuple[str, str]:
        """The two axes' toleranced quantities."""
        return tuple(quantity for _, quantity in self.axes)


@dataclass(frozen=True)
class PlacedRows:
    """The rows of a linearised yield, each placed along the run.

    g, sd: each row's mean margin and its standard deviation (arrays); names: each row's
    condition; weight: each row's weight in the union bound (1, or 0 for a row not counted);
    place: each row's place along the run (an integer array); word: (a place's noun, its
    plural, place 0's own name or None): ("step", "steps", None)."""

    g: object
    sd: object
    names: tuple[str, ...]
    weight: object
    place: object
    word: tuple[str, str, str | None]


def relative_agreement(quantity: str, predicted, simulated) -> dict | None:
    """Scene.closed_form_agreement of two lists of a stage quantity, stage by stage: the
    largest |simulated - predicted| / predicted over the stages both have; None when either
    is empty."""
    if not simulated or not predicted:
        return None
    errors = [abs(s - p) / p for s, p in zip(simulated, predicted)]
    return {"quantity": quantity, "relative_error": max(errors), "compared": len(errors)}
