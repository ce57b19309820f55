"""The objective max_mfpt: the spoke count and ramp slope that last longest on a rough ramp
(every step's own slope drawn normal with sigma = t / 3, the spec's `[tolerances] slope`),
chosen by rough.longest_lasting and refined on the finer chain (docs/rimless_wheel.md)."""

from __future__ import annotations

from ...errors import SpecError
from ...spec.model import Bounds


def longest_lasting_design(spec) -> tuple[dict, float]:
    """({spokes, slope}, the mean steps before failure) of the longest-lasting wheel."""
    from .counts import spoke_counts
    from .rough import longest_lasting

    scene, design = spec.scene, spec.design
    where = spec.source or "<spec>"
    if scene.ground != "ramp":
        raise SpecError(where, "objective.max_mfpt", "a ramp (scene.ground = \"ramp\")",
                        "stairs")
    slope = [t for t in spec.tolerances if t.quantity == "slope" and t.value is not None]
    if not slope:
        raise SpecError(where, "objective.max_mfpt", "a [tolerances] slope with a value (the "
                        "roughness of the ramp)", "none")
    bounds = design.get("slope")
    if not isinstance(bounds, Bounds) or isinstance(design.get("leg_length"), Bounds):
        raise SpecError(where, "objective.max_mfpt", "a free design.slope and a fixed "
                        "design.leg_length (the search is over the count and the slope)",
                        "another design space")
    found = longest_lasting(scene, spoke_counts(spec), (bounds.min, bounds.max),
                            float(design["leg_length"]), slope[0].value)
    return ({"spokes": int(found["spokes"]), "slope": float(found["slope"])},
            float(found["mfpt"]["estimate"]))
