"""The spec loader: the shipped problems load to typed values; every bad input becomes one
SpecError that names the key path (as written in the file) and what was expected."""

from __future__ import annotations

import copy
import math
import re
import tomllib
from pathlib import Path
from typing import Annotated

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import Field, Strict
from pydantic.dataclasses import dataclass as checked

from pdm_design import plugin
from pdm_design.errors import SpecError
from pdm_design.scenes.common import CONFIG, Number
from pdm_design.scenes.manipulators.model import Body, ManipulatorsInitial, ManipulatorsScene, Palm
from pdm_design.scenes.stairs.model import Ball, StairsInitial, StairsScene
from pdm_design.spec import Bounds, Spec, load_spec, parse_spec

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"

MANIPULATORS = """
[scene]
kind = "manipulators"
[scene.body]
mass = 1.0
width = 0.4
height = 0.2
[scene.palm]
width = 1.6
[initial]
position = [-1.25, 3.05]
velocity = [3, 0]
[design]
alpha = {min = 0.05, max = 0.5, initial = 0.2}
beta = 0.6
link_length = 2
mass_ratio = 10
[objective]
max_offset_tolerance = 1.0
[requirements]
lift_off = 0.1
[verification]
offsets = [{manipulator = 2, dx = 0.1, dy = -0.2}]
[expect]
feasible = true
"""

STAIRS = """
[scene]
kind = "stairs"
friction = 0.5
[scene.ball]
radius = 0.5
mass = 0.283
inertia = 0.035
[initial]
drop_height = 1.0
[design]
restitution = 0.8
launch_speed = 3.0
[verification]
step_errors = [{step = 3, rise = 0.01}]
"""


def base(kind: str) -> dict:
    return tomllib.loads(MANIPULATORS if kind == "manipulators" else STAIRS)


def with_value(data: dict, path: tuple, value) -> dict:
    """A deep copy of `data` with `value` placed at `path` (keys and list indices)."""
    data = copy.deepcopy(data)
    node = data
    for key in path[:-1]:
        node = node[key] if isinstance(node, list) else node.setdefault(key, {})
    node[path[-1]] = value
    return data


def without(data: dict, path: tuple) -> dict:
    data = copy.deepcopy(data)
    node = data
    for key in path[:-1]:
        node = node[key]
    del node[path[-1]]
    return data


def error_of(data: dict) -> SpecError:
    with pytest.raises(SpecError) as info:
        parse_spec(data, "bad.toml")
    return info.value


# --------------------------------------------------------------------------- shipped problems

def test_paper_manipulators_loads_typed_values():
    spec = load_spec(PROBLEMS / "paper_manipulators.toml")
    assert spec.kind == "manipulators"
    assert spec.scene == ManipulatorsScene(
        body=Body(mass=1.0, width=0.4, height=0.2),
        palm=Palm(width=1.6, thickness=0.05, friction=0.8, restitution=0.0, front_stop=1.5707963),
        initial=ManipulatorsInitial(position=(-1.25, 3.05), velocity=(3.0, 0.0)),
        gravity=9.81,
    )
    assert spec.design == {"alpha": 0.2, "beta": 0.6, "link_length": 2.0, "mass_ratio": 10.0}
    assert spec.verification.stages == 6
    assert spec.expect.feasible is True
    assert spec.name == "paper_manipulators"


def test_paper_stairs_friction_loads_typed_values():
    spec = load_spec(PROBLEMS / "paper_stairs_friction.toml")
    assert spec.scene == StairsScene(
        initial=StairsInitial(drop_height=1.0, spin=0.5),
        ball=Ball(radius=0.5, mass=0.283, inertia=0.035),
        friction=0.5,
        gravity=9.81,
    )
    assert spec.design == {"restitution": 0.8, "launch_speed": 3.0}
    assert spec.verification.stages == 20


