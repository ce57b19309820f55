"""Sweep axes and grids: `--sweep NAME=START:STOP:COUNT` resolved against a spec's TOML.

NAME is a numeric parameter of the spec, by its key name (`mass_ratio`, `friction`, `gravity`) or
by a dotted path (`scene.body.width`, `body.width`); it must identify exactly one parameter. The
candidates are the numbers written in the spec file (outside `[verification]` and `[expect]`)
plus every numeric scene, initial-state and design parameter its kind has, written or not (a
parameter left at its default can be swept too). A design variable is one parameter whether it
is fixed or free: sweeping a free one fixes it at each grid value.

Each grid point's spec is the raw TOML dict with the swept keys replaced, validated again by
`parse_spec`, so a grid value outside a parameter's domain is bad input like a bad spec file.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import itertools
import math
import types
import typing
from dataclasses import dataclass

import numpy as np

from ..errors import SpecError
from ..plugin import kinds, scene_kind
from ..scenes.common import is_number

OPTION = "--sweep"
SYNTAX = "NAME=START:STOP:COUNT, e.g. mass_ratio=5:20:4"
MAX_POINTS = 1_000_000
_SKIPPED_TABLES = ("verification", "expect")


@dataclass(frozen=True)
class SweepAxis:
    """One swept parameter: its name as given, its key path in the spec, and its grid values."""

    name: str
    path: tuple[str, ...]
    values: tuple[float, ...]

    @property
    def column(self) -> str:
        """The table column of this axis: the parameter's full dotted key path."""
        return ".".join(self.path)

    def to_json(self) -> dict:
        return {"name": self.name, "path": list(self.path), "values": list(self.values)}


@dataclass(frozen=True)
class GridPoint:
    """One point of the grid: its index per axis and the parameter values there."""

    index: tuple[int, ...]
    values: tuple[float, ...]

    @property
    def key(self) -> tuple[str, ...]:
        """The point as written in the table's sweep columns (exact: repr of each float)."""
        return tuple(format_value(v) for v in self.values)


def format_value(value: float) -> str:
    """A grid value as written in the CSV: the shortest text that reads back the same float."""
    return repr(float(value))


def parse_sweep_option(text: str) -> tuple[str, float, float, int]:
    """Split `NAME=START:STOP:COUNT` (SpecError naming the option when malformed)."""
    try:
        name, rest = text.split("=", 1)
        start, stop, count = rest.split(":")
        start, stop = float(start), float(stop)
        count = int(count)
        name = name.strip()
    except ValueError:
        raise SpecError("command line", OPTION, SYNTAX, repr(text)) from None
    if not name:
        raise SpecError("command line", OPTION, SYNTAX + " (NAME missing)", repr(text))
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise SpecError("command line", OPTION, "finite START and STOP", repr(text))
    if not 1 <= count <= MAX_POINTS:
        raise SpecError("command line", OPTION, f"a COUNT from 1 to {MAX_POINTS}", repr(text))
    if count == 1 and start != stop:
        raise SpecError("command line", OPTION, "START = STOP when COUNT is 1", repr(text))
    return name, start, stop, count


def grid_values(start: float, stop: float, count: int) -> tuple[float, ...]:
    """COUNT evenly spaced values from START to STOP, both included."""
    if count == 1:
        return (float(start),)
    return tuple(float(v) for v in np.linspace(start, stop, count))


# --------------------------------------------------------------------------- parameter names

def numeric_parameters(data: dict) -> list[tuple[str, ...]]:
    """Key paths of every numeric parameter a sweep may name in this raw spec (sorted)."""
    paths: set[tuple[str, ...]] = set()
    for key, value in data.items():
        if key in _SKIPPED_TABLES:
            continue
        if key == "design" and isinstance(value, dict):
            paths.update(("design", k) for k, v in value.items() if is_number(v)
                         or isinstance(v, dict))
        else:
            _numeric_leaves(value, (key,), paths)
    scene = data.get("scene")
    kind = scene.get("kind") if isinstance(scene, dict) else None
    if isinstance(kind, str) and kind in kinds():
        scene_class, design_class = scene_kind(kind).scene_class(), scene_kind(kind).design_class()
        for path in _schema_paths(scene_class, ("scene",)):
            paths.add(("initial", *path[2:]) if path[1:2] == ("initial",) else path)
        paths.update(("design", name) for name in design_class.VARIABLES)
    return sorted(paths)


