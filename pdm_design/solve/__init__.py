"""Solve layer: IPOPT multistart on a formulation, elastic diagnosis, cvxpy tolerance regions.

Never imports the simulator."""

from .ipopt import map_status
from .optimize import optimize
from .result import LinearisedTolerance, OptimizeResult, SolverStats, Violation

__all__ = ["LinearisedTolerance", "OptimizeResult", "SolverStats", "Violation", "map_status",
           "optimize"]
