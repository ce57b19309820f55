"""Turn results into plain JSON values: numpy scalars to floats, non-finite numbers to null."""

from __future__ import annotations

import math
from dataclasses import fields, is_dataclass
from enum import Enum

import numpy as np


def jsonable(value):
    """A JSON-serialisable copy of value (dicts, lists, floats, ints, str, bool, None)."""
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, (bool, str)) or value is None:
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [jsonable(v) for v in value]
    if hasattr(value, "to_json"):
        return jsonable(value.to_json())
    if is_dataclass(value):
        return {f.name: jsonable(getattr(value, f.name)) for f in fields(value)}
    raise TypeError(f"cannot put {type(value).__name__} into JSON")
