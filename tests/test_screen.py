"""The screened multistart (solve/screen.py): the critical distance against its closed form,
the rule on a landscape of two basins, and the long row's answer against the plain 8-start
multistart's."""

import importlib
import math
import re
import tomllib
from pathlib import Path
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from pdm_design.solve import screen
from pdm_design.solve.sobol import sobol
from pdm_design.spec.loader import parse_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def test_the_critical_distance_is_mlsls():
    # n = 2: r = (Gamma(2) 4 log N / (pi N))^(1/2); n = 1: Gamma(3/2) = sqrt(pi) / 2
    assert screen.radius(2, 32) == pytest.approx(math.sqrt(4 * math.log(32) / (math.pi * 32)))
    assert screen.radius(1, 32) == pytest.approx(0.5 * 4 * math.log(32) / 32)
    assert screen.radius(0, 32) == math.inf


def _two_basins():
    """A form-like NLP in [0, 1]^2: two wells, the deeper at (0.2, 0.2), the other at
    (0.8, 0.8), 0.85 apart (beyond the critical distance 0.37 of 32 designs)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 0)
    f = -(ca.exp(-ca.sumsqr(x - 0.2) / 0.02) + 0.9 * ca.exp(-ca.sumsqr(x - 0.8) / 0.02))
    return SimpleNamespace(key="two basins", n_design=2, nlp={"x": x, "p": p, "f": f,
                                                              "g": ca.SX(0, 1)},
                           lbx=np.zeros(2), ubx=np.ones(2), lbg=np.zeros(0), ubg=np.zeros(0))


def test_each_basin_gets_a_start_and_a_basin_one_only():
    form = _two_basins()
    sample = [np.array([0.5, 0.5])] + list(sobol(2, 31, 0))  # the guess, then the sample
    chosen = screen.screened(form, np.zeros(0), sample, always=1, starts=8)
    assert np.allclose(chosen[0], [0.5, 0.5])  # the guess always runs, first
    near = [np.linalg.norm(c - 0.2) < np.linalg.norm(c - 0.8) for c in chosen[1:]]
    assert any(near) and not all(near)  # a start in each basin
    # no start with a better sampled design within the critical distance
    values = ca.Function("f", [form.nlp["x"]], [form.nlp["f"]])
    r = screen.radius(2, len(sample))
    for c in chosen[1:]:
        better = [s for s in sample if float(values(s)) < float(values(c))]
        assert all(np.linalg.norm(s - c) > r for s in better)


@pytest.mark.slow  # the eight starts solved besides the screened one: about 11 s
def test_the_screened_answer_is_the_eight_starts_answer(monkeypatch):
    """The long row at 20 stages: the screened multistart (one start here) and the plain one
    (8 starts, none screened) give the same design."""
    screened, plain = _screened_and_plain(monkeypatch,
                                          _spec_at("manipulators_long_row_yield.toml", 20))
    assert plain.stats.starts == 8 and screened.stats.starts < 8
    for name in ("alpha", "beta"):
        assert screened.design[name] == pytest.approx(plain.design[name], abs=1e-7)


def _spec_at(problem: str, stages: int):
    """The problem's spec with its row cut (or grown) to `stages`."""
    text = (PROBLEMS / problem).read_text()
    return parse_spec(tomllib.loads(re.sub(r"(?m)^stages = \d+", f"stages = {stages}", text)))


def _target_spec(stages: int):
    return _spec_at("manipulators_yield_target.toml", stages)


def _screened_and_plain(monkeypatch, spec):
    """The answers of the screened multistart and of the plain one (8 starts, none screened)."""
    module = importlib.import_module("pdm_design.solve.optimize")
    screened = module.optimize(spec)
    monkeypatch.setattr(module, "SAMPLE", 8)
    monkeypatch.setattr(module, "screened",  # every start, each at its own target scale
                        lambda form, p, xs, always, starts: screen.at_target_scales(form, p, xs))
    return screened, module.optimize(spec)


def _target_starts(count):
    """(the 20-stage yield target's NLP, the start vectors of `count` sampled designs)."""
    from pdm_design.formulation import formulate
    from pdm_design.solve.ipopt import start_designs

    spec = _target_spec(20)
    form = formulate(spec)
    names = form.design_names
    guess = {n: spec.design[n].guess for n in names}
    designs = start_designs(names, [spec.design[n].min for n in names],
                            [spec.design[n].max for n in names], guess, count, 0)
    return form, form.defined_starts(designs, guess, form.p_default)


def test_a_yield_targets_score_is_its_largest_scale_meeting_the_target():
    """Each sampled design's score: its nines row (the linearised yield against the target)
    evaluated directly at the score is on its bound, and broken a millionth above it."""
    form, starts = _target_starts(32)
    xs = np.column_stack(starts)
    scales = screen.target_scales(form, form.p_default, xs)
    k, row = form.x_names.index(screen.AUX), screen.target_row(form)
    rows = ca.Function("g", [form.nlp["x"], form.nlp["p"]], [form.nlp["g"]])
    met = 0
    for j, s in enumerate(scales):
        x = xs[:, j].copy()
        x[k] = np.log(s)  # the NLP's variable is log s
        at = float(rows(x, form.p_default)[row])
        if s <= 1.0001e-9:  # held nowhere: broken at the smallest scale
            assert not at >= 0.0
            continue
        met += 1
        x[k] = np.log(s * (1.0 + 1e-6))
        assert at == pytest.approx(0.0, abs=1e-9)
        assert float(rows(x, form.p_default)[row]) < 0.0
    assert met >= 2


@pytest.mark.slow  # the eight starts solved besides the screened one: about 10 s
def test_the_screened_yield_target_is_the_eight_starts_answer(monkeypatch):
    """The yield target at 20 stages: the screened multistart (each sampled design scored at
    its largest scale meeting the target) and the plain one (8 starts) agree."""
    screened, plain = _screened_and_plain(monkeypatch, _target_spec(20))
    assert plain.stats.starts == 8 and screened.stats.starts < 8
    for name in ("alpha", "beta"):
        assert screened.design[name] == pytest.approx(plain.design[name], abs=1e-7)
    allocated = {t["quantity"]: t["value"] for t in plain.tolerances if t["allocated"]}
    assert allocated and {t["quantity"]: t["value"] for t in screened.tolerances
                          if t["allocated"]} == pytest.approx(allocated, rel=1e-7)


def test_the_target_scales_split_among_forked_workers_are_the_same(monkeypatch):
    """at_target_scales splits the designs among the cores (tolerances.parallel.forked_map:
    each forked child inherits the NLP's Functions); each design's root is its own, so the
    scales are the same to the bit as in one process."""
    import os

    from pdm_design.tolerances import parallel

    form, starts = _target_starts(8)
    alone = screen.at_target_scales(form, form.p_default, starts)
    monkeypatch.setattr(parallel, "local_workers", lambda workers=None: 2)
    monkeypatch.setattr(screen, "SPLIT_SECONDS", 0.0)
    split = screen.at_target_scales(form, form.p_default, starts)
    assert all(np.array_equal(a, b) for a, b in zip(alone, split, strict=True))
    # where this process can fork, the halves ran in children
    pids = parallel.forked_map(lambda part: os.getpid(), [0, 1], 2)
    if parallel._context().get_start_method() == "fork":
        assert os.getpid() not in pids
    else:
        assert pids == [os.getpid()] * 2
