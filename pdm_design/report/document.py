"""The JSON document printed by `pdm-design optimize --format json` (docs/json-schema.md).

The document carries every key the schema lists, whatever the design: a quantity that does not
exist for it (no periodic orbit, no bounce, no tolerance box asked) is null, a list with nothing
in it is []. The analysis leaves such quantities out; this layer puts them back as null.
"""

from __future__ import annotations

from ..api import DesignOutcome
from ..scenes import ManipulatorsDesign, StairsDesign
from ..spec.model import OBJECTIVES
from .jsonable import jsonable

SCHEMA = "pdm-design/optimize/1"

# The keys of each object, by scene where they differ (docs/json-schema.md).
DESIGN = {"manipulators": ManipulatorsDesign.VARIABLES, "stairs": StairsDesign.VARIABLES}
GEOMETRY = {"manipulators": ("pitch_x", "pitch_y", "palm_mass", "link_mass", "link_inertia",
                             "link_count", "pivot_friction_torque", "pivot_damping",
                             "landing_offset"),
            "stairs": ("rise", "tread", "landing_offset", "nose_clearance")}
PERIODIC = {"manipulators": ("handover_speed", "landing_speed", "contraction", "drop_per_stage",
                             "effective_mass"),
            "stairs": ("impact_speed", "vertical_impact_speed", "horizontal_speed", "spin",
                       "flight_time", "drift_per_bounce")}
APPROACH = {"manipulators": ("landing_point", "landing_velocity", "handover_speeds"),
            "stairs": ("first_vertical_impact_speed",)}
OBJECTIVE = ("weights", "value", "terms")
VERIFICATION = ("passed", "summary", "failures", "samples", "outcome", "agreement",
                "tolerance_failures", "accuracy", "accuracy_settings")
VERIFICATION_LISTS = ("failures", "tolerance_failures")
OUTCOME = ("completed", "stages_passed", "failure")


def optimize_document(outcome: DesignOutcome) -> dict:
    spec, analysis = outcome.spec, outcome.analysis
    kind = spec.kind
    return jsonable({
        "schema": SCHEMA,
        "spec": spec.source,
        "spec_sha256": spec.digest or None,
        "name": spec.name,
        "status": outcome.status,
        "status_message": outcome.status_message,
        "scene": kind,
        "scene_parameters": scene_parameters(spec.scene),
        "design": _complete(analysis.design, DESIGN[kind]),
        "free_variables": list(spec.free_variables),
        "at_bounds": outcome.at_bounds,
        "geometry": _complete(analysis.geometry, GEOMETRY[kind]),
        "periodic": _complete(analysis.periodic, PERIODIC[kind]),
        "margins": analysis.margins,
        "requirements": spec.requirements,
        "violations": list(outcome.violations),
        "approach": _complete(analysis.approach, APPROACH[kind]),
        "objective": _objective(outcome),
        "tolerance": outcome.tolerance,
        "tolerances": _tolerances(outcome.tolerances),
        "tolerances_yield": outcome.tolerances_yield,
        "verification": _verification(outcome.verification),
        "solver": outcome.solver,
    })


def scene_parameters(scene) -> dict:
    """The device-as-built keys of the spec's scene, as given (docs/json-schema.md): for
    manipulators `links` (mass of each link, inertia about its pivot or null for a uniform rod,
    count) and `pivots` (friction_torque, damping), every key even when the spec leaves them
    out (then the paper's zeros); {} for stairs, which have none."""
    if getattr(scene, "kind", None) != "manipulators":
        return {}
    links, pivots = scene.links, scene.pivots
    return {"links": {"mass": links.mass, "inertia": links.inertia, "count": links.count},
            "pivots": {"friction_torque": pivots.friction_torque, "damping": pivots.damping}}


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
