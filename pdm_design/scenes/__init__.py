"""Scenes: frozen, self-validating descriptions of what the designer does not choose,
and design points (what the designer chooses)."""

from .manipulators import (
    Body,
    Links,
    ManipulatorsDesign,
    ManipulatorsInitial,
    ManipulatorsScene,
    Palm,
    Pivots,
)
from .stairs import Ball, StairsDesign, StairsInitial, StairsScene

Scene = StairsScene | ManipulatorsScene
Design = StairsDesign | ManipulatorsDesign

__all__ = [
    "Ball", "Body", "Design", "ManipulatorsDesign", "ManipulatorsInitial", "ManipulatorsScene",
    "Links", "Palm", "Pivots", "Scene", "StairsDesign", "StairsInitial", "StairsScene",
]
