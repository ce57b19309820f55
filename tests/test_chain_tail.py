"""The chain walked until it settles, its tail in closed form (formulation/chain_tail.py),
against the chain walked to its end: the rows of ChainPieces' mapaccum graph (every call
evaluated) and their union bound summed in numpy, and the graph's own value, gradient and
Hessian (chain_moments.second_order_term with the closed-form tail switched off); and the
optimised long row's Monte Carlo yield against its linearised figure."""

from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.special import ndtr

from pdm_design.formulation import chain_moments as cm
from pdm_design.formulation import chain_tail
from pdm_design.scenes.manipulators.formulation import statistical as manip
from pdm_design.spec import load_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
LONG_ROW = PROBLEMS / "manipulators_long_row_yield.toml"
DESIGNS = [(0.0970212, 0.5144), (0.2173, 0.6747), (0.3, 0.8)]


@pytest.fixture(scope="module")
def row():
    spec = load_spec(LONG_ROW)
    return spec, manip.kept(*manip.sigmas(spec.tolerances))


def _pieces(spec, active, stages):
    chain = manip.Chain(spec.scene, active)
    sizes = (len(manip.DESIGN), sum(active[0]), sum(active[1]))
    pieces = cm.ChainPieces(chain.first, chain.middle, stages, *sizes, last=chain.last)
    if pieces.drift is None:  # a short row is one graph in the NLP; its walk is tested too
        pieces.drift = chain_tail._drift(pieces.step, pieces.shapes)
    return pieces


def _walked_to_the_end(pieces, x, each, lot):
    """(the union bound, the walked rows' g) of the whole chain: the mapaccum graph's rows,
    summed in numpy."""
    g, sd = (np.asarray(v).ravel() for v in pieces.rows_function()(x, each, lot))
    counted = np.asarray(manip.counted(pieces.names)).ravel() > 0.0
    return float(np.sum(ndtr(-g / sd)[counted])), g


@pytest.mark.parametrize("stages", [20, 100, 1000])
@pytest.mark.parametrize("alpha,beta", DESIGNS)
def test_the_settled_tail_is_the_walked_chain(row, stages, alpha, beta):
    spec, (active, each, lot) = row
    pieces = _pieces(spec, active, stages)
    assert list(pieces.drift) == chain_tail.drift_entries(pieces.shapes, (1,))  # o drifts
    x = [alpha, beta, 2.0, 10.0, 0.0, 0.0]
    u = np.array(x + each + lot)
    (g, var), walked = chain_tail.walk(pieces, (pieces.head, pieces.step, pieces.tail), u, 1)
    reference, g_ref = _walked_to_the_end(pieces, x, each, lot)
    counted = np.asarray(manip.counted(pieces.names)).ravel() > 0.0
    bound = float(np.sum(ndtr(-g[0] / np.sqrt(var[0] + cm.VARIANCE_FLOOR))[counted]))
    assert bound == pytest.approx(reference, rel=1e-11)
    assert np.max(np.abs(g[0] - g_ref)) < 1e-12 * max(1.0, np.max(np.abs(g_ref)))
    if stages >= 100:  # the walk stopped early: the tail was not walked
        assert walked < 80


@pytest.mark.parametrize("stages", [20, 1000])
def test_the_term_and_its_derivatives_are_the_graphs(row, stages):
    spec, (active, each, lot) = row
    v = ca.SX.sym("v", 2)
    args = [ca.vertcat(v[0], v[1], 2.0, 10.0, 0.0, 0.0), ca.DM(each), ca.DM(lot)]
    terms = []
    for shortened in (True, False):
        pieces = _pieces(spec, active, stages)
        if not shortened:
            pieces.drift = None  # the mapaccum graph of every call (the old path)
        counted = manip.counted(pieces.names)
        term = cm.second_order_term(pieces, lambda g, sd, c=counted: cm.failure_bound(g, sd, c),
                                    args)
        terms.append(ca.Function("t", [v], [term, ca.gradient(term, v), ca.hessian(term, v)[0]]))
    for point in ([0.0970212, 0.5144], [0.2173, 0.6747]):
        new, old = ([np.asarray(o) for o in t(point)] for t in terms)
        for a, b, tol in zip(new, old, (1e-11, 1e-8, 1e-7), strict=True):
            assert np.allclose(a, b, rtol=tol, atol=tol * np.max(np.abs(b))), (a, b)


def test_a_row_that_never_settles_is_walked_to_its_end(row, monkeypatch):
    """With the settling tolerances below 0 no stop is allowed: the walk is the whole row, and
    it is the graph's row for row (rounding only)."""
    monkeypatch.setattr(chain_tail, "ROUNDING", -1.0)
    spec, (active, each, lot) = row
    pieces = _pieces(spec, active, 30)
    x = [0.0970212, 0.5144, 2.0, 10.0, 0.0, 0.0]
    (g, _), walked = chain_tail.walk(pieces, (pieces.head, pieces.step, pieces.tail),
                                     np.array(x + each + lot), 1, tol=-1.0)
    assert walked == 29
    assert np.max(np.abs(g[0] - _walked_to_the_end(pieces, x, each, lot)[1])) < 1e-13


def test_the_optimised_rows_monte_carlo_yield_is_its_linearised_one():
    """`optimize` of the long row (100 stages), then the `yield` command's engine on 2 000
    builds: the linearised yield of the answer lies in the Monte Carlo interval."""
    from pdm_design.solve import optimize
    from pdm_design.tolerances.yield_ import yield_of

    spec = load_spec(LONG_ROW)
    result = optimize(spec)
    design = spec.design_at(result.design)
    linear = manip.linearised_yield(spec.scene, design, spec.tolerances, 100)["yield"]
    assert linear == pytest.approx(1.0 - 10.0 ** -result.objectives["max_yield"], rel=1e-9)
    mc = yield_of(spec.scene, design, spec.tolerances, builds=2000,
                  stages=spec.verification.stages, seed=0, confirm=0, scales=(),
                  sensitivity_samples=0)
    assert mc.ci_low <= linear <= mc.ci_high
