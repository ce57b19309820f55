"""The optimize document reports the spec's device-as-built scene keys in `scene_parameters`
(docs/json-schema.md); `scene` stays the kind string of schema pdm-design/optimize/1."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def optimize_json(spec: Path) -> dict:
    done = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(spec),
                           "--format", "json", "--no-verify"],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode in (0, 1), done.stderr
    return json.loads(done.stdout)


def test_real_links_are_reported_as_the_spec_gives_them(tmp_path):
    text = (ROOT / "problems" / "manipulators_real_links.toml").read_text().replace(
        "count = 2 ", "inertia = 0.9\ncount = 2 ").replace(
        "friction_torque = 0.2", "friction_torque = 0.2\ndamping = 0.05").replace(
        "max_offset_tolerance = 1.0", "max_min_margin = 1.0")
    spec = tmp_path / "real.toml"
    spec.write_text(text)
    doc = optimize_json(spec)
    assert doc["schema"] == "pdm-design/optimize/1" and doc["scene"] == "manipulators"
    assert doc["scene_parameters"] == {
        "links": {"mass": 0.5, "inertia": 0.9, "count": 2},
        "pivots": {"friction_torque": 0.2, "damping": 0.05}}
    assert doc["geometry"]["link_inertia"] == 0.9


@pytest.mark.parametrize("problem, expected", [
    ("paper_manipulators.toml", {"links": {"mass": 0.0, "inertia": None, "count": 2},
                                 "pivots": {"friction_torque": 0.0, "damping": 0.0}}),
    ("stairs_design.toml", {}),
])
def test_every_key_is_there_without_links_or_pivots(problem, expected):
    doc = optimize_json(ROOT / "problems" / problem)
    assert doc["scene_parameters"] == expected
    keys = list(doc)
    assert keys.index("scene_parameters") == keys.index("scene") + 1
    assert "`scene_parameters`" in (ROOT / "docs" / "json-schema.md").read_text()