def _numeric_leaves(value, path, out):
    if is_number(value):
        out.add(path)
    elif isinstance(value, dict):
        for key, child in value.items():
            _numeric_leaves(child, (*path, str(key)), out)


def _schema_paths(cls, prefix):
    """Key paths of the numeric fields of pydantic dataclass `cls` (nested tables included)."""
    for name, info in cls.__pydantic_fields__.items():
        annotation = info.annotation
        if dataclasses.is_dataclass(annotation):
            yield from _schema_paths(annotation, (*prefix, name))
        elif _is_float_annotation(annotation):
            yield (*prefix, name)


def _is_float_annotation(annotation) -> bool:
    if annotation is float:
        return True
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _is_float_annotation(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        return bool(args) and all(_is_float_annotation(a) for a in args)
    return False



def resolve_name(data: dict, name: str) -> tuple[str, ...]:
    """The one key path NAME identifies (a key name or a dotted tail of a path)."""
    candidates = numeric_parameters(data)
    parts = tuple(name.split("."))
    matches = [p for p in candidates if p[-len(parts):] == parts]
    if len(matches) == 1:
        return matches[0]
    if len(matches) > 1:
        shown = ", ".join(".".join(p) for p in matches)
        raise SpecError("command line", OPTION, "a name that identifies one numeric parameter "
                        "of the spec", f"'{name}', which matches {shown}: give the dotted path")
    dotted = [".".join(p) for p in candidates]
    words = sorted({p[-1] for p in candidates} | set(dotted))
    close = difflib.get_close_matches(name, words, n=4, cutoff=0.5)
    hint = f"; close matches: {', '.join(close)}" if close else ""
    raise SpecError("command line", OPTION, "a numeric parameter of the spec (e.g. "
                    f"{', '.join(sorted({p[-1] for p in candidates})[:6])}, ...)",
                    f"unknown parameter '{name}'{hint}")


def sweep_axes(data: dict, options: list[str] | tuple[str, ...]) -> tuple[SweepAxis, ...]:
    """The axes of `--sweep` options, resolved against the raw spec `data`."""
    if not options:
        raise SpecError("command line", OPTION, f"at least one {OPTION} {SYNTAX}", "none")
    axes: list[SweepAxis] = []
    for text in options:
        name, start, stop, count = parse_sweep_option(text)
        path = resolve_name(data, name)
        if any(a.path == path for a in axes):
            raise SpecError("command line", OPTION, "each parameter swept once",
                            f"'{'.'.join(path)}' twice")
        axes.append(SweepAxis(name, path, grid_values(start, stop, count)))
    total = math.prod(len(a.values) for a in axes)
    if total > MAX_POINTS:
        raise SpecError("command line", OPTION, f"at most {MAX_POINTS} grid points in all",
                        f"{total}")
    return tuple(axes)


def grid_points(axes: tuple[SweepAxis, ...]) -> list[GridPoint]:
    """Every point of the grid, in grid order (the last axis varies fastest)."""
    ranges = [range(len(a.values)) for a in axes]
    return [GridPoint(index, tuple(a.values[i] for a, i in zip(axes, index)))
            for index in itertools.product(*ranges)]


def chains(points: list[GridPoint], length: int) -> list[list[int]]:
    """Split the grid into warm-start chains: runs of at most `length` consecutive points along
    the last axis. A chain is solved in order, each point warm-started from the one before, so
    the result does not depend on how many workers run the chains."""
    out: list[list[int]] = []
    for i, point in enumerate(points):
        same_line = (out and point.index[:-1] == points[out[-1][-1]].index[:-1]
                     and len(out[-1]) < length)
        if same_line:
            out[-1].append(i)
        else:
            out.append([i])
    return out


# --------------------------------------------------------------------------- point specs

def point_data(data: dict, axes_paths, values) -> dict:
    """A copy of raw spec `data` with the swept keys set to `values` (a warm start never
    changes a free variable's `initial`: that guess is the spec's tie-break, solve/tiebreak.py)."""
    out = copy.deepcopy(data)
    for path, value in zip(axes_paths, values):
        _set(out, path, value)
    return out


def _set(data: dict, path: tuple[str, ...], value: float) -> None:
    node = data
    for key in path[:-1]:
        child = node.get(key)
        if not isinstance(child, dict):
            child = node[key] = {}
        node = child
    old = node.get(path[-1])
    # an integer key (e.g. written `mass_ratio = 10`) stays an integer when the value is whole
    node[path[-1]] = int(value) if isinstance(old, int) and float(value).is_integer() else (
        float(value))
