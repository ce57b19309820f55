"""What a worst-case allocation of a rimless wheel's tolerances needs that a spec lacks, in
words (Scene.allocation_refusal; formulation/allocation.py)."""

from __future__ import annotations

from ...spec.model import Bounds

OTHER_GROUND = {"ramp": ("rise", "tread"), "stairs": ("slope",)}


def allocation_refusal(spec):
    """(key, expected, found) of the first thing refused, or None: a quantity of the other
    ground; a hub mass allocated where no mass changes the motion (its box is unbounded); a
    given mass or start speed tolerance that takes the value to 0; spokes of their own lengths
    with fewer verification steps than spokes."""
    from .counts import spoke_counts
    from .spread import mass_moves_nothing

    scene = spec.scene
    for tol in spec.tolerances:
        key = f"tolerances.{tol.quantity}"
        if tol.quantity in OTHER_GROUND[scene.ground]:
            return (key, f"a quantity of a {scene.ground}", tol.quantity)
        if tol.quantity == "mass" and tol.allocate:
            leg = spec.design.get("leg_length")
            fixed = not isinstance(leg, Bounds)
            w = scene.wheel
            if w.spoke_mass == 0.0 or (fixed and mass_moves_nothing(w, float(leg))):
                return (f"{key}.allocate", "a quantity the wheel's motion depends on: with "
                        "no spoke mass (or a hub gyration^2 = leg_length^2 / 3) k^2 is the "
                        "same at every hub mass, so no hub mass changes the motion and its box "
                        "(a yield target's scale) is unbounded (give mass a value or leave it "
                        "out)",
                        f"spoke_mass = {w.spoke_mass:g}, gyration = {w.gyration:g}")
        own = {"mass": scene.wheel.mass, "start_speed": scene.initial.speed}
        if tol.quantity in own and not tol.allocate and tol.value >= own[tol.quantity]:
            return (f"{key}.value", f"below {own[tol.quantity]:g} (the value it is a "
                    "tolerance of)", f"{tol.value:g}")
        if (tol.quantity == "leg_length" and tol.applies_to == "each"
                and spec.verification.stages < max(spoke_counts(spec))):
            return ("verification.stages", f"an integer >= {max(spoke_counts(spec))} (the "
                    "box's builds draw one leg length a spoke from the steps' draws)",
                    str(spec.verification.stages))
    return None
