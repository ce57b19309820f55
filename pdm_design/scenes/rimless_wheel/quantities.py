"""The quantities of a rimless wheel and its ground that a `[tolerances]` table may tolerance."""

from __future__ import annotations

from ...tolerance_model import EACH_OR_LOT, LOT, Quantity, quantity

QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    quantity("slope", "rad", EACH_OR_LOT, "every step's own slope (a ramp that is not flat)"),
    quantity("rise", "m", EACH_OR_LOT, "a stair's rise"),
    quantity("tread", "m", EACH_OR_LOT, "a stair's tread"),
    quantity("start_speed", "rad/s", LOT, "the angular speed just after the first impact"),
    quantity("leg_length", "m", EACH_OR_LOT, "each spoke's own length (the steps take the "
             "spokes in turn), or one length for every spoke (lot)"),
    quantity("mass", "kg", LOT, "the hub's mass (with a radius of gyration or spoke masses it "
             "moves k^2: the impact and the stance)"),
)}
