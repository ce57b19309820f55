"""The accuracy key `carry`: "closed" (the default) or "integrated", which makes the NLP
integrate the carry on real links where the closed form also applies (docs/spec.md)."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import pytest

from pdm_design.accuracy import AccuracyError, accuracy, accuracy_from_text
from pdm_design.formulation import build as build_mod
from pdm_design.scenes.manipulators import formulation as form
from pdm_design.scenes.manipulators import physics as phys
from pdm_design.solve.optimize import optimize
from pdm_design.spec.loader import load_spec

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT / "problems" / "manipulators_real_links.toml"


def test_carry_key_is_read_from_a_table_and_the_command_line():
    assert accuracy("default").carry == "closed"
    got = accuracy({"carry": "integrated"})
    assert got.carry == "integrated" and got.name == "custom" and not got.is_preset
    assert (got.rtol, got.agreement) == (accuracy("default").rtol, accuracy("default").agreement)
    assert accuracy_from_text("base=fast,carry=integrated") == dataclasses.replace(
        accuracy("fast"), name="custom", carry="integrated")
    assert got.settings()["carry"] == "integrated" and "carry integrated" in got.describe()
    with pytest.raises(AccuracyError, match="carry: expected one of: closed, integrated"):
        accuracy({"carry": "rk4"})


def with_carry(carry, objective=None):
    spec = load_spec(REAL)
    acc = accuracy({"carry": carry, "agreement": 1e-6})
    spec = dataclasses.replace(spec, verification=dataclasses.replace(spec.verification,
                                                                      accuracy=acc))
    if objective:
        spec = dataclasses.replace(spec, objective=objective)
    return spec


def test_integrated_carry_is_built_where_the_closed_form_applies_and_agrees_with_it():
    paper = load_spec(ROOT / "problems" / "paper_manipulators.toml")
    real = load_spec(REAL)
    fixed = {}
    for carry in ("closed", "integrated"):  # the paper's design on the real links' scene
        spec = dataclasses.replace(with_carry(carry), design=paper.design,
                                   objective=paper.objective)
        fixed[carry] = form.build(spec)[2]
    design = paper.design_at()
    assert fixed["closed"].steps == 0
    assert fixed["integrated"].steps == phys.carry_steps(1e-6 / 10,
                                                         span=design.alpha + design.beta)
    # the same carry, integrated and closed: v(beta)^2 from the first landing's speed
    v = {}
    for carry, m in fixed.items():
        v[carry] = float(m.carry_v2(m.first_speed(m.fall_speed(0.0)), m.b))
    assert v["integrated"] == pytest.approx(v["closed"], rel=1e-7)
    assert v["integrated"] != v["closed"]  # (two paths, not one)
    assert real.scene == with_carry("closed").scene
    closed = with_carry("closed", {"max_min_margin": 1.0})
    integrated = with_carry("integrated", {"max_min_margin": 1.0})
    # the build cache keeps the two apart, and both optimise to the same design
    build_mod._CACHE.clear()
    a = optimize(closed, starts=2, tol=1e-8, linearise=False, check_samples=0, diagnose=False)
    b = optimize(integrated, starts=2, tol=1e-8, linearise=False, check_samples=0,
                 diagnose=False)
    assert a.success and b.success
    assert len(build_mod._CACHE) >= 2
    for key in ("alpha", "beta"):
        assert b.design[key] == pytest.approx(a.design[key], rel=1e-5, abs=1e-7)


def test_integrated_carry_with_the_robust_objective_is_refused_in_words(tmp_path):
    text = REAL.read_text().replace("[verification]\n",
                                    '[verification]\naccuracy = { carry = "integrated" }\n')
    spec = tmp_path / "robust.toml"
    spec.write_text(text)
    done = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(spec)],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "verification.accuracy.carry" in done.stderr and "closed" in done.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('carry = "integrated"', 'carry = "euler"'))
    done = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(bad)],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 2 and "carry" in done.stderr and "integrated" in done.stderr