def test_paper_stairs_frictionless_leaves_rise_and_tread_to_be_derived():
    spec = load_spec(PROBLEMS / "paper_stairs_frictionless.toml")
    assert spec.scene.frictionless
    assert spec.scene.ball == Ball(radius=0.05)
    design = spec.design_at()
    assert (design.restitution, design.launch_speed) == (0.8, 2.0)
    assert design.rise is None and design.tread is None


def test_source_is_the_path_given():
    path = PROBLEMS / "paper_stairs_friction.toml"
    assert load_spec(path).source == str(path)


def test_free_variable_becomes_bounds():
    spec = parse_spec(base("manipulators"), "m.toml")
    assert spec.design["alpha"] == Bounds(min=0.05, max=0.5, initial=0.2)
    assert spec.free_variables == ("alpha",)


def test_integers_are_accepted_as_floats():
    spec = parse_spec(base("manipulators"), "m.toml")
    assert spec.design["link_length"] == 2.0 and isinstance(spec.design["link_length"], float)
    assert spec.scene.initial.velocity == (3.0, 0.0)


def test_objective_requirements_and_offsets_are_read():
    spec = parse_spec(base("manipulators"), "m.toml")
    assert spec.objective == {"max_offset_tolerance": 1.0}
    assert spec.requirements == {"lift_off": 0.1}
    (offset,) = spec.verification.offsets
    assert (offset.manipulator, offset.dx, offset.dy) == (2, 0.1, -0.2)


def test_stairs_step_errors_are_read():
    (error,) = parse_spec(base("stairs"), "s.toml").verification.step_errors
    assert (error.step, error.rise, error.tread) == (3, 0.01, 0.0)


DOCS = Path(__file__).resolve().parent.parent / "docs" / "spec.md"


@pytest.mark.parametrize("kind", ["stairs", "manipulators"])
def test_complete_example_in_docs_loads(kind):
    blocks = re.findall(r"```toml\n(.*?)```", DOCS.read_text(encoding="utf-8"), re.DOTALL)
    specs = [parse_spec(tomllib.loads(b), "docs") for b in blocks if "[scene]" in b]
    (spec,) = [s for s in specs if s.kind == kind]
    assert spec.free_variables and spec.objective and spec.requirements
    assert spec.verification.has_stage_items


def test_parse_spec_returns_a_spec():
    assert isinstance(parse_spec(base("stairs"), "s.toml"), Spec)


# --------------------------------------------------------------------------- bad values

