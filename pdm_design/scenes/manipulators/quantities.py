"""The quantities of a row of manipulators that a `[tolerances]` table may tolerance."""

from __future__ import annotations

from ...tolerance_model import EACH_OR_LOT, LOT, Quantity, quantity

QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    quantity("pivot_x", "m", EACH_OR_LOT, "a pivot's place along the row"),
    quantity("pivot_y", "m", EACH_OR_LOT, "a pivot's height (up)"),
    quantity("link_length", "m", EACH_OR_LOT, "a manipulator's link length"),
    quantity("back_stop", "rad", EACH_OR_LOT,
       "a back stop's angle alpha (the palm rests at -alpha)"),
    quantity("palm_mass", "kg", EACH_OR_LOT, "a palm's mass"),
    quantity("friction", "1", LOT, "the object-palm friction coefficient"),
    quantity("object_mass", "kg", LOT, "the object's mass"),
    quantity("object_width", "m", LOT, "the object's width along the row"),
    quantity("feed_x", "m", LOT, "where the object starts along the row"),
    quantity("feed_speed", "m/s", LOT,
       "the object's initial speed (along its initial velocity; +x if that is 0)"),
    quantity("link_mass", "kg", EACH_OR_LOT,
       "the mass of each of a manipulator's links (nominal: [scene.links] mass)"),
    quantity("pivot_friction", "N m", EACH_OR_LOT,
       "a manipulator's Coulomb pivot friction torque, its joints together (nominal: "
       "[scene.pivots] friction_torque)"),
)}
