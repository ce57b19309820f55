"""The rimless wheel: spokes on a hub rolling down a ramp or stairs, a walker the ground moves.

Modules: `model` (the scene and the design), `physics` (closed forms for floats, numpy arrays
and CasADi symbols), `analysis` (the closed-form analysis of a fixed design), `sim` (the event
simulator and the vectorised step map), `rough` (steps before failure on rough ground: Monte
Carlo and the Markov chain's mean first-passage time), `formulation` (the NLP rows),
`template` (a spec to start from), and for the build sheet and the report `sheet`, `drawing`,
`dxf`, `plot` and `animation`. The derivations are in docs/rimless_wheel.md.
"""

from .model import (
    GROUNDS,
    RimlessWheelDesign,
    RimlessWheelInitial,
    RimlessWheelScene,
    Wheel,
    check_ground,
)

KIND = "rimless_wheel"
MARGINS = ("over_the_top", "no_flight", "no_slip", "impact_friction", "landing",
           "nose_clearance")

__all__ = ["GROUNDS", "KIND", "MARGINS", "RimlessWheelDesign", "RimlessWheelInitial",
           "RimlessWheelScene", "Wheel", "check_ground"]
