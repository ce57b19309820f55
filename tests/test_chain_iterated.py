"""The iterated chain (chain_moments.ChainPieces: the stage recursion under mapaccum, only the
deviations of a sigma other than 0) against an independent second method: the recursion
unrolled stage by stage as plain CasADi expressions (`_unrolled` below, the moments written
out as in the module docstring of formulation/chain_moments.py), on a few designs and short
rows of both scenes; and the NLP's term (chain_moments.second_order_term: value, gradient and
Hessian carried as Taylor coefficients) against exact AD of the unrolled expression."""

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from pdm_design.formulation import chain_moments as cm
from pdm_design.scenes.manipulators.formulation import statistical as manip
from pdm_design.scenes.stairs.formulation import statistical as stairs
from pdm_design.spec import load_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def _unrolled(first, stage, x, calls, sigma_each, sigma_lot, neighbours=False):
    """(g, sd[, previous, cross]): the chain written out call by call (the reference)."""
    Se = ca.diag(ca.vertcat(*[s**2 for s in sigma_each]))
    Sl = ca.diag(ca.vertcat(*[s**2 for s in sigma_lot]))
    ne = Se.shape[0]
    fn, names = first
    ns = fn.size1_in(1)
    R, C, L = ca.DM.zeros(ns, ns), ca.DM.zeros(ns, ne), ca.DM.zeros(ns, Sl.shape[0])
    g, Gz, q, s, Fz, Q = fn(x, ca.DM.zeros(ns), cm._covariance(R, C, L, Se, Sl))
    gs, vs, count = [g], [cm._variance(Gz, R, C, L, Se, Sl) + q], len(names)
    previous, cross, before = [-1] * len(names), [ca.DM.zeros(len(names))], None
    R, C, L = Q, Fz[:, ns:ns + ne], Fz[:, ns + 2 * ne:]
    for k in range(calls):
        here = stage(k)
        fn, names = here
        Sz = cm._covariance(R, C, L, Se, Sl)
        out = fn(x, s, Sz)
        g, Gz, q = out[:3]
        if before is not None and before[0] is here:
            previous += list(range(count - len(names), count))
            cross.append(cm._successive(before[1:], Gz, ns, ne))
        else:
            previous += [-1] * len(names)
            cross.append(ca.DM.zeros(len(names)))
        gs.append(g)
        vs.append(cm._variance(Gz, R, C, L, Se, Sl) + q)
        count += len(names)
        if k < calls - 1:
            s, Fz, Q = out[3:]
            before = (here, Gz, Sz, Fz)
            A, Bk = Fz[:, :ns], Fz[:, ns:ns + ne]
            Bk1, BL = Fz[:, ns + ne:ns + 2 * ne], Fz[:, ns + 2 * ne:]
            AC = A @ C + Bk
            R = A @ R @ A.T + AC @ Se @ AC.T + Q
            C, L = Bk1, A @ L + BL
    g, sd = ca.vertcat(*gs), ca.sqrt(ca.vertcat(*vs) + cm.VARIANCE_FLOOR)
    return (g, sd, np.array(previous), ca.vertcat(*cross)) if neighbours else (g, sd)


@pytest.fixture(scope="module")
def row():
    spec = load_spec(PROBLEMS / "manipulators_long_row_yield.toml")
    return spec.scene, manip.sigmas(spec.tolerances)


def _manip_reference(scene, x, stages, each, lot):
    chain = manip.Chain(scene)
    return _unrolled(chain.first, lambda k: chain.last if k == stages - 1 else chain.middle,
                     x, stages, each, lot)


DESIGNS = [(0.2, 0.6), (0.0970212, 0.5144), (0.45, 1.0)]


