"""Reading spec files: TOML in, a typed and validated Spec out, or one SpecError saying what is
wrong (the file, the key path as the user wrote it, what was expected and what was found).

This is the only module that reads raw TOML. The scenes validate themselves (pydantic); this module
checks the layout around them and turns pydantic's errors into key paths of the spec file.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import re
import reprlib
import stat
import tomllib
import typing
from pathlib import Path
from typing import Annotated, Any, NamedTuple

import pydantic
from pydantic import Field, Strict, TypeAdapter

from .. import plugin
from ..accuracy import Accuracy, AccuracyError, accuracy
from ..errors import SpecError, did_you_mean
from ..scenes.common import CONFIG, is_number
from .model import (
    Bounds,
    Expectations,
    Spec,
    Verification,
    Weight,
)

MAX_FILE_BYTES = 8 * 2**20
"""Larger files are refused unread: no spec needs megabytes."""

TOP_LEVEL_KEYS = ("name", "description", "scene", "initial", "design", "objective",
                  "requirements", "verification", "expect", "tolerances")
BOUNDS_KEYS = ("min", "max", "initial")
FREE_OR_FIXED = "a number (fixed) or a table {min = .., max = .., initial = ..} (free)"
RequiredMargin = Annotated[float, Strict(), Field(ge=-1, le=1)]


class _Kind(NamedTuple):
    """What the loader asks of the spec's scene (pdm_design.plugin.Scene)."""

    scene: type
    design: type
    margins: tuple[str, ...]
    verification_hints: dict[str, str]  # verification keys this kind does not take, and why
    plugin: plugin.Scene

    @classmethod
    def of(cls, found: plugin.Scene) -> _Kind:
        return cls(found.scene_class(), found.design_class(), found.margins,
                   found.verification_hints, found)

_SCENE_HINTS = {"initial": "initial conditions go in the top-level [initial] table"}
_WEIGHT = TypeAdapter(Weight, config=CONFIG)
_REQUIRED_MARGIN = TypeAdapter(RequiredMargin, config=CONFIG)
_MISSING = object()


class _Invalid(Exception):
    """One problem, before the file name is attached."""

    def __init__(self, key: str, expected: str, found: str | None):
        super().__init__(key)
        self.key, self.expected, self.found = key, expected, found


# --------------------------------------------------------------------------- reading the file

def load_spec(path: str | Path) -> Spec:
    """Read and validate the spec file at `path`. Raises SpecError for any problem."""
    return parse_spec(read_spec_data(path), str(path))


def read_spec_data(path: str | Path) -> dict:
    """The spec file at `path` as TOML data, not yet validated (a sweep edits it point by point
    before parse_spec). Raises SpecError when the file cannot be read or is not TOML."""
    source = str(path)
    text = _read_text(Path(path), source)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(source, "", "valid TOML", str(exc)) from None
    except RecursionError:
        raise SpecError(source, "", "TOML nested at most a few hundred levels deep",
                        "deeper nesting") from None
    except ValueError as exc:  # e.g. an integer with thousands of digits
        found = ("an integer of more than 4300 digits" if "int_max_str_digits" in str(exc)
                 else str(exc))  # (Python's advice on that limit is for programmers)
        raise SpecError(source, "", "valid TOML", found) from None


def _read_text(path: Path, source: str) -> str:
    try:
        if stat.S_ISFIFO(path.stat().st_mode):  # opening one waits for a writer, maybe forever
            raise SpecError(source, "", "a spec file", "a named pipe")
        with path.open("rb") as stream:
            raw = stream.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise SpecError(source, "", "an existing spec file", "no such file") from None
    except IsADirectoryError:
        raise SpecError(source, "", "a spec file", "a directory") from None
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise SpecError(source, "", "a readable spec file", reason) from None
    if len(raw) > MAX_FILE_BYTES:
        raise SpecError(source, "", f"a spec file of at most {MAX_FILE_BYTES // 2**20} MB",
                        "a larger file")
    nul = raw.find(b"\0")
    if nul >= 0:
        raise SpecError(source, "", "TOML text", f"binary data (a NUL byte at offset {nul})")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SpecError(source, "", "UTF-8 text", f"binary data (byte 0x{raw[exc.start]:02x} "
                                                  f"at offset {exc.start})") from None


