"""The JSON document printed by `pdm-design optimize --format json` (docs/json-schema.md).

The document carries every key the schema lists, whatever the design: a quantity that does not
exist for it (no periodic orbit, no impact, no tolerance box asked) is null, a list with nothing
in it is []. The analysis leaves such quantities out; this layer puts them back as null.
"""

from __future__ import annotations

from ..api import DesignOutcome
from ..plugin import of
from ..spec.model import OBJECTIVES
from .jsonable import jsonable

SCHEMA = "pdm-design/optimize/1"

# The keys of the design, geometry, periodic and approach objects are the scene's
# (Scene.document_keys; docs/json-schema.md).
OBJECTIVE = ("weights", "value", "terms")
VERIFICATION = ("passed", "summary", "failures", "samples", "outcome", "agreement",
                "tolerance_failures", "accuracy", "accuracy_settings")
VERIFICATION_LISTS = ("failures", "tolerance_failures")
OUTCOME = ("completed", "stages_passed", "failure")


def optimize_document(outcome: DesignOutcome) -> dict:
    spec, analysis = outcome.spec, outcome.analysis
    kind, keys = spec.kind, of(spec).document_keys()
    return jsonable({
        "schema": SCHEMA,
        "spec": spec.source,
        "spec_sha256": spec.digest or None,
        "name": spec.name,
        "status": outcome.status,
        "status_message": outcome.status_message,
        "scene": kind,
        "scene_parameters": scene_parameters(spec.scene),
        "design": _complete(analysis.design, keys["design"]),
        "free_variables": list(spec.free_variables),
        "at_bounds": outcome.at_bounds,
        "geometry": _complete(analysis.geometry, keys["geometry"]),
        "periodic": _complete(analysis.periodic, keys["periodic"]),
        "margins": analysis.margins,
        "requirements": spec.requirements,
        "violations": list(outcome.violations),
        "approach": _complete(analysis.approach, keys["approach"]),
        "objective": _objective(outcome),
        "tolerance": outcome.tolerance,
        "tolerances": _tolerances(outcome.tolerances),
        "tolerances_yield": outcome.tolerances_yield,
        "verification": _verification(outcome.verification),
        "solver": outcome.solver,
    })


def scene_parameters(scene) -> dict:
    """The device-as-built keys of the spec's scene, as given (docs/json-schema.md;
    Scene.scene_parameters): every key even when the spec leaves them out; {} for a scene
    that has none."""
    return of(scene).scene_parameters(scene)


def _complete(values: dict | None, keys: tuple[str, ...], lists: tuple[str, ...] = ()) -> dict:
    """values with every key of `keys` (first, in that order; null, or [] for `lists`, where it
    has none), then any other key it has."""
    values = values or {}
    out = {k: values.get(k, [] if k in lists else None) for k in keys}
    out.update({k: v for k, v in values.items() if k not in out})
    return out


def _objective(outcome: DesignOutcome) -> dict | None:
    """The objective with every term's key (api's values: null where it has none)."""
    if outcome.objective is None:
        return None
    objective = _complete(outcome.objective, OBJECTIVE)
    objective["terms"] = _complete(objective["terms"], OBJECTIVES)
    return objective


def _verification(verification: dict | None) -> dict | None:
    if verification is None:
        return None
    out = _complete(verification, VERIFICATION, VERIFICATION_LISTS)
    if isinstance(out["outcome"], dict):
        out["outcome"] = _complete(out["outcome"], OUTCOME)
    return out


def _tolerances(entries) -> list[dict] | None:
    """optimize's allocated tolerance list ({quantity, applies_to, value (SI), unit,
    limited_by}, docs/json-schema.md), None when the spec allocates none."""
    if entries is None:
        return None
    keys = ("quantity", "applies_to", "value", "unit", "allocated", "limited_by")
    return [{k: e[k] for k in keys} for e in entries]
