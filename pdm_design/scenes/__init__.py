"""Scenes: frozen, self-validating descriptions of what the designer does not choose,
and design points (what the designer chooses)."""

from .manipulators import Body, ManipulatorsDesign, ManipulatorsInitial, ManipulatorsScene, Palm
from .stairs import Ball, StairsDesign, StairsInitial, StairsScene

Scene = StairsScene | ManipulatorsScene
Design = StairsDesign | ManipulatorsDesign

__all__ = [
    "Ball", "Body", "Design", "ManipulatorsDesign", "ManipulatorsInitial", "ManipulatorsScene",
    "Palm", "Scene", "StairsDesign", "StairsInitial", "StairsScene",
]