@pytest.mark.parametrize("stages", [1, 2, 3, 6])
@pytest.mark.parametrize("alpha,beta", DESIGNS)
def test_the_iterated_manipulators_chain_is_the_unrolled_one(row, stages, alpha, beta):
    scene, (each, lot) = row
    x = manip.design_vector({"alpha": alpha, "beta": beta, "link_length": 2.0,
                             "mass_ratio": 10.0})
    g0, sd0 = (np.asarray(v).ravel() for v in _manip_reference(scene, x, stages, each, lot))
    active, kept_each, kept_lot = manip.kept(each, lot)
    assert sum(active[1]) < len(lot)  # the lots of sigma 0 are left out of the iterated one
    fn, names = manip.rows_function(scene, stages, active)
    g1, sd1 = (np.asarray(v).ravel() for v in fn(x, kept_each, kept_lot))
    assert len(names) == g0.size
    np.testing.assert_allclose(g1, g0, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(sd1, sd0, rtol=1e-12, atol=1e-14)


def test_every_deviation_kept_gives_the_same_rows(row):
    # a lot sigma set on every lot quantity: nothing left out, the same numbers
    scene, (each, lot) = row
    lot = [0.01 * (i + 1) for i in range(len(lot))]
    x = manip.design_vector({"alpha": 0.2, "beta": 0.6, "link_length": 2.0,
                             "mass_ratio": 10.0})
    g0, sd0 = (np.asarray(v).ravel() for v in _manip_reference(scene, x, 4, each, lot))
    active, kept_each, kept_lot = manip.kept(each, lot)
    g1, sd1 = (np.asarray(v).ravel()
               for v in manip.rows_function(scene, 4, active)[0](x, kept_each, kept_lot))
    np.testing.assert_allclose(g1, g0, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(sd1, sd0, rtol=1e-12, atol=1e-14)


def test_the_nlp_term_has_the_unrolled_expressions_value_gradient_and_hessian(row):
    # union bound of 5 palms in (alpha, beta) and a yield target's scale s on the pivots:
    # the Taylor-carried node against exact AD of the unrolled SX expression
    scene, (each, lot) = row
    a, b, s = ca.SX.sym("a"), ca.SX.sym("b"), ca.SX.sym("s")
    values = {"alpha": a, "beta": b, "link_length": 2.0, "mass_ratio": 10.0}
    each = [each[0] * s, each[1] * s, *each[2:]]
    v = ca.vertcat(a, b, s)
    term = manip.union_bound(scene, values, 5, each, lot)
    g, sd = _manip_reference(scene, manip.design_vector(values), 5, each, lot)
    names = manip.rows_function(scene, 5, manip.kept(each, lot)[0])[1]
    reference = manip.failure_bound(g, sd, names)
    for expr in (term, reference):
        assert ca.depends_on(expr, v)
    new, old = (ca.Function("f", [v], [e, ca.gradient(e, v), ca.hessian(e, v)[0]])
                for e in (term, reference))
    for point in ([0.2, 0.6, 1.0], [0.0970212, 0.5144, 1.3], [0.3, 0.8, 0.7]):
        for got, want in zip(new(point), old(point), strict=True):
            np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-9,
                                       atol=1e-13)


@pytest.mark.parametrize("stages", [1, 2, 4])
def test_the_iterated_stairs_chain_and_its_cross_terms_are_the_unrolled_ones(stages):
    spec = load_spec(PROBLEMS / "stairs_yield.toml")
    scene = spec.scene
    each, lot = stairs.sigmas(spec.tolerances)
    values = stairs.design_values(scene, spec.design_at())
    x = ca.vertcat(*[values[n] for n in stairs.DESIGN])
    chain = stairs.StairsChain(scene)
    g0, sd0, prev0, cross0 = _unrolled(chain.first, lambda k: chain.middle, x, stages - 1,
                                       each, lot, neighbours=True)
    fn, names, previous, nines = stairs.rows_function(scene, stages)
    g1, sd1, cross1 = fn(x, each, lot)
    np.testing.assert_array_equal(previous, prev0)
    for got, want in ((g1, g0), (sd1, sd0), (cross1, cross0)):
        np.testing.assert_allclose(np.asarray(got).ravel(), np.asarray(want).ravel(),
                                   rtol=1e-12, atol=1e-14)
    # the NLP's term at the design, numbers in: the nines of the unrolled rows
    term = stairs.yield_term(scene, values, spec.tolerances, stages)
    want = nines(g0, sd0, cross0)
    assert float(term) == pytest.approx(float(want), rel=1e-12)
