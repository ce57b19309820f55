"""The designer: known optima, honest status, elastic diagnosis, robust tolerance vs an independent
grid search, soundness of the robust box by independent stage-by-stage propagation, cvxpy boxes.

Every reference number here is computed in this file with plain numpy/math formulas (the closed
forms of docs/physics.md written afresh), never by the NLP's code path.
"""

from __future__ import annotations

import itertools
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from pdm_design.formulation import formulate
from pdm_design.scenes.manipulators.model import Body, ManipulatorsInitial, ManipulatorsScene, Palm
from pdm_design.scenes.stairs.analysis import nose_clearance
from pdm_design.solve import map_status, optimize
from pdm_design.solve.ipopt import start_designs
from pdm_design.solve.tolerance import linear_safe_set
from pdm_design.spec import load_spec, parse_spec
from pdm_design.spec.model import Bounds, Spec
from pdm_design.status import Status

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
G = 9.81


def paper_scene(friction=0.8):
    return ManipulatorsScene(
        body=Body(mass=1.0, width=0.4, height=0.2),
        palm=Palm(width=1.6, friction=friction),
        initial=ManipulatorsInitial(position=(-1.25, 3.05), velocity=(3.0, 0.0)),
    )


def beta_spec(objective, requirements, beta_max=1.2, beta_initial=0.5):
    return Spec(source="test", scene=paper_scene(),
                design={"alpha": 0.2, "beta": Bounds(min=0.2, max=beta_max, initial=beta_initial),
                        "link_length": 2.0, "mass_ratio": 10.0},
                objective=objective, requirements=requirements)


# -- known optima -----------------------------------------------------------------------------

@pytest.mark.parametrize("slip_margin, beta_max", [(0.1, 1.2), (0.0, 1.2), (0.0, 0.55)])
def test_fastest_convergence_with_beta_free_is_the_largest_beta_friction_allows(slip_margin,
                                                                                beta_max):
    # c = (m/(m+M))^2 cos^2(a + b) falls as b grows (a + b < pi/2), so the optimum is the largest
    # beta allowed: friction during the carry, tan b <= mu (1 - margin), or the bound.
    spec = beta_spec({"fastest_convergence": 1.0}, {"slip_carry": slip_margin}, beta_max)
    expected = min(math.atan(0.8 * (1 - slip_margin)), beta_max)
    result = optimize(spec)
    assert result.status is Status.OPTIMAL
    assert result.design["beta"] == pytest.approx(expected, abs=1e-6)


def _min_drop_beta(a=0.2, l=2.0, k=10.0 / 11.0, r=0.5):
    """Drop l (cos a - cos b) grows with b; the smallest b keeps the periodic landing speed u*
    over the top with margin r: u*^2 (1 - r) = 2 g l (1 - cos a), with
    u*^2 = c s*^2, s*^2 = 2 g l (cos a - cos b) / (1 - c), c = (q/(1+q))^2 cos^2(a + b)."""

    def u_star_sq(b):
        c = (k * math.cos(a + b)) ** 2
        return c * 2 * G * l * (math.cos(a) - math.cos(b)) / (1 - c)

    return brentq(lambda b: u_star_sq(b) * (1 - r) - 2 * G * l * (1 - math.cos(a)), a + 1e-9,
                  0.6, xtol=1e-15)


def test_min_drop_with_beta_free_is_where_the_over_the_top_margin_binds():
    a, l, r = 0.2, 2.0, 0.5
    b_star = _min_drop_beta(a, l, r=r)
    result = optimize(beta_spec({"min_drop": 1.0}, {"over_the_top": r}, 1.0, 0.8))
    assert result.status is Status.OPTIMAL
    # within the rows' backoff (100 times IPOPT's tol 1e-8: formulation/common.py), on its
    # safe side: a larger beta, a larger drop
    assert 0.0 <= result.design["beta"] - b_star <= 1e-5
    assert result.objectives["min_drop"] == pytest.approx(l * (math.cos(a) - math.cos(b_star)),
                                                          abs=1e-5)


