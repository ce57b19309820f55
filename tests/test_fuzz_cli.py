"""Fuzz `pdm-design optimize` with whole malformed spec files (item 4 of the speed/accuracy issue).

Every file generated here is broken in one known way: a value of the wrong type, a string where a
number belongs, a huge or non-finite number, deep nesting, an unknown key, a missing required
key, a value out of its range, a truncated line, a duplicated key, an empty file, binary data.
The command must exit with code 2 and print one message that names the file and - where the
fault has a key - the key path as the user wrote it; never a traceback, never anything on
stdout. (tests/test_spec_loader.py has the parse-level property test with garbage at every
key; this one goes through the command line with whole files.)

The representative subset runs by default; `python -m pytest -m slow tests/test_fuzz_cli.py`
runs many more examples.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pdm_design.cli import main

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
# Fixed designs only: a mutation can never start an optimisation.
BASES = {name: tomllib.loads((PROBLEMS / f"{name}.toml").read_text(encoding="utf-8"))
         for name in ("paper_manipulators", "paper_stairs_friction",
                      "paper_stairs_frictionless")}

# Keys without which a spec is incomplete (removing one must be refused, naming it).
REQUIRED = {
    "paper_manipulators": [("scene",), ("scene", "kind"), ("scene", "body"),
                           ("scene", "body", "mass"), ("scene", "body", "width"),
                           ("scene", "body", "height"), ("scene", "palm"),
                           ("scene", "palm", "width"), ("initial",), ("initial", "position"),
                           ("design",), ("design", "alpha"), ("design", "beta"),
                           ("design", "link_length"), ("design", "mass_ratio")],
    "paper_stairs_friction": [("scene",), ("scene", "kind"), ("initial",),
                              ("initial", "drop_height"), ("design",),
                              ("design", "restitution"), ("design", "launch_speed")],
    "paper_stairs_frictionless": [("scene", "kind"), ("initial", "drop_height"),
                                  ("design", "restitution"), ("design", "launch_speed")],
}
# Values outside the documented range of a key (docs/spec.md), by key name.
OUT_OF_RANGE = {
    "mass": [0.0, -1.0], "width": [0.0, -0.4], "height": [-0.2], "thickness": [0.0],
    "friction": [-0.1], "restitution": [1.5, -0.1], "front_stop": [4.0, 0.0],
    "alpha": [2.0, -0.1, math.pi / 2], "beta": [0.0, 1.6], "link_length": [0.0, -2.0],
    "mass_ratio": [0.0, -10.0], "gravity": [0.0, -9.81], "drop_height": [0.0, -1.0],
    "launch_speed": [0.0, -3.0], "radius": [-0.5], "inertia": [-0.035], "stages": [0, -1],
}


# ------------------------------------------------------------------ a small TOML writer

def toml_value(value) -> str:
    """TOML text of a value (inline tables and arrays; strings as JSON-escaped basic strings,
    which TOML reads the same way)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, RawToml):
        return value.text
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(type(value))


def toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


class RawToml:
    """A value written verbatim (dates, literals the writer would not produce)."""

    def __init__(self, text: str):
        self.text = text


def dumps(data: dict) -> str:
    """The spec as TOML with [table] headers, the way people write them."""
    lines: list[str] = []

    def table(node: dict, prefix: tuple):
        scalars = [(k, v) for k, v in node.items() if not isinstance(v, dict)]
        tables = [(k, v) for k, v in node.items() if isinstance(v, dict)]
        if prefix and (scalars or not tables):
            lines.append("[" + ".".join(toml_key(k) for k in prefix) + "]")
        for k, v in scalars:
            lines.append(f"{toml_key(k)} = {toml_value(v)}")
        for k, v in tables:
            table(v, (*prefix, k))

    table(data, ())
    return "\n".join(lines) + "\n"