# --------------------------------------------------------------------------- the spec's layout

def content_digest(data: dict) -> str:
    """sha256 of a spec's TOML data: its keys and values, not its layout or comments."""
    text = json.dumps(data, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def parse_spec(data: dict, source: str = "<spec>") -> Spec:
    """Validate a spec already read from TOML (a dict); `source` names it in errors."""
    try:
        return _parse(data, source)
    except _Invalid as problem:
        raise SpecError(source, problem.key, problem.expected, problem.found) from None


def _parse(data: Any, source: str) -> Spec:
    if not isinstance(data, dict):
        raise _Invalid("", "a table of keys", _show(data))
    if not data:
        raise _Invalid("scene", "a [scene] table", "an empty spec")
    _check_keys(data, TOP_LEVEL_KEYS, "")
    name, description = _string(data, "name"), _string(data, "description")
    kind = _kind(_table(data, "scene", required=True))
    scene = _scene(data, kind)
    design = _design(_table(data, "design", required=True), kind.design)
    verification = _verification(_table(data, "verification"), kind)
    _check_stages(verification, kind, design)
    problem = kind.plugin.check_spec(scene, design)
    if problem:
        raise _Invalid(*problem)
    expect_table = _table(data, "expect")
    _check_fields(expect_table, Expectations, "expect")
    tolerances = _tolerances(_table(data, "tolerances"), kind.plugin)
    if "min_yield" in expect_table and not tolerances:
        raise _Invalid("expect.min_yield", "a [tolerances] table to draw the builds from",
                       "no [tolerances]")
    objective = _objective(data, kind.plugin)
    _check_max_yield(objective, kind.plugin, scene, tolerances)
    _check_yield_target(tolerances)
    return Spec(
        source=source,
        scene=scene,
        design=design,
        objective=objective,
        requirements=_named_numbers(data, "requirements", kind.plugin.requirement_keys,
                                    _REQUIRED_MARGIN),
        verification=verification,
        expect=_build(Expectations, expect_table, "expect"),
        tolerances=tolerances,
        name=name,
        description=description,
        digest=content_digest(data),
    )


def _objective(data: dict, scene: plugin.Scene) -> dict[str, float]:
    """[objective]: weights of the scene's objectives (Scene.objectives), stored under the
    shared terms' names (Scene.objective_aliases)."""
    weights = _named_numbers(data, "objective", scene.objectives + scene.search_objectives,
                             _WEIGHT)
    return {scene.objective_aliases.get(name, name): w for name, w in weights.items()}


def _verification(table: dict, kind: _Kind) -> Verification:
    """[verification]: its settings, and the per-stage lists of the scene (Scene.stage_lists)
    built item by item, each stage listed once."""
    table = dict(table)
    lists = kind.plugin.stage_lists()
    setting = table.pop("accuracy", _MISSING)
    _check_keys(table, _verification_keys(lists, kind.verification_hints), "verification",
                kind.verification_hints)
    given = {key: table.pop(key) for key in lists if key in table}
    for key, items in given.items():
        if isinstance(items, list):  # (a wrong type is reported when the list is built)
            for i, item in enumerate(items):
                _check_fields(item, lists[key].item, f"verification.{key}[{i}]")
    if setting is not _MISSING:
        table["accuracy"] = _accuracy(setting)
    fields = tuple(Verification.__pydantic_fields__)
    before = fields[:fields.index("stage_lists")]  # errors in the order of the table's fields
    _build(Verification, {k: v for k, v in table.items() if k in before}, "verification")
    built = tuple((key, _stage_list(given.get(key, []), found, f"verification.{key}"))
                  for key, found in lists.items())
    verification = _build(Verification, {**table, "stage_lists": built}, "verification")
    for (key, items), found in zip(built, lists.values()):
        _check_unique(items, found.index, f"verification.{key}")
    return verification


def _verification_keys(lists: dict, hints: dict) -> tuple[str, ...]:
    """The keys [verification] takes: Verification's settings, the scene's per-stage lists in
    the place of its stage_lists, less those the scene refuses (its hints)."""
    keys = []
    for name in Verification.__pydantic_fields__:
        keys += list(lists) if name == "stage_lists" else [name]
    return tuple(key for key in keys if key not in hints)


def _stage_list(data: Any, found: plugin.StageList, path: str) -> tuple:
    """The items of one per-stage list (an array of tables of `found.item`); the first error
    becomes an _Invalid at its key."""
    try:
        return _items_of(found.item).validate_python(data)
    except pydantic.ValidationError as exc:
        error = exc.errors()[0]
        key, node = _locate(path, error["loc"], data)
        raise _invalid(error, key, data=node) from None


@functools.cache
def _items_of(item: type) -> TypeAdapter:
    return TypeAdapter(tuple[item, ...], config=CONFIG)


def _check_stages(verification: Verification, kind: _Kind, design: dict) -> None:
    """What the number of stages allows: a run that fits in memory, an NLP IPOPT can solve,
    and the per-stage lists' items on stages that are run."""
    stages = verification.stages
    free = any(isinstance(v, Bounds) for v in design.values())
    for asked in (False, True) if free else (False,):  # what is run, then what is optimised
        limit, why = kind.plugin.stage_limit(asked)
        if stages > limit:
            raise _Invalid("verification.stages", f"an integer <= {limit} {why}", str(stages))
    lists = kind.plugin.stage_lists()
    for key, items in verification.stage_lists:
        attribute = lists[key].index
        for i, item in enumerate(items):
            if getattr(item, attribute) > stages:
                raise _Invalid(f"verification.{key}[{i}].{attribute}", f"an integer <= "
                               f"verification.stages ({stages})", str(getattr(item, attribute)))


def _accuracy(setting: Any) -> Accuracy:
    """verification.accuracy: a preset name or an inline table of tolerances (parsed by
    pdm_design.accuracy, whose errors name the key within the table)."""
    try:
        return accuracy(setting)
    except AccuracyError as error:
        path = "verification.accuracy"
        key = _join(path, error.key) if error.key else path
        found = error.found if error.found is not None else _show(error.value)
        raise _Invalid(key, error.expected, found) from None


def _string(data: dict, key: str) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        raise _Invalid(key, "a string", _show(value))
    return value


def _table(data: dict, key: str, *, required: bool = False) -> dict:
    value = data.get(key, _MISSING)
    if value is _MISSING and not required:
        return {}
    if not isinstance(value, dict):
        found = "nothing" if value is _MISSING else _show(value)
        article = "an" if key[0] in "aeiou" else "a"
        raise _Invalid(key, f"{article} [{key}] table", found)
    return value


def _kind(scene: dict) -> _Kind:
    kind = scene.get("kind", _MISSING)
    if kind is _MISSING:
        raise _Invalid("scene.kind", f"one of the installed scenes: "
                       f"{', '.join(plugin.kinds())}", "nothing")
    installed = plugin.kinds()
    if not isinstance(kind, str) or kind not in installed:
        raise _Invalid("scene.kind", f"one of the installed scenes: {', '.join(installed)}",
                       _show(kind) + did_you_mean(kind, installed))
    try:
        return _Kind.of(plugin.scene_kind(kind))
    except plugin.SceneUnavailable as exc:
        raise _Invalid("scene.kind", "an installed scene that loads", str(exc)) from None


def _scene(data: dict, kind: _Kind):
    fields = {k: v for k, v in data["scene"].items() if k != "kind"}
    _check_fields(fields, kind.scene, "scene", _SCENE_HINTS, exclude=("initial",))
    initial = _table(data, "initial", required=True)
    initial_class = kind.scene.__pydantic_fields__["initial"].annotation
    _check_fields(initial, initial_class, "initial")
    return _build(kind.scene, {**fields, "initial": initial}, "scene", moved=("initial",))


def _named_numbers(data: dict, key: str, names: tuple[str, ...], adapter) -> dict[str, float]:
    table = _table(data, key)
    _check_keys(table, names, key)
    out = {}
    for name, value in table.items():
        try:
            out[name] = adapter.validate_python(value)
        except pydantic.ValidationError as exc:
            raise _invalid(exc.errors()[0], _join(key, name)) from None
    return out


def _check_unique(items, attribute: str, path: str) -> None:
    seen = set()
    for i, item in enumerate(items):
        number = getattr(item, attribute)
        if number in seen:
            raise _Invalid(f"{path}[{i}].{attribute}", f"a {attribute} not listed before in "
                           f"{path}", _show(number))
        seen.add(number)


# --------------------------------------------------------------------------- [tolerances]

TOLERANCE_SETTINGS = {"distribution": "the default distribution of every quantity",
                      "builds": "builds drawn by `pdm-design yield`",
                      "seed": "the random seed of the builds drawn",
                      "confirm": "random builds the event simulator confirms",
                      "yield_target": "the yield the allocated tolerances are sized for",
                      "workers": "local processes the event simulator runs the builds on "
                                 "(default: the machine's cores)"}
TOLERANCE_KEYS = ("value", "allocate", "weight", "applies_to", "distribution")
_COUNT = TypeAdapter(Annotated[int, Strict(), Field(ge=1, le=10_000_000)], config=CONFIG)
_SEED = TypeAdapter(Annotated[int, Strict(), Field(ge=0, le=2**63 - 1)], config=CONFIG)
_CONFIRM = TypeAdapter(Annotated[int, Strict(), Field(ge=0, le=100_000)], config=CONFIG)
_WORKERS = TypeAdapter(Annotated[int, Strict(), Field(ge=1, le=4096)], config=CONFIG)
_PLUS_MINUS = TypeAdapter(Annotated[float, Strict(), Field(gt=0, le=1e6)], config=CONFIG)
_STRICT_BOOL = TypeAdapter(Annotated[bool, Strict()], config=CONFIG)
_FRACTION = TypeAdapter(Annotated[float, Strict(), Field(gt=0, lt=1)], config=CONFIG)


def _check_max_yield(objective: dict, found: plugin.Scene, scene, tolerances) -> None:
    """objective.max_yield needs tolerances that all have values, and a scene whose linearised
    yield models it (Scene.max_yield_refusal)."""
    if not objective.get("max_yield"):
        return
    refusal = found.max_yield_refusal(scene)
    if refusal:
        raise _Invalid("objective.max_yield", *refusal)
    if not tolerances or any(t.value is None for t in tolerances):
        raise _Invalid("objective.max_yield", "a [tolerances] table whose every quantity has "
                       "a value (the yield is at given tolerances)",
                       "no [tolerances]" if not tolerances else "a tolerance to allocate")


def _check_yield_target(tolerances) -> None:
    """tolerances.yield_target sizes allocated tolerances by the scene's linearised yield: it
    needs a quantity with allocate = true."""
    if tolerances.yield_target is None:
        return
    if not any(t.allocate for t in tolerances):
        raise _Invalid("tolerances.yield_target", "a quantity with allocate = true (the "
                       "tolerances sized for the target)", "no tolerance to allocate")


def _tolerances(table: dict, scene: plugin.Scene):
    """[tolerances]: settings (distribution, builds, seed, confirm) and one table per quantity
    of the scene (Scene.quantities) with value = +-t (SI) or allocate = true (and a weight),
    applies_to ("each" or "lot") and distribution ("normal" or "uniform")."""
    from ..tolerance_model import DISTRIBUTIONS, Tolerance, Tolerances

    quantities = scene.quantities()
    _check_keys(table, tuple(TOLERANCE_SETTINGS) + tuple(quantities), "tolerances")
    default = _choice(table, "distribution", DISTRIBUTIONS, "tolerances", "normal")
    settings = {key: _setting(table, key, adapter) for key, adapter in
                (("builds", _COUNT), ("seed", _SEED), ("confirm", _CONFIRM),
                 ("yield_target", _FRACTION), ("workers", _WORKERS)) if key in table}
    items = []
    for name, quantity in quantities.items():
        if name not in table:
            continue
        path = _join("tolerances", name)
        entry = table[name]
        if not isinstance(entry, dict):
            raise _Invalid(path, "a table {value = .., applies_to = .., distribution = ..} "
                           "or {allocate = true, weight = ..}", _show(entry))
        _check_keys(entry, TOLERANCE_KEYS, path)
        applies = _choice(entry, "applies_to", quantity.applies, path,
                          quantity.default_applies_to)
        value, weight = _tolerance_value(entry, path)
        items.append(Tolerance(name, applies, value, weight,
                               _choice(entry, "distribution", DISTRIBUTIONS, path, default)))
    return Tolerances(tuple(items), **settings)


def _tolerance_value(entry: dict, path: str) -> tuple[float | None, float]:
    """(value, weight) of one quantity's table: exactly one of value and allocate = true."""
    allocate = _setting(entry, "allocate", _STRICT_BOOL, path) if "allocate" in entry else False
    if allocate and "value" in entry:
        raise _Invalid(_join(path, "allocate"), "either value (a tolerance to check) or "
                       "allocate = true (one to find), not both", "both")
    if not allocate and "value" not in entry:
        raise _Invalid(_join(path, "value"), "a number > 0 (the +- tolerance, SI), or "
                       "allocate = true", "nothing")
    if "weight" in entry and not allocate:
        raise _Invalid(_join(path, "weight"), "a weight only with allocate = true (it says how "
                       "cheap the quantity is to hold tight)", _show(entry["weight"]))
    weight = _setting(entry, "weight", _PLUS_MINUS, path) if "weight" in entry else 1.0
    value = None if allocate else _setting(entry, "value", _PLUS_MINUS, path)
    return value, weight


def _setting(table: dict, key: str, adapter, path: str = "tolerances"):
    try:
        return adapter.validate_python(table[key])
    except pydantic.ValidationError as exc:
        raise _invalid(exc.errors()[0], _join(path, key)) from None


def _choice(table: dict, key: str, allowed: tuple[str, ...], path: str, default: str) -> str:
    value = table.get(key, default)
    if not isinstance(value, str) or value not in allowed:
        raise _Invalid(_join(path, key), "one of: " + ", ".join(f'"{a}"' for a in allowed),
                       _show(value) + did_you_mean(value, allowed))
    return value


# --------------------------------------------------------------------------- the design space

def _design(table: dict, design_class) -> dict[str, float | Bounds]:
    _check_keys(table, design_class.VARIABLES, "design")
    values: dict[str, float | Bounds] = {}
    for name, value in table.items():
        path = _join("design", name)
        if isinstance(value, dict):
            _check_keys(value, BOUNDS_KEYS, path)
            values[name] = _build(Bounds, value, path)
        elif is_number(value):
            values[name] = value
        else:
            raise _Invalid(path, FREE_OR_FIXED, _show(value))
    for name, info in design_class.__pydantic_fields__.items():
        if info.is_required() and name not in values:
            raise _Invalid(_join("design", name), FREE_OR_FIXED.replace(
                "a number", "this required variable as a number", 1), "nothing")
    _check_design_points(design_class, values)
    return {k: v if isinstance(v, Bounds) else float(v) for k, v in values.items()}


def _check_design_points(design_class, values: dict) -> None:
    """Each free variable's min and max, then every fixed value and guess, must be valid."""
    guesses = {k: v.guess if isinstance(v, Bounds) else v for k, v in values.items()}
    for name, bounds in values.items():
        if isinstance(bounds, Bounds):
            for end in ("min", "max"):
                error = _first_error(design_class, {**guesses, name: getattr(bounds, end)}, name)
                if error:
                    raise _invalid(error, f"design.{_key(name)}.{end}")
    error = _first_error(design_class, guesses)
    if error:
        name = error["loc"][0] if error["loc"] else None
        value = values.get(name)
        if isinstance(value, Bounds):
            suffix = ".initial" if value.initial is not None else ""
            raise _invalid(error, f"design.{_key(name)}{suffix}", found=_show(value.guess)
                           + ("" if suffix else " (the middle of [min, max])"))
        raise _invalid(error, _join("design", name) if name else "design", data=guesses)


def _first_error(cls, kwargs: dict, only: str | None = None) -> dict | None:
    try:
        cls(**kwargs)
    except pydantic.ValidationError as exc:
        errors = [e for e in exc.errors() if only is None or e["loc"][:1] == (only,)]
        return errors[0] if errors else None
    return None


# --------------------------------------------------------------------------- unknown keys

def _check_fields(table: Any, cls, path: str, hints: dict | None = None, exclude=()) -> None:
    """Unknown keys in `table` (and in the tables nested in it) meant for dataclass `cls`."""
    if not isinstance(table, dict):
        return  # pydantic reports the wrong type
    fields = {k: v for k, v in cls.__pydantic_fields__.items() if k not in exclude}
    _check_keys(table, tuple(fields), path, hints)
    for name, info in fields.items():
        nested, many = _nested_dataclass(info.annotation)
        if nested is None or name not in table:
            continue
        child, child_path = table[name], _join(path, name)
        if not many:
            _check_fields(child, nested, child_path)
        elif isinstance(child, list):
            for i, item in enumerate(child):
                _check_fields(item, nested, f"{child_path}[{i}]")


def _nested_dataclass(annotation) -> tuple[type | None, bool]:
    """The dataclass a field holds (or None), and whether it holds an array of them."""
    if dataclasses.is_dataclass(annotation):
        return annotation, False
    args = typing.get_args(annotation)
    variadic = typing.get_origin(annotation) is tuple and len(args) == 2 and args[1] is Ellipsis
    if variadic and dataclasses.is_dataclass(args[0]):
        return args[0], True
    return None, False


def _check_keys(table: dict, known: tuple[str, ...], path: str, hints: dict | None = None):
    for key in table:
        if key not in known:
            where = f"a key of {path}" if path else "a top-level key"
            hint = (hints or {}).get(key)
            found = f"unknown key {_show(key)}" + (f" ({hint})" if hint else
                                                   did_you_mean(key, known))
            raise _Invalid(_join(path, key), f"{where} ({', '.join(known)})", found)


# --------------------------------------------------------------------------- pydantic's errors

def _build(cls, kwargs: dict, path: str, moved: tuple[str, ...] = ()):
    """Construct dataclass `cls`; its first error becomes an _Invalid at the spec's key path.
    Fields named in `moved` come from top-level tables of the same name."""
    try:
        return cls(**kwargs)
    except pydantic.ValidationError as exc:
        error = exc.errors()[0]
        loc = error["loc"]
        key, node = _locate("" if loc and loc[0] in moved else path, loc, kwargs)
        if error["type"] in ("missing", "missing_argument") and _holds_table(cls, loc):
            raise _Invalid(key, "a table (this key is required)", "nothing") from None
        raise _invalid(error, key, data=node) from None


def _holds_table(cls, loc: tuple) -> bool:
    """Whether the field at pydantic location `loc` of dataclass `cls` is itself a dataclass."""
    for item in loc:
        info = getattr(cls, "__pydantic_fields__", {}).get(item)
        if info is None:
            return False
        cls = info.annotation
    return dataclasses.is_dataclass(cls)


def _invalid(error: dict, key: str, *, found: str | None = None, data: Any = _MISSING):
    """An _Invalid from one pydantic error. `data` is the input at the error's location."""
    kind, ctx = error["type"], error.get("ctx") or {}
    if kind == "value_error":  # a cross-field check in __post_init__: blame its first word
        message = str(ctx.get("error", error["msg"]))
        subject = message.split(" ", 1)[0]
        if isinstance(data, dict) and subject in data:
            key, data = _join(key, subject), data[subject]
        return _Invalid(key, f"consistent values ({message})", found or _show(data))
    if kind == "missing" and error["loc"] and isinstance(error["loc"][-1], int):
        # an item missing from a fixed-length array: the only ones in a spec are points [x, y]
        return _Invalid(key, "an array of 2 items", found or _show(list(error["input"])))
    if kind in ("missing", "missing_argument"):
        return _Invalid(key, "a value (this key is required)", "nothing")
    return _Invalid(key, _expected(error), found or _show(error["input"]))


def _expected(error: dict) -> str:
    """What a pydantic error says was expected, in the words of a spec file."""
    kind, ctx = error["type"], error.get("ctx") or {}
    simple = {
        "float_type": "a number", "float_parsing": "a number", "finite_number": "a finite number",
        "int_type": "an integer", "int_parsing": "an integer", "int_from_float": "an integer",
        "bool_type": "true or false", "bool_parsing": "true or false", "string_type": "a string",
        "dataclass_type": "a table", "dataclass_args_type": "a table", "dict_type": "a table",
        "tuple_type": "an array", "list_type": "an array",
    }
    if kind == "float_type" and is_number(error["input"]):  # an integer too big for a float
        return "a finite number"
    if kind in simple:
        return simple[kind]
    for name, symbol in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
        if name in ctx:
            return f"a number {symbol} {_number(ctx[name])}"
    if kind == "literal_error":
        return "one of: " + re.sub(r"'|\bor\b", "", ctx["expected"]).replace("  ", ", ")
    if kind in ("too_short", "too_long"):
        return f"an array of {ctx.get('min_length', ctx.get('max_length'))} items"
    return error["msg"][:1].lower() + error["msg"][1:]


def _locate(base: str, loc: tuple, data: Any) -> tuple[str, Any]:
    """The spec key path of a pydantic location, and the input found there (None if missing).
    Labels in `loc` that are not keys or indices of the input (union tags) are skipped."""
    path, node = base, data
    for item in loc:
        if isinstance(node, dict) and isinstance(item, str):
            path, node = _join(path, item), node.get(item)
        elif isinstance(node, list) and isinstance(item, int) and 0 <= item < len(node):
            path, node = f"{path}[{item}]", node[item]
    return path, node


# --------------------------------------------------------------------------- small helpers


def _key(key: Any) -> str:
    """A key as TOML would write it: bare when it can be, else a basic string with its control
    characters escaped (a raw newline would split the one-line error)."""
    key = str(key)
    if re.fullmatch(r"[A-Za-z0-9_-]+", key):
        return key
    return json.dumps(key, ensure_ascii=False).replace("\x7f", "\\u007f")


def _join(path: str, key: Any) -> str:
    return f"{path}.{_key(key)}" if path else _key(key)


def _number(x: float) -> str:
    for value, name in ((math.pi / 2, "pi/2"), (math.pi, "pi")):
        if x == value:
            return name
    return f"{x:g}"


class _TomlRepr(reprlib.Repr):
    """Short reprs of what was found, in TOML's spelling of booleans; never fails."""

    def repr_bool(self, x, level):
        return "true" if x else "false"

    def repr_int(self, x, level):
        try:
            return super().repr_int(x, level)
        except ValueError:  # more digits than int -> str allows
            return f"an integer of {x.bit_length()} bits"


_REPR = _TomlRepr()
_REPR.maxlevel, _REPR.maxstring, _REPR.maxother, _REPR.maxlong = 3, 50, 50, 40


def _show(value: Any, limit: int = 60) -> str:
    text = _REPR.repr(value)  # reprlib already survives objects whose repr fails
    return text if len(text) <= limit else text[: limit - 3] + "..."