def test_zero_bound_relaxation_puts_the_optimum_next_to_its_constraint():
    # Same closed-form optimum as above; the precise preset's tol 1e-11 and bound_relax_factor 0
    # keep the answer within the rows' backoff of it (100 tol: 1e-9 of a row), on its safe side.
    b_star = _min_drop_beta(r=0.5)
    result = optimize(beta_spec({"min_drop": 1.0}, {"over_the_top": 0.5}, 1.0, 0.8),
                      tol=1e-11, bound_relax_factor=0.0)
    assert result.status is Status.OPTIMAL
    assert 0.0 <= result.design["beta"] - b_star <= 1e-8


# -- honest status ----------------------------------------------------------------------------

@pytest.mark.parametrize("ipopt, status", [
    ("Solve_Succeeded", Status.OPTIMAL),
    ("Solved_To_Acceptable_Level", Status.ACCEPTABLE),
    ("Maximum_Iterations_Exceeded", Status.ITERATION_LIMIT),
    ("Infeasible_Problem_Detected", Status.INFEASIBLE),
    ("Restoration_Failed", Status.SOLVER_ERROR),
    ("Maximum_CpuTime_Exceeded", Status.SOLVER_ERROR),
])
def test_ipopt_return_status_maps_to_one_vocabulary(ipopt, status):
    assert map_status(ipopt) is status


def test_iteration_limit_is_reported_not_optimal():
    result = optimize(beta_spec({"fastest_convergence": 1.0}, {}), max_iter=1, starts=2)
    assert result.status is Status.ITERATION_LIMIT
    assert not result.success


def test_infeasible_spec_names_the_condition_and_how_far_it_is():
    result = optimize(load_spec(PROBLEMS / "infeasible_manipulators.toml"))
    assert result.status is Status.INFEASIBLE
    names = {v.name for v in result.violations}
    assert names == {"slip_carry"}
    # Best achievable: beta at its lower bound 0.5, margin(mu, tan b) = (mu - tan b) / tan b.
    expected = (0.3 - math.tan(0.5)) / math.tan(0.5)
    (violation,) = result.violations
    assert violation.achieved == pytest.approx(expected, abs=1e-5)
    assert violation.required == 0.0
    assert "friction" in violation.text and "beta at its lower bound" in result.message


def test_requirements_are_parameters_of_one_built_nlp():
    spec = beta_spec({"fastest_convergence": 1.0}, {"slip_carry": 0.0})
    other = beta_spec({"fastest_convergence": 1.0}, {"slip_carry": 0.2})
    assert formulate(spec) is formulate(other)
    assert optimize(other).design["beta"] == pytest.approx(math.atan(0.8 * 0.8), abs=1e-6)


def test_warm_start_reaches_the_same_optimum_in_fewer_iterations():
    spec = load_spec(PROBLEMS / "manipulators_robust.toml")
    cold = optimize(spec, starts=1, linearise=False)
    warm = optimize(spec, starts=1, warm_start=cold, linearise=False)
    assert warm.status is Status.OPTIMAL
    # two runs: the warm start's (first, _multistart) and the same cold start again
    assert cold.stats.starts == 1 and warm.stats.starts == 2
    assert warm.stats.return_statuses == ("Solve_Succeeded", "Solve_Succeeded")
    assert warm.objective == pytest.approx(cold.objective, abs=1e-8)
    # strictly fewer: the reported run is not the cold one, whose iterations repeat exactly
    assert warm.stats.iterations < cold.stats.iterations
    # and it is the warm run: the two runs' iterations (and the tie-break's) add up to the total
    assert warm.stats.total_iterations == (warm.stats.iterations + cold.stats.total_iterations
                                           - cold.stats.tie_break_iterations
                                           + warm.stats.tie_break_iterations)


# -- robust tolerance: independent grid --------------------------------------------------------

def robust_tolerance_grid(scene, alpha, beta, *, link_length, mass_ratio, stages, iters=32):
    """The NLP's robust tolerance definition (docs/optimizer.md), written afresh in numpy and
    solved by bisection on tau at every (alpha, beta): no CasADi, no pdm_design code."""
    a, b = np.meshgrid(np.asarray(alpha, float), np.asarray(beta, float), indexing="ij")
    lo = np.zeros_like(a)
    hi = np.full_like(a, 0.5)
    ok0 = _robust_ok(scene, a, b, lo, link_length, mass_ratio, stages)
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        ok = _robust_ok(scene, a, b, mid, link_length, mass_ratio, stages)
        lo = np.where(ok, mid, lo)
        hi = np.where(ok, hi, mid)
    return np.where(ok0, lo, -1.0)


