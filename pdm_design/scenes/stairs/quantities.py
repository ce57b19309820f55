"""The quantities of a flight of stairs that a `[tolerances]` table may tolerance."""

from __future__ import annotations

from ...tolerance_model import EACH_OR_LOT, LOT, Quantity, quantity

QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    quantity("rise", "m", EACH_OR_LOT, "a step's rise"),
    quantity("tread", "m", EACH_OR_LOT, "a step's tread"),
    quantity("restitution", "1", LOT, "the ball's coefficient of restitution"),
    quantity("friction", "1", LOT, "the ball-step friction coefficient"),
    quantity("launch_speed", "m/s", LOT, "the launch speed"),
    quantity("launch_x", "m", LOT, "where the ball is launched along the stairs"),
)}
