"""The Python API. The CLI is a thin layer over these functions."""

from __future__ import annotations

from dataclasses import dataclass, field

from .analysis import Analysis, analyse
from .spec.model import Spec
from .status import Status


@dataclass(frozen=True)
class DesignOutcome:
    """The answer to `pdm-design optimize`: the design, what the closed forms say about it, and
    (when run) the solver's statistics and the simulator's verification."""

    spec: Spec
    status: Status
    analysis: Analysis
    violations: tuple[str, ...] = ()
    objective: dict | None = None
    tolerance: dict | None = None
    verification: dict | None = None
    solver: dict | None = None
    notes: tuple[str, ...] = field(default=())

    @property
    def exit_code(self) -> int:
        verified = self.verification is None or self.verification.get("passed", False)
        return 0 if self.status.is_success and verified else 1


def evaluate(spec: Spec, *, verify: bool = True, accuracy: str | None = None) -> DesignOutcome:
    """Evaluate a spec whose design is fully fixed: closed forms, then (unless verify=False)
    the event simulator from the spec's initial state."""
    if spec.free_variables:
        raise ValueError("evaluate() needs a fixed design; use design() for free variables")
    point = spec.design_at()
    analysis = analyse(spec.scene, point)
    violations = tuple(analysis.problems) + tuple(analysis.violations(spec.requirements))
    status = Status.EVALUATED if not violations else Status.INFEASIBLE
    verification = None
    if verify and not analysis.problems:
        from .verify import verify_nominal

        verification = verify_nominal(spec, point, analysis, accuracy=accuracy)
    return DesignOutcome(spec=spec, status=status, analysis=analysis, violations=violations,
                         verification=verification)


def design(spec: Spec, *, verify: bool = True, accuracy: str | None = None) -> DesignOutcome:
    """Solve the spec: evaluate a fixed design, or optimise the free variables; verify."""
    if not spec.free_variables:
        return evaluate(spec, verify=verify, accuracy=accuracy)
    raise NotImplementedError("optimising free design variables is not available yet")