def _robust_ok(scene, a, b, tau, l, q, N):
    with np.errstate(all="ignore"):
        return _robust_ok_raw(scene, a, b, tau, l, q, N)


def _robust_ok_raw(scene, a, b, tau, l, q, N):
    g = scene.gravity
    mu, W = scene.palm.friction, scene.palm.width
    w, h = scene.body.width, scene.body.height
    (x0, y0), (vx0, vy0) = scene.initial.position, scene.initial.velocity
    k, B = q / (1 + q), 2 * g * l
    ok = np.ones_like(a, dtype=bool)
    cm, cp = np.cos(b) - 2 * tau / l, np.cos(b) + 2 * tau / l
    th_hi, th_lo = np.arccos(cm), np.arccos(cp)
    H, C0 = y0 - l * np.cos(a), x0 + l * np.sin(a)

    def Q(dy):
        return np.sqrt(vy0**2 + 2 * g * (H - dy))

    def t(dy):
        return (vy0 + Q(dy)) / g

    def u1(Qv):
        return k * (vx0 * np.cos(a) - Qv * np.sin(a))

    ok &= (H - tau - 1e-3 * l >= 0) & (u1(Q(-tau)) >= 0) & (np.cos(a + th_hi) >= 0)
    ok &= l * (np.cos(a) - np.cos(b)) - 2 * tau >= 0
    ok &= (mu - np.tan(a) >= 0) & (mu - np.tan(th_hi) >= 0)
    # Invariant interval of landing speeds.
    curv = np.maximum((np.cos(th_lo) / np.sin(th_lo)) ** 2 / 8 - 1 / np.cos(a + th_lo) ** 2, 0)
    sag = np.exp(-curv * (th_hi - th_lo) ** 2 / 8)
    u_lo = u1(Q(-tau))
    for th in (th_lo, th_hi):
        kappa = k * np.cos(a + th) * sag
        E = B * (np.cos(a) - np.cos(th))
        u_lo = np.minimum(u_lo, np.where(kappa < 1, np.sqrt(kappa**2 * E / (1 - kappa**2)), np.inf))
    ok &= u_lo**2 - B * (1 - np.cos(a)) >= 0
    u1_hi = u1(Q(tau))
    u_max = np.minimum(np.sqrt(g * l * np.cos(a)), np.sqrt(np.maximum(
        g * l * cm - B * (np.cos(a) - cm), 0)))
    D = B * (np.cos(a) - np.cos(b))

    def high_ok(u):
        lam = -np.tan(a + b) + 0.5 * B * np.sin(b) / (u**2 + D)
        F_b = k * np.cos(a + b) * np.sqrt(u**2 + D)
        worst = np.maximum(*(F_b * np.exp(lam * (th - b) + curv * (th - b) ** 2 / 2)
                             for th in (th_lo, th_hi)))
        return u - worst >= 0

    any_high = np.zeros_like(ok)
    for s in np.linspace(0.0, 1.0, 81):
        u = u1_hi + s * (u_max - u1_hi)
        any_high |= high_ok(u) & (u <= u_max)
    ok &= any_high & (u1_hi <= u_max)
    # Landing positions.
    cot_b = np.cos(b) / np.sin(b)
    o1_hi, o1_lo = C0 + vx0 * t(-tau) + tau, C0 + vx0 * t(tau) - tau
    slope = cot_b - vx0 / Q(0)
    o_hi = C0 + vx0 * t(0) + tau * (1 + cot_b) + np.abs(slope) * tau
    phi_min = np.minimum(vx0 * t(tau) + cot_b * tau, vx0 * t(-tau) - cot_b * tau)
    r_min = np.minimum(l * (np.sin(th_lo) - np.sin(b)) + 2 * tau * cot_b,
                       l * (np.sin(th_hi) - np.sin(b)) - 2 * tau * cot_b)
    o_lo = C0 + phi_min - tau * (1 + cot_b) + (N - 1) * r_min
    ok &= (W / 2 - w / 2 - o_hi >= 0) & (W / 2 - w / 2 + o_lo >= 0)
    ok &= (w / 2 - h / 2 * np.tan(a) >= 0) & (W / 2 - o_hi - h / 2 * np.tan(a) >= 0)
    ok &= (w / 2 - h / 2 * np.tan(th_hi) >= 0) & (W / 2 + o_lo - h / 2 * np.tan(th_hi) >= 0)

    def impact_ok(px, py, oh, ol):
        return ((mu * py - np.abs(px) >= 0) & (w / 2 * py - h / 2 * np.abs(px) >= 0)
                & ((W / 2 - oh) * py + h / 2 * px >= 0) & ((W / 2 + ol) * py - h / 2 * px >= 0))

    for th in (th_lo, th_hi):
        kc = k * np.cos(a + th)
        ok &= impact_ok(kc * np.cos(a) - np.cos(th), kc * np.sin(a) + np.sin(th), o_hi, o_lo)
    for Qv in (Q(tau), Q(-tau)):
        u = u1(Qv)
        ok &= impact_ok(u * np.cos(a) - vx0, u * np.sin(a) + Qv, o1_hi, o1_lo)
    return ok


