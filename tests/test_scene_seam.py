"""The seam between the shared layers and the scenes (docs/scenes.md): the shared code never
asks which scene it has, scenes are found through entry points, and a command imports only the
scene its spec names."""

from __future__ import annotations

import io
import json
import re
import subprocess
import sys
import tokenize
from pathlib import Path

import pytest

from pdm_design import plugin

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "pdm_design"
PROBLEMS = ROOT / "problems"
SHARED = sorted(p for p in PACKAGE.rglob("*.py") if "scenes" not in p.relative_to(PACKAGE).parts
                or p.relative_to(PACKAGE).parts[:2] == ("scenes", "common.py")
                or p.relative_to(PACKAGE).parts == ("scenes", "__init__.py"))
SCENE_IMPORT = re.compile(r"^\s*(from|import)\s+(pdm_design\.|\.+)scenes\.(?!common\b)\w+")


def _scene_names() -> set[str]:
    """The installed kinds and the names of their scene and design dataclasses."""
    names = set(plugin.kinds())
    for kind in plugin.kinds():
        scene = plugin.scene_kind(kind)
        names |= {scene.scene_class().__name__, scene.design_class().__name__}
    return names


def _naming_lines(path: Path, names: set[str]) -> list[str]:
    text = path.read_text()
    found = []
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        literal = token.type == tokenize.STRING and token.string.strip("'\"rbfu") in names
        if literal or (token.type == tokenize.NAME and token.string in names):
            found.append(f"{path.relative_to(ROOT)}:{token.start[0]}: {token.line.strip()}")
    for number, line in enumerate(text.splitlines(), 1):
        if SCENE_IMPORT.match(line):
            found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    return found


def test_the_shared_layers_name_no_scene_and_import_no_scene_package():
    names = _scene_names()
    assert {"stairs", "manipulators", "StairsScene"} <= names  # the check sees the scenes
    found = [line for path in SHARED for line in _naming_lines(path, names)]
    assert not found, "shared modules that name a scene:\n" + "\n".join(found)


# the words of the scenes that ship (their kinds, parts and motions), case-insensitive
SCENE_WORDS = re.compile(r"manipulator|stair|rimless|compass|wheel|gait|walker|palm|bounce|spoke"
                         r"|ball", re.IGNORECASE)


def _speaking_lines(paths) -> list[str]:
    return [f"{path.relative_to(ROOT)}:{number}: {line.strip()}" for path in paths
            for number, line in enumerate(path.read_text().splitlines(), 1)
            if SCENE_WORDS.search(line)]


def test_no_line_of_the_shared_layer_speaks_a_scene_s_words():
    # code, comments and docstrings alike: what a scene knows reaches the shared layer through
    # its Scene object (its per-stage lists, its random streams' keys, ...)
    shared = sorted(p for p in PACKAGE.rglob("*.py")
                    if p.relative_to(PACKAGE).parts[0] != "scenes")
    assert len(shared) > 50 and _speaking_lines(PACKAGE.glob("scenes/*/plugin.py"))
    found = _speaking_lines(shared)
    assert not found, "shared lines that speak of a scene:\n" + "\n".join(found)


def test_every_scene_is_an_entry_point_that_gives_its_own_kind():
    assert {"stairs", "manipulators"} <= set(plugin.kinds())
    for kind in plugin.kinds():
        scene = plugin.scene_kind(kind)
        assert isinstance(scene, plugin.Scene) and scene.kind == kind
        assert scene is plugin.scene_kind(kind)  # loaded once


def test_an_unknown_kind_is_refused_naming_the_installed_ones():
    with pytest.raises(plugin.SceneUnavailable, match="installed: " + ", ".join(plugin.kinds())):
        plugin.scene_kind("conveyor")


def _modules_after(code: str) -> set[str]:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys, json\n"
                          "print(json.dumps(sorted(sys.modules)))"],
                         capture_output=True, text=True, check=True, cwd=ROOT)
    return set(json.loads(out.stdout.splitlines()[-1]))


def test_help_imports_no_numerics_and_no_scene():
    loaded = _modules_after("import pdm_design.cli as c\ntry:\n    c.main(['--help'])\n"
                            "except SystemExit:\n    pass")
    heavy = {m for m in loaded if m.split(".")[0] in ("numpy", "casadi", "matplotlib", "scipy")}
    assert not heavy
    assert not {m for m in loaded if m.startswith("pdm_design.scenes.") and
                m != "pdm_design.scenes.common"}


@pytest.mark.parametrize("spec, other", [("paper_stairs_frictionless.toml", "manipulators"),
                                         ("paper_manipulators.toml", "stairs")])
def test_a_command_imports_only_the_scene_its_spec_names(spec, other):
    loaded = _modules_after("from pdm_design.api import design\nfrom pdm_design.spec import "
                            f"load_spec\ndesign(load_spec({str(PROBLEMS / spec)!r}))")
    assert not {m for m in loaded if m.startswith(f"pdm_design.scenes.{other}")}


def test_the_cli_refuses_an_unknown_kind_with_exit_2(tmp_path):
    spec = tmp_path / "conveyor.toml"
    spec.write_text('[scene]\nkind = "conveyr"\n[initial]\n[design]\n')
    out = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(spec)],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 2
    assert "scene.kind" in out.stderr and ", ".join(plugin.kinds()) in out.stderr
    assert "Traceback" not in out.stderr
