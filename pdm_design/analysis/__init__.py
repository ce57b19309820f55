"""Closed-form analysis of a fixed design, scene by scene."""

from .result import Analysis, margin


def analyse(scene, design, stages: int | None = None) -> Analysis:
    """The closed-form analysis of `design` in `scene` (dispatches on the scene kind); stages:
    the number of stages the design must pass (stairs: the approach from the drop height is
    then followed bounce by bounce; a row of manipulators settles monotonically, its first
    approach and periodic orbit bound every stage)."""
    if scene.kind == "stairs":
        from .stairs import analyse_stairs

        return analyse_stairs(scene, design, stages)
    from .manipulators import analyse_manipulators

    return analyse_manipulators(scene, design, stages)


__all__ = ["Analysis", "analyse", "margin"]
