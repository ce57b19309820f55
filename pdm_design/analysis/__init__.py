"""Closed-form analysis of a fixed design, scene by scene."""

from .result import Analysis, margin


def analyse(scene, design) -> Analysis:
    """The closed-form analysis of `design` in `scene` (dispatches on the scene kind)."""
    if scene.kind == "stairs":
        from .stairs import analyse_stairs

        return analyse_stairs(scene, design)
    from .manipulators import analyse_manipulators

    return analyse_manipulators(scene, design)


__all__ = ["Analysis", "analyse", "margin"]
