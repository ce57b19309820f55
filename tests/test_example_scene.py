"""A scene from outside pdm-design (examples/pendulum_row), installed as a third party would
install it, works with every command; its optimum is held against the closed form derived here.

The puck (m, restitution e) hits a bob M at rest: r = (m - e M)/(m + M) of its speed stays, the
bob takes G = (1 + e) m/(m + M). Down a ramp that drops h: v_next^2 = r^2 v^2 + 2 g h, so the
periodic speed is v*^2 = 2 g h/(1 - r^2). max_min_margin balances the puck going on,
1 - e M/m, against no bob looping on the orbit, 1 - G^2 v*^2/(4 g l) (the first impact's is
larger at the template's start speed): the optimum is where the two are equal.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from scipy.optimize import brentq

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "pendulum_row"
G = 9.81
M_PUCK, E, DROP, ROD, V0 = 1.0, 0.5, 0.2, 0.5, 2.0  # the template's numbers


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The example installed with pip into a fresh folder (its entry point with it)."""
    target = tmp_path_factory.mktemp("site")
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--disable-pip-version-check", "--target", str(target), str(EXAMPLE)],
                   check=True, capture_output=True)
    return target


def _run(installed, *args, cwd):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (
        str(installed), os.environ.get("PYTHONPATH"))))}
    out = subprocess.run([sys.executable, "-m", "pdm_design", *args], capture_output=True,
                         text=True, env=env, cwd=cwd)
    return out.returncode, out.stdout, out.stderr


def _margins(M):
    r = (M_PUCK - E * M) / (M_PUCK + M)
    gain = (1 + E) * M_PUCK / (M_PUCK + M)
    v2 = 2 * G * DROP / (1 - r * r)
    return 1 - E * M / M_PUCK, 1 - gain**2 * v2 / (4 * G * ROD), r, math.sqrt(v2)


@pytest.fixture(scope="module")
def spec(installed, tmp_path_factory):
    folder = tmp_path_factory.mktemp("spec")
    code, _, err = _run(installed, "init", "pendulum_row", "--out", "row.toml", cwd=folder)
    assert code == 0, err
    return folder / "row.toml"


def test_the_scene_is_unknown_until_installed(tmp_path):
    out = subprocess.run([sys.executable, "-m", "pdm_design", "init", "pendulum_row"],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 2 and "not an installed scene" in out.stderr


def test_optimize_finds_the_balanced_bob_mass(installed, spec):
    code, out, err = _run(installed, "optimize", str(spec), "--format", "json", cwd=spec.parent)
    assert code == 0, err
    answer = json.loads(out)
    best = brentq(lambda M: _margins(M)[0] - _margins(M)[1], 0.1, 1.9, xtol=1e-12)
    forward, no_loop, r, v_star = _margins(best)
    assert answer["design"]["bob_mass"] == pytest.approx(best, rel=1e-6)
    assert answer["margins"]["forward"] == pytest.approx(forward, rel=1e-6)
    assert answer["periodic"]["bob_speed"] == pytest.approx(v_star, rel=1e-6)
    assert answer["periodic"]["contraction"] == pytest.approx(r * r, rel=1e-6)


def test_the_text_report_prints_the_units_the_scene_gives(installed, spec):
    # pdm-design's shared table has none of these quantities: the units are the scene's own
    # (Scene.quantity_units)
    import re

    code, out, err = _run(installed, "optimize", str(spec), cwd=spec.parent)
    assert code == 0, err
    for name, unit in (("bob_mass", "kg"), ("rod_length", "m"), ("pitch", "m"),
                       ("bob_speed", "m/s"), ("contraction", "")):
        found = re.search(rf"^  {name} +(\S+)( \S+)?", out, re.M)
        assert found, (name, out)
        assert (found.group(2) or "").strip() == unit, found.group(0)


def test_simulate_settles_on_the_periodic_speed(installed, spec):
    code, out, err = _run(installed, "simulate", str(spec), "--stages", "40", "--format",
                          "json", cwd=spec.parent)
    assert code == 0, err
    run = json.loads(out)
    best = brentq(lambda M: _margins(M)[0] - _margins(M)[1], 0.1, 1.9, xtol=1e-12)
    speeds = [s["bob_speed_before"] for s in run["stages"]]
    assert run["outcome"]["completed"] and len(speeds) == 40
    assert speeds[-1] == pytest.approx(_margins(best)[3], rel=1e-7)  # r^2 = 0.24 a stage


def test_check_passes_the_expectations(installed, spec):
    code, out, err = _run(installed, "check", str(spec), cwd=spec.parent)
    assert code == 0, out + err


def test_sheet_report_and_table_run_on_the_interface_defaults(installed, spec):
    folder = spec.parent
    for args, made in ((("sheet", str(spec), "--out", "s"), "s/sheet.csv"),
                       (("report", str(spec), "--out", "r"), "r/report.html"),
                       (("table", str(spec), "--sweep", "drop=0.1:0.3:3", "--out", "t"),
                        "t/table.csv")):
        code, _, err = _run(installed, *args, cwd=folder)
        assert code == 0, err
        assert (folder / made).stat().st_size > 0


def test_yield_of_one_toleranced_part_is_the_exact_probability(installed, spec):
    """Every bob's mass drawn normal (sigma = t/3). At the first bob the puck arrives at the
    start speed whatever was built: no bob loops there (gain^2 v0^2 <= 1.5^2 x 4 < 4 g l), so
    a build gets past bob 1 exactly when that bob is neither too heavy for the puck to go on
    (e M_1 >= m) nor without mass (M_1 <= 0): Phi((m/e - M)/sigma) - Phi(-M/sigma). (Later a
    light bob lets the puck speed up until one loops: no closed form there.)"""
    from scipy.stats import norm

    code, out, err = _run(installed, "optimize", str(spec), "--format", "json", cwd=spec.parent)
    M = json.loads(out)["design"]["bob_mass"]
    fixed = spec.parent / "fixed.toml"
    text = spec.read_text().replace("bob_mass = { min = 0.1, max = 1.9, initial = 1.0 }",
                                    f"bob_mass = {M!r}")
    fixed.write_text(text + '\n[tolerances]\nbuilds = 4000\nconfirm = 5\n'
                            'bob_mass = { value = 1.5, applies_to = "each" }\n')
    code, out, err = _run(installed, "yield", str(fixed), "--format", "json", cwd=spec.parent)
    assert code == 0, err
    run = json.loads(out)
    sigma = 0.5
    exact = norm.cdf((M_PUCK / E - M) / sigma) - norm.cdf(-M / sigma)
    assert run["survival_band"]["low"][0] <= exact <= run["survival_band"]["high"][0]
    assert 0.8 < exact < 0.9  # a band that can miss: 4000 builds, about +-1 %