BAD_VALUES = [
    # (kind, path, value, key in the error, gist of what was expected)
    ("manipulators", ("scene", "body", "mass"), "1", "scene.body.mass", "a number"),
    ("manipulators", ("scene", "body", "mass"), True, "scene.body.mass", "a number"),
    ("manipulators", ("scene", "body", "mass"), -1.0, "scene.body.mass", "a number >= 1e-06"),
    ("stairs", ("scene", "ball", "mass"), -0.2, "scene.ball.mass", "a number >= 1e-06"),
    ("manipulators", ("scene", "palm", "restitution"), 1.5, "scene.palm.restitution",
     "a number <= 1"),
    ("manipulators", ("scene", "palm", "restitution"), -0.1, "scene.palm.restitution",
     "a number >= 0"),
    ("stairs", ("design", "restitution"), 1.2, "design.restitution", "a number <= 1"),
    ("manipulators", ("design", "beta"), math.pi / 2, "design.beta", "a number < pi/2"),
    ("manipulators", ("design", "beta"), -0.1, "design.beta", "a number > 0"),
    ("manipulators", ("design", "alpha"), {"min": 0.1, "max": 1.6}, "design.alpha.max",
     "a number < pi/2"),
    ("manipulators", ("design", "beta"), {"min": 0.0, "max": 1.0}, "design.beta.min",
     "a number > 0"),
    ("manipulators", ("scene", "gravity"), math.nan, "scene.gravity", "a finite number"),
    ("manipulators", ("initial", "position", 1), math.inf, "initial.position[1]",
     "a finite number"),
    ("manipulators", ("design", "link_length"), -math.inf, "design.link_length",
     "a finite number"),
    ("manipulators", ("initial", "position"), [1.0, 2.0, 3.0], "initial.position",
     "an array of 2 items"),
    ("manipulators", ("initial", "position"), [1.0], "initial.position", "an array of 2 items"),
    ("manipulators", ("verification", "offsets", 0, "dx"), "0.1", "verification.offsets[0].dx",
     "a number"),
    ("manipulators", ("verification", "offsets", 0, "manipulator"), 0,
     "verification.offsets[0].manipulator", "a number >= 1"),
    ("manipulators", ("verification", "stages"), 6.0, "verification.stages", "an integer"),
    ("manipulators", ("verification", "accuracy"), "quick", "verification.accuracy",
     "one of: fast, default, precise"),
    ("manipulators", ("expect", "feasible"), "yes", "expect.feasible", "true or false"),
    ("manipulators", ("objective", "max_offset_tolerance"), -1.0,
     "objective.max_offset_tolerance", "a number >= 0"),
    ("manipulators", ("requirements", "lift_off"), "high", "requirements.lift_off", "a number"),
    ("manipulators", ("requirements", "lift_off"), 1.5, "requirements.lift_off", "a number <= 1"),
    ("manipulators", ("design", "mass_ratio"), [10], "design.mass_ratio", "a number (fixed)"),
    ("manipulators", ("scene", "body"), 3, "scene.body", "a table"),
    ("manipulators", ("name",), 7, "name", "a string"),
    ("manipulators", ("scene", "kind"), "conveyor", "scene.kind",
     "one of the installed scenes: compass_gait, manipulators, rimless_wheel, stairs"),
    ("stairs", ("scene", "friction"), -0.5, "scene.friction", "a number >= 0"),
]


@pytest.mark.parametrize("kind, path, value, key, expected", BAD_VALUES,
                         ids=[f"{c[3]}={c[2]!r}" for c in BAD_VALUES])
def test_bad_value_names_key_and_expectation(kind, path, value, key, expected):
    error = error_of(with_value(base(kind), path, value))
    assert error.key == key
    assert error.expected.startswith(expected)
    assert error.file == "bad.toml"
    assert str(error).startswith(f"bad.toml: {key}: expected {expected}")


def test_found_value_is_shown():
    error = error_of(with_value(base("manipulators"), ("scene", "body", "mass"), True))
    assert error.found == "true"


def test_long_found_value_is_truncated():
    error = error_of(with_value(base("manipulators"), ("name",), ["x" * 500] * 50))
    assert len(error.found) <= 60


# --------------------------------------------------------------------------- unknown keys

UNKNOWN_KEYS = [
    ("manipulators", ("nmae",), "nmae", "name"),
    ("manipulators", ("scene", "gravty"), "scene.gravty", "gravity"),
    ("manipulators", ("scene", "body", "mas"), "scene.body.mas", "mass"),
    ("manipulators", ("initial", "velocty"), "initial.velocty", "velocity"),
    ("manipulators", ("design", "alfa"), "design.alfa", "alpha"),
    ("manipulators", ("design", "alpha", "mx"), "design.alpha.mx", "max"),
    ("manipulators", ("objective", "max_offset_tolerence"), "objective.max_offset_tolerence",
     "max_offset_tolerance"),
    ("manipulators", ("requirements", "liftoff"), "requirements.liftoff", "lift_off"),
    ("manipulators", ("verification", "offsets", 0, "ddx"), "verification.offsets[0].ddx", "dx"),
    ("manipulators", ("expect", "feasable"), "expect.feasable", "feasible"),
    ("stairs", ("scene", "ball", "radus"), "scene.ball.radus", "radius"),
    ("stairs", ("design", "restitusion"), "design.restitusion", "restitution"),
    ("stairs", ("requirements", "nose_clearence"), "requirements.nose_clearence",
     "nose_clearance"),
]


