"""Closed-form analysis of a fixed design, scene by scene."""

from .result import Analysis, margin


def analyse(scene, design, stages: int | None = None) -> Analysis:
    """The closed-form analysis of `design` in `scene` (the scene's own); stages:
    the number of stages the design must pass (stairs: the approach from the drop height is
    then followed bounce by bounce; a row of manipulators settles monotonically, its first
    approach and periodic orbit bound every stage)."""
    from ..plugin import of

    return of(scene).analyse(scene, design, stages)


__all__ = ["Analysis", "analyse", "margin"]
