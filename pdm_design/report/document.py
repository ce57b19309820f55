"""The JSON document printed by `pdm-design optimize --format json` (docs/json-schema.md)."""

from __future__ import annotations

from ..api import DesignOutcome
from .jsonable import jsonable

SCHEMA = "pdm-design/optimize/1"


def optimize_document(outcome: DesignOutcome) -> dict:
    spec, analysis = outcome.spec, outcome.analysis
    return jsonable({
        "schema": SCHEMA,
        "spec": spec.source,
        "name": spec.name,
        "status": outcome.status,
        "status_message": outcome.status.message,
        "scene": spec.kind,
        "design": analysis.design,
        "free_variables": list(spec.free_variables),
        "geometry": analysis.geometry,
        "periodic": analysis.periodic,
        "margins": analysis.margins,
        "requirements": spec.requirements,
        "violations": list(outcome.violations),
        "approach": analysis.approach,
        "objective": outcome.objective,
        "tolerance": outcome.tolerance,
        "verification": outcome.verification,
        "solver": outcome.solver,
    })