@pytest.mark.parametrize("kind, path, key, suggestion", UNKNOWN_KEYS,
                         ids=[c[2] for c in UNKNOWN_KEYS])
def test_unknown_key_suggests_the_close_one(kind, path, key, suggestion):
    error = error_of(with_value(base(kind), path, 0.1))
    assert error.key == key
    assert f"did you mean '{suggestion}'?" in str(error)


def test_unknown_key_without_close_match_lists_known_keys():
    error = error_of(with_value(base("manipulators"), ("scene", "body", "colour"), "red"))
    assert error.key == "scene.body.colour"
    assert "did you mean" not in str(error)
    assert "mass, width, height" in error.expected


@pytest.mark.parametrize("kind, other", [("stairs", "offsets"), ("manipulators", "step_errors")])
def test_an_unknown_verification_key_lists_every_key_the_kind_takes(kind, other):
    error = error_of(with_value(base(kind), ("verification", "colour"), "red"))
    assert error.key == "verification.colour"
    listed = set(error.expected.split("(")[1].rstrip(")").split(", "))
    assert {"stages", "samples", "accuracy"} <= listed and other not in listed


def test_unknown_scene_kind_suggests_the_close_one():
    error = error_of(with_value(base("manipulators"), ("scene", "kind"), "manipulator"))
    assert error.key == "scene.kind"
    assert "did you mean 'manipulators'?" in str(error)


def test_margin_of_the_other_kind_is_unknown():
    error = error_of(with_value(base("stairs"), ("requirements", "lift_off"), 0.1))
    assert error.key == "requirements.lift_off"
    assert "nose_clearance" in error.expected


def test_offsets_in_a_stairs_spec_are_refused():
    error = error_of(with_value(base("stairs"), ("verification", "offsets"), []))
    assert error.key == "verification.offsets"
    assert "step_errors" in error.found


def test_initial_inside_scene_points_to_the_top_level_table():
    error = error_of(with_value(base("stairs"), ("scene", "initial"), {"drop_height": 1.0}))
    assert error.key == "scene.initial"
    assert "top-level [initial]" in error.found


def test_key_with_a_dot_is_quoted_in_the_path():
    error = error_of(with_value(base("stairs"), ("scene", "ball.radius"), 0.1))
    assert error.key == 'scene."ball.radius"'


# ------------------------------------------------------------------- missing and cross-field

MISSING = [
    ("manipulators", ("scene",), "scene", "a [scene] table"),
    ("manipulators", ("scene", "kind"), "scene.kind",
     "one of the installed scenes: compass_gait, manipulators, rimless_wheel, stairs"),
    ("manipulators", ("scene", "body"), "scene.body", "a table"),
    ("manipulators", ("scene", "body", "mass"), "scene.body.mass", "a value"),
    ("manipulators", ("initial",), "initial", "an [initial] table"),
    ("manipulators", ("initial", "position"), "initial.position", "a value"),
    ("manipulators", ("design",), "design", "a [design] table"),
    ("manipulators", ("design", "beta"), "design.beta", "this required variable"),
    ("stairs", ("design", "launch_speed"), "design.launch_speed", "this required variable"),
    ("stairs", ("initial", "drop_height"), "initial.drop_height", "a value"),
]


@pytest.mark.parametrize("kind, path, key, expected", MISSING, ids=[c[2] for c in MISSING])
def test_missing_required_key_is_named(kind, path, key, expected):
    error = error_of(without(base(kind), path))
    assert error.key == key
    assert error.expected.startswith(expected)
    assert error.found == "nothing"


def test_bounds_with_min_above_max():
    bounds = {"min": 0.4, "max": 0.1}
    error = error_of(with_value(base("manipulators"), ("design", "alpha"), bounds))
    assert error.key == "design.alpha.min"
    assert "must not exceed max" in error.expected


def test_bounds_with_initial_outside():
    bounds = {"min": 0.1, "max": 0.4, "initial": 0.5}
    error = error_of(with_value(base("manipulators"), ("design", "alpha"), bounds))
    assert error.key == "design.alpha.initial"