@pytest.fixture(scope="module")
def robust():
    spec = load_spec(PROBLEMS / "manipulators_robust.toml")
    return spec, optimize(spec, linearise=True)


def test_robust_optimum_is_at_least_as_good_as_a_dense_grid(robust):
    spec, result = robust
    assert result.status is Status.OPTIMAL
    alpha = np.linspace(spec.design["alpha"].min, spec.design["alpha"].max, 121)
    beta = np.linspace(spec.design["beta"].min, spec.design["beta"].max, 201)
    grid = robust_tolerance_grid(spec.scene, alpha, beta, link_length=2.0, mass_ratio=10.0,
                                 stages=spec.verification.stages)
    best = grid.max()
    assert best > 0.0
    tol = result.tolerance["dx"]
    assert tol >= best - 1e-6
    assert tol <= best * 1.05  # the two implementations agree on what the tolerance is


# -- robust tolerance: soundness by independent propagation -----------------------------------

@np.errstate(invalid="ignore")
def propagate_offsets(scene, design, dx, dy, N):
    """Exact stage-by-stage conditions for one offset sequence (numpy, afresh): the smallest
    margin-like slack (>= 0 when every condition holds), vectorised over rows of dx, dy."""
    g = scene.gravity
    mu, W = scene.palm.friction, scene.palm.width
    w, h = scene.body.width, scene.body.height
    (x0, y0), (vx0, vy0) = scene.initial.position, scene.initial.velocity
    a, b, l, q = design["alpha"], design["beta"], design["link_length"], design["mass_ratio"]
    k = q / (1 + q)
    worst = np.full(dx.shape[0], np.inf)

    def need(x):  # nan: a quantity does not exist (e.g. no handover), a failure
        nonlocal worst
        worst = np.minimum(worst, np.where(np.isnan(x), -np.inf, x))

    def impact(px, py, o):
        need(mu * py - np.abs(px))
        need(np.minimum(w / 2, W / 2 - o) * py + h / 2 * px)
        need(np.minimum(w / 2, W / 2 + o) * py - h / 2 * px)

    fall = y0 - (l * np.cos(a) + dy[:, 0])
    Qv = np.sqrt(vy0**2 + 2 * g * fall)
    u = k * (vx0 * np.cos(a) - Qv * np.sin(a))
    o = x0 + vx0 * (vy0 + Qv) / g - (-l * np.sin(a) + dx[:, 0])
    impact(u * np.cos(a) - vx0, u * np.sin(a) + Qv, o)
    for K in range(N):
        need(W / 2 - w / 2 - np.abs(o))
        need(u**2 - 2 * g * l * (1 - np.cos(a)))
        need(g * l * np.cos(a) - u**2)
        need(np.minimum(w / 2, W / 2 - o) - h / 2 * np.tan(a))
        delta = dy[:, K + 1] - dy[:, K]
        need(l * (np.cos(a) - np.cos(b)) - delta)
        cth = np.cos(b) + delta / l
        th = np.arccos(cth)
        v2 = u**2 + 2 * g * l * (np.cos(a) - cth)
        need(g * l * cth - v2)
        need(mu - np.tan(th))
        need(np.minimum(w / 2, W / 2 + o) - h / 2 * np.tan(th))
        if K == N - 1:
            break
        v = np.sqrt(v2)
        u = k * v * np.cos(a + th)
        o = o + l * (np.sin(th) - np.sin(b)) - (dx[:, K + 1] - dx[:, K])
        impact(u * np.cos(a) - v * np.cos(th), u * np.sin(a) + v * np.sin(th), o)
    return worst


