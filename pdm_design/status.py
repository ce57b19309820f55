"""One status vocabulary for every answer the tool gives, with what to do about each."""

from __future__ import annotations

from enum import Enum


class Status(Enum):
    """Outcome of evaluating or optimising a design. The value is the name used in JSON."""

    OPTIMAL = "optimal"
    EVALUATED = "evaluated"
    ACCEPTABLE = "acceptable"
    ITERATION_LIMIT = "iteration_limit"
    INFEASIBLE = "infeasible"
    SOLVER_ERROR = "solver_error"
    UNVERIFIED = "unverified"

    @property
    def message(self) -> str:
        return _MESSAGES[self]

    @property
    def is_success(self) -> bool:
        """Only a converged optimum or a fully checked fixed design counts as success."""
        return self in (Status.OPTIMAL, Status.EVALUATED)

    @property
    def exit_code(self) -> int:
        return 0 if self.is_success else 1


_MESSAGES = {
    Status.OPTIMAL: "IPOPT converged to a local optimum that meets every constraint.",
    Status.EVALUATED: "The design is fixed; it was evaluated and meets every requirement.",
    Status.ACCEPTABLE: "IPOPT stopped at its 'acceptable' tolerance, not at optimality: "
    "tighten nothing, but re-run with more iterations or a better initial guess before building.",
    Status.ITERATION_LIMIT: "IPOPT hit its iteration limit: raise the limit or give an initial "
    "guess closer to the answer.",
    Status.INFEASIBLE: "No design meets every requirement: relax the requirements listed as "
    "violated, widen the bounds, or change the scene.",
    Status.UNVERIFIED: "IPOPT converged, but an independent re-check of the answer (closed-form "
    "analysis or offsets sampled inside the tolerance box) failed: do not build it; see the "
    "checks and report the spec.",
    Status.SOLVER_ERROR: "The solver failed (numerical trouble): check the scene for degenerate "
    "values and report the spec if it looks sound.",
}