def key_path(path: tuple) -> str:
    """A key path as the loader prints it: dotted keys, [i] for array items."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def leaves(node, prefix=()):
    """(path, value) of every value that is not a table, and of every table."""
    if isinstance(node, dict):
        if prefix:
            yield prefix, node
        for k, v in node.items():
            yield from leaves(v, (*prefix, k))
    else:
        yield prefix, node


def replaced(data, path, value):
    data = json.loads(json.dumps(data))  # deep copy of plain TOML data
    node = data
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value
    return data


def removed(data, path):
    data = json.loads(json.dumps(data))
    node = data
    for part in path[:-1]:
        node = node[part]
    del node[path[-1]]
    return data


# ------------------------------------------------------------------ malformed files

def wrong_types(value):
    """Values of another type than `value` (never one the loader may coerce)."""
    if isinstance(value, bool):
        return ["yes", 1, 0.0, [True], {"value": True}]
    if isinstance(value, (int, float)):
        return [str(value), f"{value} m", "", True, False, [value], {"value": value},
                RawToml("1979-05-27"), RawToml("07:32:00")]
    if isinstance(value, str):
        return [1, 2.5, True, [value], {"value": value}, RawToml("1979-05-27T07:32:00Z")]
    if isinstance(value, list):
        return [1.0, "1.0, 2.0", True, {"x": 1.0}, [], [1.0], [1.0, 2.0, 3.0], ["a", "b"]]
    return ["table", 1.0, True, [1, 2]]  # a table


@st.composite
def malformed(draw):
    """(file content, key path the message must name, or None for faults without a key)."""
    name = draw(st.sampled_from(sorted(BASES)))
    data = BASES[name]
    kind = draw(st.sampled_from(["wrong_type", "huge", "huge_finite", "non_finite", "deep",
                                 "unknown_key", "missing", "out_of_range", "truncated",
                                 "duplicate", "empty", "binary"]))
    paths = list(leaves(data))
    numbers = [(p, v) for p, v in paths if isinstance(v, (int, float))
               and not isinstance(v, bool)]
    if kind == "wrong_type":
        path, value = draw(st.sampled_from(paths))
        return dumps(replaced(data, path, draw(st.sampled_from(wrong_types(value))))), path
    if kind == "huge":
        path, _ = draw(st.sampled_from(numbers))
        digits = draw(st.integers(min_value=310, max_value=4000))
        sign = draw(st.sampled_from(["", "-"]))
        return dumps(replaced(data, path, RawToml(sign + "9" * digits))), path
    if kind == "huge_finite":  # finite, but beyond every key's range (|x| <= 1e6 at most)
        path, _ = draw(st.sampled_from(numbers))
        value = 10.0 ** draw(st.floats(7, 308)) * draw(st.sampled_from([1.0, -1.0]))
        return dumps(replaced(data, path, value)), path
    if kind == "non_finite":
        path, _ = draw(st.sampled_from(numbers))
        literal = draw(st.sampled_from(["nan", "+nan", "-nan", "inf", "+inf", "-inf", "1e400",
                                        "-1e999"]))
        return dumps(replaced(data, path, RawToml(literal))), path
    if kind == "deep":
        path, value = draw(st.sampled_from(numbers))
        depth = draw(st.integers(min_value=2, max_value=3000))
        if draw(st.booleans()):
            text = "[" * depth + repr(float(value)) + "]" * depth
        else:
            text = "{a = " * depth + repr(float(value)) + "}" * depth
        # beyond the TOML reader's nesting limit the fault is the whole file's (no key to name)
        return dumps(replaced(data, path, RawToml(text))), Deep(path)
    if kind == "unknown_key":
        tables = [p for p, v in paths if isinstance(v, dict)] + [()]
        table = draw(st.sampled_from(tables))
        key = draw(st.from_regex(r"[a-z][a-z_]{0,12}", fullmatch=True))
        node = data
        for part in table:
            node = node[part]
        if key in node or (table == () and key in ("name", "description", "objective",
                                                     "requirements", "verification",
                                                     "expect", "scene", "initial", "design")):
            key += "_x"
        value = draw(st.sampled_from([1.0, "x", True, [1, 2], {"y": 1}]))
        return dumps(replaced(data, (*table, key), value)), (*table, key)
    if kind == "missing":
        path = draw(st.sampled_from(REQUIRED[name]))
        return dumps(removed(data, path)), path
    if kind == "out_of_range":
        choices = [(p, bad) for p, v in numbers if p[-1] in OUT_OF_RANGE
                   for bad in OUT_OF_RANGE[p[-1]]]
        path, bad = draw(st.sampled_from(choices))
        return dumps(replaced(data, path, bad)), path
    if kind == "truncated":
        lines = dumps(data).splitlines()
        assignments = [i for i, line in enumerate(lines) if " = " in line]
        i = draw(st.sampled_from(assignments))
        lines[i] = lines[i][: lines[i].index(" = ") + 3]  # "key = " and nothing after it
        return "\n".join(lines) + "\n", None
    if kind == "duplicate":
        lines = dumps(data).splitlines()
        assignments = [i for i, line in enumerate(lines) if " = " in line]
        i = draw(st.sampled_from(assignments))
        return "\n".join(lines[: i + 1] + [lines[i]] + lines[i + 1:]) + "\n", None
    if kind == "empty":
        return draw(st.sampled_from(["", "\n\n", "   \t\n", "# only a comment\n",
                                     "\ufeff"])), ("scene",)
    noise = draw(st.binary(min_size=1, max_size=256))
    return b"\x00" + noise + dumps(data).encode(), None


class Deep(tuple):
    """The key of a deeply nested value, or no key if the file is refused as too deep."""


def run_optimize(path: Path):
    result = CliRunner().invoke(main, ["optimize", str(path)])
    return result


def check_refused(tmp_path: Path, content, path):
    spec = tmp_path / "fuzz.toml"
    if isinstance(content, bytes):
        spec.write_bytes(content)
    else:
        spec.write_text(content, encoding="utf-8")
    result = run_optimize(spec)
    message = result.stderr
    assert isinstance(result.exception, SystemExit), f"traceback: {result.exception!r}"
    assert result.exit_code != 0
    assert result.exit_code == 2, f"exit {result.exit_code} for:\n{content!r}\n{message}"
    assert result.stdout == ""
    assert "Traceback" not in message and "internal error" not in message
    assert message.startswith(f"error: {spec}"), message  # names the file first
    assert message.count("\n") == 1  # one line
    if isinstance(path, Deep) and "nested" in message:
        path = None
    if path is not None:
        where = key_path(path)
        named = message[len(f"error: {spec}: "):]
        assert named.startswith(where) and named[len(where)] in ":.[", (
            f"the message should name {where!r}:\n{message}")
    else:
        assert "line" in message or "binary" in message or "nested" in message, message


# ------------------------------------------------------------------ the tests

def test_the_writer_round_trips_every_base_spec(tmp_path):
    for name, data in BASES.items():
        assert tomllib.loads(dumps(data)) == data
        spec = tmp_path / f"{name}.toml"
        spec.write_text(dumps(data), encoding="utf-8")
        assert run_optimize(spec).exit_code == 0, name


FUZZ = settings(max_examples=300, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])


@FUZZ
@given(case=malformed())
def test_malformed_spec_exits_2_naming_file_and_key(tmp_path, case):
    check_refused(tmp_path, *case)


@pytest.mark.slow
@settings(FUZZ, max_examples=3000)
@given(case=malformed())
def test_malformed_spec_exits_2_naming_file_and_key_many(tmp_path, case):
    check_refused(tmp_path, *case)


@pytest.mark.parametrize("name, key, value", [
    ("paper_manipulators", ("scene", "gravity"), 1e300),
    ("paper_manipulators", ("scene", "body", "mass"), 1e-300),
    ("paper_manipulators", ("design", "link_length"), 1e200),
    ("paper_manipulators", ("design", "mass_ratio"), 1e300),
    ("paper_manipulators", ("scene", "body", "width"), 1e-200),
    ("paper_manipulators", ("initial", "velocity"), [1e300, 0.0]),
    ("paper_stairs_frictionless", ("scene", "gravity"), 1e300),
    ("paper_stairs_frictionless", ("initial", "drop_height"), 1e-250),
    ("paper_stairs_friction", ("design", "launch_speed"), 1e250),
    ("paper_stairs_friction", ("scene", "ball", "radius"), 1e300),
])
def test_absurd_magnitudes_are_refused_by_key(tmp_path, name, key, value):
    # Well-formed numbers whose squares overflow (or underflow to 0) cannot describe a device:
    # refused at their key (scenes.common bounds every magnitude to [1e-6, 1e6] in SI).
    content = dumps(replaced(BASES[name], key, value))
    check_refused(tmp_path, content, key if not isinstance(value, list) else (*key, 0))


@pytest.mark.parametrize("content, key", [
    ("", ("scene",)), (b"\x00\x01\x02", None), (b"\xff\xfe" + "[scene]".encode("utf-16-le"), None),
    ("[scene\n", None), ("scene = 1\n", ("scene",)), ("[[scene]]\nkind = 'stairs'\n", ("scene",)),
])
def test_classic_broken_files(tmp_path, content, key):
    check_refused(tmp_path, content, key)


def test_a_plot_that_fails_half_way_leaves_no_file(tmp_path, monkeypatch):
    # `simulate --plot` writes through io.atomic_path: a figure whose writing fails after some
    # bytes leaves neither the target nor a temporary file behind.
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    def broken(self, fname, *args, **kwargs):
        Path(fname).write_bytes(b"\x89PNG half a file")
        raise OSError("disk full")

    monkeypatch.setattr(Figure, "savefig", broken)
    out = tmp_path / "plots" / "run.png"
    result = CliRunner().invoke(main, ["simulate", str(PROBLEMS / "paper_manipulators.toml"),
                                       "--stages", "2", "--plot", str(out)])
    assert result.exit_code != 0
    assert not out.exists()
    assert not any(p.is_file() for p in tmp_path.rglob("*"))