def test_robust_box_holds_for_offsets_sampled_inside_it(robust):
    spec, result = robust
    tau, N = result.tolerance["dx"], spec.verification.stages
    rng = np.random.default_rng(7)
    n = 4000
    dx = tau * np.concatenate([rng.choice([-1.0, 1.0], (n, N)), rng.uniform(-1, 1, (n, N))])
    dy = tau * np.concatenate([rng.choice([-1.0, 1.0], (n, N + 1)),
                               rng.uniform(-1, 1, (n, N + 1))])
    alt = np.where(np.arange(N + 1) % 2 == 0, 1.0, -1.0)
    ramp = np.linspace(1.0, -1.0, N + 1)
    patterns = [alt, -alt, ramp, -ramp, np.ones(N + 1), -np.ones(N + 1)]
    for pat, sx in itertools.product(patterns, (-1.0, 1.0)):
        dy = np.vstack([dy, tau * pat])
        dx = np.vstack([dx, tau * sx * np.ones(N)])
    worst = propagate_offsets(spec.scene, result.design, dx, dy, N)
    assert np.all(worst >= -1e-9)


def test_a_box_larger_than_the_robust_one_is_not_claimed_sound_by_accident(robust):
    # The robust box is conservative, not arbitrary: three times the box breaks some condition.
    spec, result = robust
    tau, N = 3 * result.tolerance["dx"], spec.verification.stages
    alt = np.where(np.arange(N + 1) % 2 == 0, 1.0, -1.0)
    dy = tau * np.vstack([alt, -alt, np.linspace(1, -1, N + 1), np.linspace(-1, 1, N + 1)])
    dx = tau * np.vstack([np.ones(N), -np.ones(N), -np.ones(N), np.ones(N)])
    assert propagate_offsets(spec.scene, result.design, dx, dy, N).min() < 0


# -- cvxpy in the linearised safe set ---------------------------------------------------------

def safe_set_by_differences(form, x, step=1e-5):
    """(A, b) of the linearised safe set b + A d >= 0, written afresh: the scenario rows
    slack_i(x, d) >= 0 (no requirements in manipulators_robust.toml) divided by |scale_i(x, 0)|,
    differentiated by central differences in every offset (no CasADi Jacobian, no
    `linear_safe_set`). Rows independent of d (validity rows of the design alone) keep A = 0."""
    sc = form.scenario
    n = len(sc.offset_names)

    def rows(d):
        slack, scale = sc.function(x, d)
        return np.asarray(slack, dtype=float).ravel(), np.asarray(scale, dtype=float).ravel()

    slack0, scale0 = rows(np.zeros(n))
    norm = np.where(np.abs(scale0) > 1e-12, np.abs(scale0), 1.0)
    A = np.empty((len(slack0), n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = step
        A[:, j] = (rows(e)[0] - rows(-e)[0]) / (2 * step) / norm
    return A, slack0 / norm


@pytest.fixture(scope="module")
def safe_set(robust):
    spec, result = robust
    assert not spec.requirements  # every row is slack >= 0: b + A d >= 0 needs no r_i
    form = formulate(spec)
    return form, safe_set_by_differences(form, result.solution.x)


def test_linearised_safe_set_matches_central_differences(robust, safe_set):
    spec, result = robust
    form, (A_fd, b_fd) = safe_set
    A, b, keep = linear_safe_set(form, result.solution.x, form.parameters(spec.requirements))
    assert b == pytest.approx(b_fd, abs=1e-12)
    assert np.abs(A - A_fd).max() <= 1e-6 * max(1.0, np.abs(A_fd).max())
    assert set(keep) == set(np.flatnonzero(np.abs(A_fd).sum(axis=1) > 1e-9))


def test_cvxpy_box_corners_lie_in_the_linearised_safe_set(robust, safe_set):
    # The safe set by central differences, not the Jacobian that fed cvxpy: an A that came out
    # too small would let cvxpy report boxes too large, and their corners leave this set.
    spec, result = robust
    form, (A, b) = safe_set
    lin = result.linearised
    groups = form.scenario.groups
    half = np.zeros(A.shape[1])
    for name, cols in groups.items():
        half[list(cols)] = lin.box[name]
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=A.shape[1]))) * half
    assert np.all(b[:, None] + A @ corners.T >= -1e-6)
    # ... and it is the largest axis box: 1 % more in either group leaves the set
    for name, cols in groups.items():
        bigger = half.copy()
        bigger[list(cols)] *= 1.01
        assert np.any(b[:, None] + A @ (corners / half * bigger).T < 0), name
    square = np.array(list(itertools.product((-1.0, 1.0), repeat=A.shape[1]))) * lin.square
    assert np.all(b[:, None] + A @ square.T >= -1e-6)
    # ... and it is the largest: a 1 % larger square leaves the set at some corner.
    assert np.any(b[:, None] + A @ (1.01 * square.T) < 0)


