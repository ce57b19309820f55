"""Closed-form analysis of a fixed design, scene by scene."""

from .result import Analysis, margin


def analyse(scene, design, stages: int | None = None) -> Analysis:
    """The closed-form analysis of `design` in `scene` (the scene's own); stages:
    the number of stages the design must pass (a scene may follow the approach to its
    periodic orbit stage by stage, or bound every stage by the first and the periodic one)."""
    from ..plugin import of

    return of(scene).analyse(scene, design, stages)


__all__ = ["Analysis", "analyse", "margin"]