def test_friction_with_a_point_ball_blames_friction():
    error = error_of(with_value(base("stairs"), ("scene", "ball", "radius"), 0.0))
    assert error.key == "scene.friction"
    assert "point ball" in error.expected


def test_repeated_offset_manipulator():
    offsets = [{"manipulator": 2}, {"manipulator": 2, "dx": 0.1}]
    error = error_of(with_value(base("manipulators"), ("verification", "offsets"), offsets))
    assert error.key == "verification.offsets[1].manipulator"


def test_spec_that_is_not_a_table():
    assert error_of([1, 2]).key == ""


# --------------------------------------------------------------------------- files

def write(tmp_path: Path, content: str | bytes) -> Path:
    path = tmp_path / "spec.toml"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    return path


def load_error(path: Path) -> SpecError:
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert info.value.file == str(path)
    return info.value


def test_valid_file_loads(tmp_path):
    assert load_spec(write(tmp_path, STAIRS)).kind == "stairs"


def test_missing_file(tmp_path):
    assert load_error(tmp_path / "nope.toml").found == "no such file"


def test_directory(tmp_path):
    assert load_error(tmp_path).found == "a directory"


def test_named_pipe_is_refused_not_waited_on(tmp_path):
    import os

    os.mkfifo(tmp_path / "spec.toml")  # opening it would wait for a writer that never comes
    assert load_error(tmp_path / "spec.toml").found == "a named pipe"


def test_an_integer_too_long_to_read_is_named_as_such(tmp_path):
    error = load_error(write(tmp_path, "[scene]\ngravity = 1" + "0" * 5000 + "\n"))
    assert (error.expected, error.found) == ("valid TOML", "an integer of more than 4300 digits")


def test_empty_file(tmp_path):
    error = load_error(write(tmp_path, ""))
    assert (error.key, error.found) == ("scene", "an empty spec")


def test_binary_file(tmp_path):
    error = load_error(write(tmp_path, bytes(range(256)) * 4))
    assert error.expected == "TOML text" and "binary" in error.found


def test_invalid_utf8(tmp_path):
    error = load_error(write(tmp_path, b'name = "caf\xe9"\n'))
    assert error.expected == "UTF-8 text" and "0xe9" in error.found


def test_toml_syntax_error_gives_line_and_column(tmp_path):
    error = load_error(write(tmp_path, '[scene]\nkind = "stairs"\ngravity = = 9.81\n'))
    assert error.expected == "valid TOML"
    assert "line 3" in error.found


@pytest.mark.parametrize("literal", ["nan", "inf", "-inf", "+nan"])
def test_toml_nan_and_inf_literals_are_refused(tmp_path, literal):
    error = load_error(write(tmp_path, STAIRS.replace("drop_height = 1.0",
                                                      f"drop_height = {literal}")))
    assert (error.key, error.expected) == ("initial.drop_height", "a finite number")


def test_utf8_byte_order_mark_is_accepted(tmp_path):
    assert load_spec(write(tmp_path, "\ufeff" + STAIRS)).kind == "stairs"


@pytest.mark.parametrize("value", ["[" * 20000 + "]" * 20000, "{a = " * 5000 + "1" + "}" * 5000])
def test_deeply_nested_toml_is_refused(tmp_path, value):
    error = load_error(write(tmp_path, f"name = {value}\n"))
    assert error.key == ""


def test_oversized_file_is_refused_unread(tmp_path):
    error = load_error(write(tmp_path, b"#" * (8 * 2**20 + 1)))
    assert error.found == "a larger file"


def test_huge_integer_is_refused(tmp_path):
    load_error(write(tmp_path, "name = " + "9" * 5000 + "\n"))


def test_deeply_nested_value_in_parsed_data():
    deep: object = 1.0
    for _ in range(100_000):
        deep = [deep]
    error = error_of(with_value(base("manipulators"), ("initial", "position"), deep))
    assert error.key == "initial.position[0]"


