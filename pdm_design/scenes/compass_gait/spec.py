"""A compass-gait spec's own tables: [scene] (with [scene.walker]), [initial] and [design] into
the scene and the design values (numbers fixed, Bounds free), with errors that name the key."""

from __future__ import annotations

from pydantic import ValidationError

from ...errors import SpecError
from .scene import CompassGaitDesign, CompassGaitInitial, CompassGaitScene, Walker

# requirement keys of this scene: margins (analysis.py) and the stability bound
MARGINS = ("stance_contact", "no_slip", "stability", "hip_limit")
REQUIREMENTS = (*MARGINS, "max_spectral_radius")
OBJECTIVES = ("min_spectral_radius", "max_slope_tolerance")


def read_tables(data: dict, source: str = "<spec>"):
    """(scene, design values): design values are numbers or spec.model.Bounds."""
    from ...spec.model import Bounds

    scene_table = dict(data.get("scene", {}))
    scene_table.pop("kind", None)
    walker = scene_table.pop("walker", {})
    try:
        walker = Walker(**walker)
    except (ValidationError, TypeError) as exc:
        raise _error(source, "scene.walker", exc) from None
    try:
        initial = CompassGaitInitial(**data.get("initial", {}))
    except (ValidationError, TypeError) as exc:
        raise _error(source, "initial", exc) from None
    try:
        scene = CompassGaitScene(initial=initial, walker=walker, **scene_table)
    except (ValidationError, TypeError) as exc:
        raise _error(source, "scene", exc) from None
    design: dict = {}
    for name, value in data.get("design", {}).items():
        if name not in CompassGaitDesign.VARIABLES:
            raise SpecError(source, f"design.{name}", "one of " +
                            ", ".join(CompassGaitDesign.VARIABLES), found=repr(name))
        if isinstance(value, dict):
            try:
                design[name] = Bounds(**value)
            except (ValidationError, TypeError) as exc:
                raise _error(source, f"design.{name}", exc) from None
        else:
            design[name] = value
    try:  # the design's ground and numbers, at the free variables' guesses
        design_at(design)
    except (ValidationError, TypeError) as exc:
        raise _error(source, "design", exc) from None
    return scene, design


def design_at(values: dict, free: dict | None = None) -> CompassGaitDesign:
    """The design with every free variable at its guess (or at free[name])."""
    from ...spec.model import Bounds

    out = {}
    for name, value in values.items():
        if isinstance(value, Bounds):
            value = (free or {}).get(name, value.guess)
        out[name] = float(value)
    return CompassGaitDesign(**out)


def _error(source, key, exc) -> SpecError:
    if isinstance(exc, ValidationError):
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err.get("loc", ()) if p != "__root__")
        path = f"{key}.{where}" if where else key
        return SpecError(source, path, err.get("msg", "a valid value"),
                         found=repr(err.get("input")) if "input" in err else None)
    return SpecError(source, key, "known keys only", found=str(exc))
