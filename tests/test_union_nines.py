"""The union bound's nines in logarithms (formulation/chain_moments.union_nines) against scipy's
log_ndtr: the same value where the bound is a number, and a finite, right value, gradient and
curvature far inside, where the bound in linear terms is 0."""

import casadi as ca
import numpy as np
import pytest
from scipy.special import log_ndtr, logsumexp

from pdm_design.formulation import chain_moments as cm


def reference(beta, counted):
    """-log10 sum_counted Phi(-beta), from scipy."""
    return -logsumexp(log_ndtr(-np.asarray(beta)[np.asarray(counted, bool)])) / np.log(10.0)


def function(rows):
    g, sd = ca.MX.sym("g", rows), ca.MX.sym("sd", rows)
    counted = ca.DM([1.0] * (rows - 1) + [0.0])  # the last row does not count
    value = cm.union_nines(g, sd, counted)
    grad = ca.gradient(value, g)
    return ca.Function("n", [g, sd], [value, grad, ca.jacobian(grad, g)]), counted


@pytest.mark.parametrize("beta", [[2.5, 3.0, 4.9, -1.0], [0.5, 1.0, 2.0, 9.0],
                                  [5.0, 6.0, 8.5, 0.0], [12.0, 30.0, 40.0, 1.0],
                                  [-3.0, 45.0, 100.0, 2.0]])
def test_the_value_is_scipys_at_any_reliability(beta):
    fn, counted = function(len(beta))
    sd = np.array([0.3, 2.0, 1.5, 1.0])
    value = float(fn(np.array(beta) * sd, sd)[0])
    assert value == pytest.approx(reference(beta, np.asarray(counted).ravel()), rel=2e-7)


def test_where_the_bound_is_a_number_it_is_failure_bounds_logarithm():
    g, sd = ca.DM([2.0, 3.1, 4.5, 0.2]), ca.DM([1.0, 1.0, 1.2, 1.0])
    counted = ca.DM([1.0, 1.0, 1.0, 0.0])
    linear = -np.log10(float(cm.failure_bound(g, sd, counted)))
    assert float(cm.union_nines(g, sd, counted)) == pytest.approx(linear, rel=1e-13)


def test_far_inside_the_derivatives_are_finite_and_right():
    """Every beta above 8.3: 1 - erf is 0 in floating point, the linear bound 0, and the old
    nines' gradient came out 1e280. Here: central differences of scipy's reference."""
    beta = np.array([9.0, 11.0, 20.0, 3.0])
    fn, counted = function(4)
    sd = np.ones(4)
    _, grad, hess = (np.asarray(o, float) for o in fn(beta, sd))
    mask = np.asarray(counted).ravel()
    h = 1e-4
    size = np.abs(grad).max()  # log_tail's fit: its slope to 0.2 % of a far row's own
    for i in range(3):
        e = np.zeros(4)
        e[i] = h
        fd = (reference(beta + e, mask) - reference(beta - e, mask)) / (2 * h)
        assert grad[i, 0] == pytest.approx(fd, rel=1e-5, abs=1e-7 * size)
        fd2 = (reference(beta + e, mask) - 2 * reference(beta, mask)
               + reference(beta - e, mask)) / h ** 2
        assert hess[i, i] == pytest.approx(fd2, rel=1e-3, abs=1e-6 * size)
    assert grad[3, 0] == 0.0  # the row that does not count


def test_a_row_that_is_not_a_number_stays_one():
    g, sd = ca.DM([2.0, np.nan]), ca.DM([1.0, 1.0])
    assert np.isnan(float(cm.union_nines(g, sd, ca.DM([1.0, 1.0]))))


def test_the_nines_row_is_the_log_ratio_and_its_tangent_below_the_floor():
    """formulation/yield_target.log_ratio: log r from LOG_FLOOR up; below, the tangent there
    (the same value and slope at the floor), a number where the nines are none or negative,
    and a NaN stays one."""
    import math

    from pdm_design.formulation.yield_target import LOG_FLOOR, log_ratio

    r = ca.SX.sym("r")
    fn = ca.Function("f", [r], [log_ratio(r), ca.gradient(log_ratio(r), r)])
    for x in (LOG_FLOOR, 0.7, 1.0, 3.0, 1e6):
        value, slope = (float(o) for o in fn(x))
        assert value == pytest.approx(math.log(x), rel=1e-15, abs=1e-15)
        assert slope == pytest.approx(1.0 / x, rel=1e-15)
    below, slope = (float(o) for o in fn(LOG_FLOOR * (1.0 - 1e-9)))
    assert below == pytest.approx(math.log(LOG_FLOOR), abs=1e-8)
    assert slope == pytest.approx(1.0 / LOG_FLOOR, rel=1e-12)
    for x in (0.0, -2.0):
        assert float(fn(x)[0]) == pytest.approx(math.log(LOG_FLOOR) + (x - LOG_FLOOR) / LOG_FLOOR)
    assert np.isnan(float(fn(np.nan)[0]))