def test_cvxpy_ellipsoid_lies_in_the_linearised_safe_set(robust, safe_set):
    spec, result = robust
    form, (A, b) = safe_set
    E = np.array(result.linearised.ellipsoid["matrix"])
    rng = np.random.default_rng(3)
    u = rng.normal(size=(A.shape[1], 2000))
    u /= np.linalg.norm(u, axis=0)
    assert np.all(b[:, None] + A @ (E @ u) >= -1e-5)
    # ... and it touches the set: the support of E along the binding row, ||E A_i||, reaches b_i
    moving = np.abs(A).sum(axis=1) > 1e-9
    reach = np.linalg.norm(A[moving] @ E, axis=1) / b[moving]
    assert reach.max() == pytest.approx(1.0, abs=1e-3)


# -- stairs ---------------------------------------------------------------------------------

def test_stairs_design_is_optimal_and_its_error_box_is_sound():
    spec = load_spec(PROBLEMS / "stairs_design.toml")
    result = optimize(spec)
    assert result.status is Status.OPTIMAL
    tau = result.tolerance["rise"]
    assert tau > 0
    d = result.design
    eps, vx, rise, tread, r = (d["restitution"], d["launch_speed"], d["rise"], d["tread"],
                               spec.scene.ball.radius)
    assert rise == pytest.approx((1 - eps**2) * 1.0)  # periodic from the first impact
    assert tread == pytest.approx(vx * (1 + eps) * math.sqrt(2 * 1.0 / G))
    N = spec.verification.stages
    rng = np.random.default_rng(5)
    sequences = [(np.full(N, s1 * tau), np.full(N, s2 * tau)) for s1 in (-1, 1) for s2 in (-1, 1)]
    sequences += [(tau * rng.choice([-1.0, 1.0], N), tau * rng.choice([-1.0, 1.0], N))
                  for _ in range(40)]
    for er, et in sequences:
        # step n = tread n and the riser at its back (the simulator's numbering): er[0] is the
        # first riser, below the fixed launcher, so the first fall is h0 + er[0]
        v = math.sqrt(2 * G * (1.0 + er[0]))
        L = d["landing_offset"] + vx * (v - math.sqrt(2 * G * 1.0)) / G
        for n in range(N):
            assert L - r >= 0.02 * tread - 1e-9  # riser clearance with the required margin
            next_rise = rise + (er[n + 1] if n + 1 < N else 0.0)
            gap = nose_clearance(vx, eps * v, G, r, tread + et[n], L, next_rise)
            assert gap >= -1e-9  # the analysis' own clearance: the ball never touches a nose
            up = eps * v
            down = math.sqrt(up**2 + 2 * G * next_rise)
            L = L + vx * (up + down) / G - (tread + et[n])
            v = down