def test_long_array_is_validated():
    offsets = [{"manipulator": i, "dx": 0.001} for i in range(1, 100_001)]
    data = with_value(base("manipulators"), ("verification", "stages"), 100_000)
    data = with_value(data, ("design", "alpha"), 0.2)  # a fixed design: rows up to 100 000
    spec = parse_spec(with_value(data, ("verification", "offsets"), offsets))
    assert len(spec.verification.offsets) == 100_000


@pytest.mark.parametrize("kind, table, stages, value, key, expected", [
    # the row keeps every stage's record; more would not fit in memory (docs/spec.md)
    ("manipulators", {}, 100_001, None, "verification.stages", "an integer <= 100000"),
    # an offset or step error on a stage that is not run
    ("manipulators", {"offsets": [{"manipulator": 7}]}, 6, None,
     "verification.offsets[0].manipulator", "an integer <= verification.stages (6)"),
    ("stairs", {"step_errors": [{"step": 21}]}, 20, None,
     "verification.step_errors[0].step", "an integer <= verification.stages (20)"),
    # an NLP with rows for every bounce: free variables limit the bounces, a fixed design not
    ("stairs", {}, 201, {"min": 1.0, "max": 3.0}, "verification.stages",
     "an integer <= 200 when the design has free variables"),
    # an optimised row (alpha free) is verified at every corner of its box: at most 10 000
    ("manipulators", {}, 10_001, None, "verification.stages",
     "an integer <= 10000 when the design has free variables"),
])
def test_stages_limit_what_is_run_and_optimised(kind, table, stages, value, key, expected):
    data = with_value(base(kind), ("verification", "stages"), stages)
    for name, item in table.items():
        data = with_value(data, ("verification", name), item)
    if value is not None:
        data = with_value(data, ("design", "launch_speed"), value)
    with pytest.raises(SpecError) as error:
        parse_spec(data, "s.toml")
    assert error.value.key == key and error.value.expected.startswith(expected)


def test_a_fixed_stairs_design_may_be_simulated_for_many_bounces():
    data = with_value(base("stairs"), ("verification", "stages"), 10_000_000)
    assert parse_spec(data, "s.toml").verification.stages == 10_000_000


# --------------------------------------------------------------------------- property

def all_paths(node, prefix=()):
    """Every key path in a spec: dict keys and list indices."""
    yield prefix
    items = node.items() if isinstance(node, dict) else (
        enumerate(node) if isinstance(node, list) else ())
    for key, child in items:
        yield from all_paths(child, (*prefix, key))


# Specs that use every key (so that garbage can land on each one).
FULL = {
    "manipulators": MANIPULATORS.replace("[scene]\n", """
name = "full"
description = "every key"
[scene]
gravity = 9.81
""", 1).replace("width = 1.6\n", """width = 1.6
thickness = 0.05
friction = 0.8
restitution = 0.0
front_stop = 1.5
""").replace("mass_ratio = 10\n", """mass_ratio = 10
first_pivot_x = {min = -0.1, max = 0.1}
first_pivot_y = 0.0
""").replace("[expect]\n", """stages = 3
accuracy = "fast"
samples = 0
[expect]
verified = true
min_objective = 0.0
min_tolerance = 0.0
min_margin = 0.0
"""),
    "stairs": STAIRS.replace("drop_height = 1.0\n", """drop_height = 1.0
spin = 0.5
""").replace("launch_speed = 3.0\n", """launch_speed = 3.0
rise = 0.3
tread = {min = 1.0, max = 2.0, initial = 1.5}
landing_offset = 0.7
[objective]
max_min_margin = 1
min_drop = 0.5
[requirements]
nose_clearance = 0.01
"""),
}
KEY_NAMES = sorted({str(p[-1]) for data in map(tomllib.loads, FULL.values())
                    for p in all_paths(data) if p})
