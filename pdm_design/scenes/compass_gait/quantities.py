"""The quantities of a compass-gait walker and its ground that a `[tolerances]` table may
tolerance: every step's ground (its slope; on stairs its rise) and the start state."""

from __future__ import annotations

from ...tolerance_model import EACH_OR_LOT, LOT, Quantity, quantity

START = ("start_stance", "start_swing", "start_stance_rate", "start_swing_rate")

QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    quantity("slope", "rad", EACH_OR_LOT, "every step's own slope (on stairs: its tread's tilt)"),
    quantity("rise", "m", EACH_OR_LOT, "a stair's rise"),
    quantity("start_stance", "rad", LOT, "the stance leg's angle just after the first strike"),
    quantity("start_swing", "rad", LOT, "the swing leg's angle just after the first strike"),
    quantity("start_stance_rate", "rad/s", LOT, "the stance leg's rate just after the first "
             "strike"),
    quantity("start_swing_rate", "rad/s", LOT, "the swing leg's rate just after the first "
             "strike"),
)}


def tolerance_refusal(spec, name: str):
    """A rise tolerance on a ramp: the ramp has no rise (key, expected, found)."""
    if name == "rise" and spec.design_at().slope is not None:
        return (f"tolerances.{name}", "a rise tolerance on stairs (design.rise and "
                "design.tread): a ramp has no rise; tolerance its slope", "a ramp (design.slope)")
    return None