def test_freeing_link_length_and_mass_ratio_beats_every_grid_mechanism():
    # The four mechanism parameters free: the optimum must be at least as good as the best of
    # an independent grid over all four (numpy bisection, robust_tolerance_grid).
    spec = load_spec(PROBLEMS / "manipulators_robust_all_free.toml")
    result = optimize(spec)
    assert result.status is Status.OPTIMAL
    d = spec.design
    alpha = np.linspace(d["alpha"].min, d["alpha"].max, 31)
    beta = np.linspace(d["beta"].min, d["beta"].max, 51)
    best = max(
        robust_tolerance_grid(spec.scene, alpha, beta, link_length=length, mass_ratio=ratio,
                              stages=spec.verification.stages).max()
        for length in np.linspace(d["link_length"].min, d["link_length"].max, 5)
        for ratio in (d["mass_ratio"].min, 10.0, d["mass_ratio"].max))
    assert best > 0.0
    assert result.tolerance["dx"] >= best - 1e-6


def test_a_start_where_the_closed_forms_are_undefined_is_moved_toward_the_guess():
    # beta below alpha: no periodic handover, the speed interval's square roots are of negative
    # numbers. IPOPT from there stops at once; from the point defined_start picks, on the way to
    # the spec's guess, it reaches the optimum of the whole problem.
    from pdm_design.solve.ipopt import SolverOptions, solve_once, solver_for

    spec = load_spec(PROBLEMS / "manipulators_robust.toml")
    form = formulate(spec)
    p = form.parameters(spec.requirements)
    solver = solver_for(form.key, form.nlp, SolverOptions())
    guess = {n: spec.design[n].guess for n in form.design_names}
    bad = {"alpha": 0.503, "beta": 0.304}

    def run(x0):
        return solve_once(solver, x0, p, form.lbx, form.ubx, form.lbg, form.ubg)

    assert run(form.start_vector(bad)).return_status == "Invalid_Number_Detected"
    x0 = form.defined_start(bad, guess, p)
    t = (x0[0] - guess["alpha"]) / (bad["alpha"] - guess["alpha"])
    assert 0.0 < t < 1.0
    assert x0[1] == pytest.approx(guess["beta"] + t * (bad["beta"] - guess["beta"]))
    moved = run(x0)
    assert moved.return_status == "Solve_Succeeded"
    assert -moved.f == pytest.approx(optimize(spec).tolerance["dx"], rel=1e-6)


@pytest.mark.parametrize("name", ["manipulators_robust", "manipulators_robust_all_free",
                                  "stairs_design", "paper_manipulators"])
def test_starts_checked_together_are_the_starts_checked_one_by_one(name):
    from pdm_design.solve.ipopt import start_designs

    spec = load_spec(PROBLEMS / f"{name}.toml")
    form = formulate(spec)
    p = form.parameters(spec.requirements)
    names = form.design_names
    guess = {n: spec.design[n].guess for n in names}
    designs = [d for seed in range(4) for d in start_designs(
        names, [spec.design[n].min for n in names], [spec.design[n].max for n in names],
        guess, 8, seed=seed)]
    one_by_one = [form.defined_start(d, guess, p) for d in designs]
    if "alpha" in names:  # some of these points (2 and 4 of 32) are undefined and moved
        moved = [not np.allclose(x, form.start_vector(d)) for x, d in zip(one_by_one, designs)]
        assert any(moved)
    assert np.array_equal(np.array(form.defined_starts(designs, guess, p)),
                          np.array(one_by_one))


def test_an_optimum_on_a_bound_is_reported_within_it():
    """Restitution free up to 1: the margins grow as the bounces lose less, so the optimum sits
    on the bound, where the rise (1 - eps^2) h0 is 0. IPOPT relaxes bounds by 1e-8; the design
    it reports must not be the restitution 1 + 7e-9 and rise -1e-8 that the re-check refuses."""
    spec = parse_spec({
        "scene": {"kind": "stairs", "ball": {"radius": 0.05}},
        "initial": {"drop_height": 1.0},
        "design": {"restitution": {"min": 0.0, "max": 1.0},
                   "launch_speed": {"min": 0.5, "max": 3.0, "initial": 2.0},
                   "landing_offset": {"min": 0.0, "max": 3.0, "initial": 0.8}},
        "objective": {"max_min_margin": 1.0}})
    result = optimize(spec)
    assert result.status is Status.OPTIMAL
    assert 0.0 <= result.design["restitution"] <= 1.0 and result.design["rise"] >= 0.0


