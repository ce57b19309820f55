"""`[verification] step_errors` of the walkers: a slope error given for one step of a ramp moves
that step's chord alone (the rimless wheel: the hub's angle at the impact grows by the error at
that step only, and the stance before it keeps the pendulum's energy), errors of the other
ground are refused in words, and the compass gait takes `slope` and refuses `rise`."""

import math
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ERROR = 0.01  # rad, the slope error at step 2


def _spec(tmp_path, problem, item):
    text = (ROOT / "problems" / problem).read_text()
    assert "\n[verification]\n" in text
    path = tmp_path / problem
    path.write_text(text.replace("\n[verification]\n",
                                 f"\n[verification]\nstep_errors = [{item}]\n", 1))
    return path


def _run(*args):
    return subprocess.run([sys.executable, "-m", "pdm_design", *args], capture_output=True,
                          text=True, cwd=ROOT)


def _impacts(path):
    import json

    done = _run("simulate", str(path), "--format", "json")
    assert done.returncode == 0, done.stderr
    return [e for e in json.loads(done.stdout)["events"] if e["kind"] == "impact"]


def test_a_wheels_slope_error_moves_its_own_step_and_keeps_the_pendulums_energy(tmp_path):
    plain = _impacts(ROOT / "problems" / "rimless_wheel_ramp.toml")
    erred = _impacts(_spec(tmp_path, "rimless_wheel_ramp.toml", f"{{step = 2, slope = {ERROR}}}"))
    assert erred[0] == plain[0]
    for k, shift in ((1, ERROR), (2, 0.0), (3, 0.0)):  # the angle at impact k + 1
        assert erred[k]["before"]["phi"] == pytest_approx(plain[k]["before"]["phi"] + shift)
    # stance 2, from impact 1 to impact 2, keeps (1/2) (l^2 + k^2) w^2 + g l cos(phi): the centre
    # of mass at the hub, k^2 = (M k_h^2 + S l^2 / 3) / (M + S) with S the spokes' mass
    spec = tomllib.loads((ROOT / "problems" / "rimless_wheel_ramp.toml").read_text())
    wheel, design = spec["scene"]["wheel"], spec["design"]
    hub, spokes, leg = wheel["mass"], design["spokes"] * wheel["spoke_mass"], design["leg_length"]
    k2 = (hub * wheel["gyration"] ** 2 + spokes * leg**2 / 3) / (hub + spokes)
    start, end = erred[0]["after"], erred[1]["before"]
    energy = [0.5 * (leg**2 + k2) * e["omega"] ** 2 + spec["scene"]["gravity"] * leg
              * math.cos(e["phi"]) for e in (start, end)]
    assert energy[1] == pytest_approx(energy[0], rel=1e-9)


def pytest_approx(value, rel=1e-12):
    import pytest

    return pytest.approx(value, rel=rel, abs=1e-12)


def test_a_wheel_refuses_the_other_grounds_errors(tmp_path):
    for problem, item, words in (
            ("rimless_wheel_stairs.toml", "{step = 2, slope = 0.01}", "take rise and tread"),
            ("rimless_wheel_ramp.toml", "{step = 3, rise = 0.01}", "take slope errors only")):
        done = _run("simulate", str(_spec(tmp_path, problem, item)))
        assert done.returncode == 1 and words in done.stderr, done.stderr
        assert "Traceback" not in done.stderr


def test_the_compass_gait_takes_a_slope_error_and_refuses_a_rise(tmp_path):
    plain = _run("simulate", str(ROOT / "problems" / "compass_gait_ramp.toml"), "--format", "json")
    erred = _run("simulate", str(_spec(tmp_path, "compass_gait_ramp.toml",
                                       "{step = 2, slope = 0.01}")), "--format", "json")
    assert plain.returncode == erred.returncode == 0
    assert plain.stdout != erred.stdout
    rise = _spec(tmp_path, "compass_gait_ramp.toml", "{step = 2, rise = 0.01}")
    done = _run("simulate", str(rise))
    assert done.returncode == 2 and "step_errors[0].rise" in done.stderr, done.stderr
