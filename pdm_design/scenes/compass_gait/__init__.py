"""The compass-gait scene: a passive two-legged walker on a ramp (docs/compass_gait.md)."""

from .scene import CompassGaitDesign, CompassGaitInitial, CompassGaitScene, Walker

__all__ = ["CompassGaitDesign", "CompassGaitInitial", "CompassGaitScene", "Walker"]
