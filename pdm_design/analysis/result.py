"""The closed-form analysis of one fixed design: geometry, periodic orbit, margins, problems."""

from __future__ import annotations

from dataclasses import dataclass, field


def required(name: str, requirements: dict[str, float], kind: str) -> float:
    """The least value margin `name` of a scene of `kind` must have: the largest requirement
    that holds it, its own or one of those that hold it too (Scene.covered_by: docs/spec.md,
    section 7), as the optimizer's rows do."""
    from ..plugin import scene_kind

    covering = scene_kind(kind).covered_by.get(name, ()) if kind else ()
    return max(float(requirements.get(key, 0.0)) for key in (name, *covering))


def margin(capacity, demand) -> float:
    """Normalised slack of a condition demand <= capacity, in [-1, 1].

    1 - demand/capacity while the condition holds (the fraction of capacity to spare), and
    -(1 - capacity/demand) when it fails (the fraction of the demand that cannot be met);
    0 exactly at the limit.
    """
    capacity, demand = float(capacity), float(demand)
    scale = max(capacity, demand)
    if scale <= 0.0:
        return 0.0 if capacity == demand else -1.0
    return (capacity - demand) / scale


@dataclass(frozen=True)
class Analysis:
    """What the closed forms say about one design (no simulation involved).

    design: every design variable by its spec name, resolved (SI units, radians).
    geometry, periodic: named derived quantities; None where they do not exist.
    margins: each physical condition's normalised slack (see `margin`); >= 0 means it holds.
    approach: the first approach from the initial state into the periodic pattern.
    problems: reasons in words why the design cannot work (besides negative margins).
    """

    kind: str
    design: dict[str, float]
    geometry: dict[str, float | None]
    periodic: dict[str, float | None]
    margins: dict[str, float]
    approach: dict[str, object] = field(default_factory=dict)
    problems: tuple[str, ...] = ()

    def violations(self, requirements: dict[str, float] | None = None) -> list[str]:
        """Margins below their required minimum (default 0: `required`), in words."""
        requirements = requirements or {}
        out = []
        for name, value in self.margins.items():
            need = required(name, requirements, self.kind)
            if value < need:
                out.append(f"margin {name} = {value:.4g} is below the required {need:.4g}")
        return out

    def feasible(self, requirements: dict[str, float] | None = None) -> bool:
        return not self.problems and not self.violations(requirements)
