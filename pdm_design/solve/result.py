"""Small frozen result objects of the solve layer."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..status import Status


@dataclass(frozen=True)
class Violation:
    """A condition the elastic diagnosis could not meet."""

    name: str  # margin / condition name (as in the spec's [requirements])
    where: str
    required: float  # required margin (normalised)
    achieved: float  # margin reached at the least-violation design
    text: str  # the whole diagnosis in words
    equality: bool = False

    def to_json(self) -> dict:
        return {"name": self.name, "where": self.where, "required": self.required,
                "achieved": self.achieved, "message": self.text}


@dataclass(frozen=True)
class SolverStats:
    """Solver statistics. Times in seconds."""

    iterations: int  # IPOPT iterations of the run whose answer is reported
    total_iterations: int  # over every IPOPT run (and the elastic runs)
    solve_time: float  # wall time of the reported run
    total_solve_time: float  # over every IPOPT run
    starts: int
    build_time: float  # building the NLP (0 when it came from the cache)
    wall_time: float  # the whole optimize call
    return_statuses: tuple[str, ...] = ()
    # starts solved in stacked runs, several per IPOPT run (0: one run per start); when the
    # reported run is one, iterations and solve_time are that whole run's
    stacked_starts: int = 0
    # iterations of the tie-break run (solve/tiebreak.py; counted in total_iterations): the
    # optimal design nearest the spec's guess (-1: not run); kept: its design is the answer
    tie_break_iterations: int = -1
    tie_break_kept: bool = False

    def to_json(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__} | {
            "return_statuses": list(self.return_statuses)}


@dataclass(frozen=True)
class LinearisedTolerance:
    """Tolerances of the linearised safe set {d : g0 + J d >= 0} at the optimum (cvxpy).

    square: largest half-width of a box with the same width on every coordinate;
    box: largest-area box with one half-width per axis group (e.g. dx, dy);
    ellipsoid: largest-volume ellipsoid centred on the nominal, as its smallest and largest
    semi-axes, the radius of a sphere enclosing the same volume, and its extent along each
    coordinate.
    """

    square: float
    box: dict[str, float]
    ellipsoid: dict[str, object]
    coordinates: tuple[str, ...]
    status: str = "optimal"

    def to_json(self) -> dict:
        ellipsoid = {k: v for k, v in self.ellipsoid.items() if k != "matrix"}
        return {"square": self.square, "box": self.box, "ellipsoid": ellipsoid,
                "coordinates": list(self.coordinates), "status": self.status}


@dataclass(frozen=True)
class Solution:
    """The raw solution vector with multipliers, for warm starts."""

    key: str
    x: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray


@dataclass(frozen=True)
class OptimizeResult:
    """What `optimize` found.

    status: one of Status (only OPTIMAL / EVALUATED are success).
    design: every design variable by its spec name (SI units, radians), derived ones included.
    objective: the weighted score sum_j w_j (+/-) term_j (higher is better); None if infeasible.
    objectives: each objective term's natural value (tolerance in m, drop in m, ...).
    tolerance: the robust box half-widths per axis (None unless max_offset_tolerance is asked).
    linearised: the cvxpy box and ellipsoid in the linearised safe set (None if not computed).
    margins: nominal normalised margins of the closed-form analysis, by margin name.
    robust_margins: each NLP condition's worst-case normalised margin, by condition label.
    violations: elastic diagnosis when infeasible.
    checks: independent re-checks of the answer (closed forms, sampled offsets).
    """

    status: Status
    design: dict[str, float]
    objective: float | None
    objectives: dict[str, float]
    tolerance: dict[str, float] | None
    linearised: LinearisedTolerance | None
    margins: dict[str, float]
    robust_margins: dict[str, float]
    periodic: dict[str, float | None]
    violations: tuple[Violation, ...]
    checks: dict[str, object]
    stats: SolverStats
    message: str
    solution: Solution | None = field(default=None, repr=False)
    at_bounds: tuple[str, ...] = ()  # design variables at a bound of the least-violation design
    # the distinct local optima the runs reached (solve.optimize.optima): what a table continues
    # from at its next point (optimize's `continued`)
    optima: tuple[Solution, ...] = field(default=(), repr=False)
    # the allocated and given tolerances of a spec whose [tolerances] allocates (formulation/
    # allocation.py): {quantity, applies_to, value (SI), unit, allocated}; None otherwise
    tolerances: tuple[dict, ...] | None = None

    @property
    def success(self) -> bool:
        return self.status.is_success

    def to_json(self) -> dict:
        return {
            "status": self.status.value,
            "message": self.message,
            "design": self.design,
            "objective": self.objective,
            "objectives": self.objectives,
            "tolerance": self.tolerance,
            "linearised_tolerance": self.linearised.to_json() if self.linearised else None,
            "tolerances": list(self.tolerances) if self.tolerances is not None else None,
            "margins": self.margins,
            "robust_margins": self.robust_margins,
            "periodic": self.periodic,
            "violations": [v.to_json() for v in self.violations],
            "checks": self.checks,
            "solver": self.stats.to_json(),
        }