def _robust_manipulators(scale: float = 1.0, stages: int = 6):
    """problems/manipulators_robust.toml with every length times `scale` (speeds times its
    square root, so that every angle and every ratio stays the same)."""
    data = tomllib.loads((PROBLEMS / "manipulators_robust.toml").read_text())
    body, palm, initial = data["scene"]["body"], data["scene"]["palm"], data["initial"]
    for table, keys in ((body, ("width", "height")), (palm, ("width", "thickness"))):
        for key in keys:
            table[key] *= scale
    initial["position"] = [v * scale for v in initial["position"]]
    initial["velocity"] = [v * math.sqrt(scale) for v in initial["velocity"]]
    data["design"]["link_length"] *= scale
    data["verification"]["stages"] = stages
    return parse_spec(data)


def test_the_linearised_sets_scale_with_the_device():
    """Dimensional analysis: ten times the size, ten times every half-width (cvxpy in metres
    failed at that size and the report silently lost the linearised sets)."""
    one, ten = (optimize(_robust_manipulators(k), check_samples=0, linearise=True).linearised
                for k in (1, 10))
    assert one.status == ten.status == "optimal"
    assert ten.square == pytest.approx(10 * one.square, rel=1e-6)
    for axis in ("dx", "dy"):
        assert ten.box[axis] == pytest.approx(10 * one.box[axis], rel=1e-4)  # a flat optimum
    assert ten.ellipsoid["min_semi_axis"] == pytest.approx(
        10 * one.ellipsoid["min_semi_axis"], rel=1e-4)


def test_many_offsets_leave_the_robust_box_and_say_why_the_linearised_sets_are_missing():
    spec = _robust_manipulators(stages=130)  # dx1..dx130 and dy1..dy131
    result = optimize(spec, check_samples=0, linearise=True)
    assert result.status is Status.OPTIMAL and result.tolerance["dx"] > 0
    assert result.linearised.status.startswith("not computed: 261 offset coordinates")


def test_a_row_of_tiny_manipulators_has_the_same_optimum_to_scale():
    """Dimensional analysis: links of 40 microns tolerate 2e-5 times the offsets of 2 m links
    (IPOPT's absolute tolerances on an objective in metres stopped it 2.2e-5 short there), and
    every start finds it (IPOPT's push of the tolerance off 0, a hundredth of its bound, was 8 %
    of such a link, and 3 of 8 starts ended Invalid_Number_Detected)."""
    k = 2e-5
    one, tiny = (optimize(_robust_manipulators(s), check_samples=0, linearise=False)
                 for s in (1.0, k))
    assert tiny.status is Status.OPTIMAL
    assert set(tiny.stats.return_statuses) == {"Solve_Succeeded"}
    assert tiny.tolerance["dx"] / k == pytest.approx(one.tolerance["dx"], rel=5e-6)
    assert tiny.design["alpha"] == pytest.approx(one.design["alpha"], abs=1e-6)


def test_bounds_spanning_decades_are_searched_in_log_scale():
    """A link length free in [1e-6, 1e6] m with no guess: drawn evenly, 7 of 8 starts fell above
    1e5 m, where the object starts below the first palm, and every start failed."""
    starts = start_designs(["link_length"], [1e-6], [1e6], {"link_length": 1.0}, 8)
    exponents = sorted(math.log10(s["link_length"]) for s in starts[1:])
    assert exponents[0] < -3 and exponents[-1] > 3 and -3 < exponents[3] < 3
    data = tomllib.loads((PROBLEMS / "manipulators_robust.toml").read_text())
    data["design"]["link_length"] = {"min": 1e-6, "max": 1e6}
    assert optimize(parse_spec(data), check_samples=0).status is Status.OPTIMAL
