"""The SI unit of every design, geometry and periodic-orbit quantity, one table for the text
report (report/text.py) and the report page (report/html.py): the shared quantities' here, a
scene's own over them (Scene.quantity_units); and the geometry a scene shows
(Scene.shown_geometry)."""

from __future__ import annotations

# the quantities of the shared objectives (formulation.common.OBJECTIVE_SENSE: min_drop,
# fastest_convergence), whatever scene reports them
UNITS = {"contraction": "", "drop_per_stage": "m", "spectral_radius": ""}


def units_of(kind: str) -> dict[str, str]:
    """{quantity: SI unit} of a scene of `kind`: the shared table with the scene's own over it."""
    from ..plugin import scene_kind

    return {**UNITS, **scene_kind(kind).quantity_units}


def built_parts(kind: str, geometry: dict) -> dict:
    """The geometry a scene of `kind` shows (Scene.shown_geometry; the JSON keeps every key)."""
    from ..plugin import scene_kind

    return scene_kind(kind).shown_geometry(geometry)