keys = st.sampled_from(KEY_NAMES) | st.text(max_size=8)
garbage = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=12),
    lambda children: st.lists(children, max_size=4)
    | st.dictionaries(keys, children, max_size=4),
    max_leaves=12,
)
PATHS = [(kind, path) for kind, text in FULL.items() for path in all_paths(tomllib.loads(text))
         if path]


@pytest.mark.parametrize("kind", FULL)
def test_full_spec_for_the_property_test_is_valid(kind):
    spec = parse_spec(tomllib.loads(FULL[kind]), "full.toml")
    assert spec.kind == kind and spec.free_variables


@settings(max_examples=500, deadline=None)
@given(where=st.sampled_from(PATHS), value=garbage, new_key=st.booleans(), key=keys)
def test_garbage_anywhere_gives_a_spec_or_a_spec_error(where, value, new_key, key):
    kind, path = where
    data = tomllib.loads(FULL[kind])
    if new_key:
        parent = data
        for part in path:
            parent = parent[part]
        if isinstance(parent, dict):
            path = (*path, key)
    try:
        result = parse_spec(with_value(data, path, value), "garbage.toml")
    except SpecError as error:
        assert error.file == "garbage.toml" and str(error)
    else:
        assert isinstance(result, Spec)


# --------------------------------------------------------------------------- a scene's own lists

@checked(frozen=True, config=CONFIG)
class Tilt:
    """An item of a per-stage list a scene could declare: one stage's tilt (rad)."""

    stage: Annotated[int, Strict(), Field(ge=1)]
    angle: Number = 0.0


@pytest.fixture
def tilting(monkeypatch):
    """The stairs scene with a second per-stage list, "tilts", declared before its own."""
    scene = plugin.scene_kind("stairs")
    lists = {"tilts": plugin.StageList(Tilt, "stage"), **scene.stage_lists()}
    monkeypatch.setattr(type(scene), "stage_lists", lambda self: lists)
    return base("stairs")


def test_a_scene_s_own_per_stage_list_is_read_from_its_key(tilting):
    tilts = [{"stage": 2, "angle": 0.01}, {"stage": 1}]
    spec = parse_spec(with_value(tilting, ("verification", "tilts"), tilts))
    assert spec.verification.stage_list("tilts") == (Tilt(2, 0.01), Tilt(1, 0.0))
    assert spec.verification.tilts == spec.verification.stage_list("tilts")
    assert [e.step for e in spec.verification.stage_list("step_errors")] == [3]
    assert spec.verification.stage_list("offsets") == () and spec.verification.has_stage_items
    untouched = parse_spec(tilting).verification
    assert untouched.stage_list("tilts") == () and untouched.stage_list("step_errors")


@pytest.mark.parametrize("tilts, key, expected", [
    ([{"stage": 2}, {"stage": 2}], "verification.tilts[1].stage",
     "a stage not listed before in verification.tilts"),
    ([{"stage": 7}], "verification.tilts[0].stage", "an integer <= verification.stages (6)"),
    ([{"stage": 0}], "verification.tilts[0].stage", "a number >= 1"),
    ([{"stage": 1, "angel": 0.1}], "verification.tilts[0].angel", "a key of verification.tilts[0] "
     "(stage, angle)"),
    ([{"angle": 0.1}], "verification.tilts[0].stage", "a value (this key is required)"),
    (0.1, "verification.tilts", "an array"),
])
def test_a_scene_s_own_per_stage_list_is_checked_like_every_other(tilting, tilts, key, expected):
    data = with_value(with_value(tilting, ("verification", "stages"), 6), ("verification", "tilts"),
                      tilts)
    error = error_of(data)
    assert (error.key, error.expected) == (key, expected)


def test_the_scene_s_lists_are_the_keys_verification_takes_in_their_place(tilting):
    error = error_of(with_value(tilting, ("verification", "tilt"), []))
    assert error.key == "verification.tilt"
    assert error.expected == "a key of verification (stages, accuracy, samples, tilts, step_errors)"
