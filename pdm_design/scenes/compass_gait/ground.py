"""A design's ground and walker numbers, as the step map and the simulator take them."""

from __future__ import annotations

from . import physics as phys
from .stepmap import Ground


def params_for(scene, design) -> phys.Params:
    """The closed forms' numbers of the scene's walker with the design's parameters."""
    return phys.params_of(design.walker(scene), scene.gravity)


def ground_of(design, params: phys.Params, slope_error: float = 0.0,
              rise_error: float = 0.0) -> Ground:
    """The ground of one step: the design's ramp (its slope plus slope_error) or stairs (the
    tread tilted by slope_error, the rise plus rise_error, m)."""
    if design.slope is not None:
        return Ground(float(design.slope) + slope_error, 0.0)
    return Ground(slope_error, (float(design.rise) + rise_error) / params.l)
