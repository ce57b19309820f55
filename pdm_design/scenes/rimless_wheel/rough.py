"""Steps before failure on a rough ramp: every step's chord slope is the design's plus a normal
error of standard deviation sigma = tolerance / 3 (docs/rimless_wheel.md, section 8).

`monte_carlo`: many wheels on the vectorised step map (`steps.step_map`): the survival curve and
the mean steps before failure (censored at the run's length). `mfpt`: the mean first-passage
time by the discretised return map as an absorbing Markov chain (Byl & Tedrake 2009): the state
is the stance energy E = omega^2 - rate (1 - cos phi) (the post-impact speed referred to the
spoke's vertical: on rough ground the post-impact speed alone does not fix the next step, the
angle the stance starts at does too; E does), in bins; a bin's transitions integrate the slope's
normal density exactly over the slopes that take its centre into each bin and over those that
fail. The interval reflects the discretisation: the chain is solved at two resolutions and
extrapolated (Richardson, second order: the centre of a bin stands for it); the interval spans
both resolutions and the extrapolation, widened by their difference.
"""

from __future__ import annotations

import math

import numpy as np

from . import physics as phys
from .analysis import WheelNumbers, resolve
from .steps import OK, point_failures, step_map

# Beyond this many steps the chain's failure probabilities (about 1 / mfpt a step) are below
# what I - Q keeps against its unit diagonal in double precision: reported as a lower bound.
MFPT_LIMIT = 1e12
SIGMAS = 12.0  # slopes beyond this many standard deviations are not looked at (P < 4e-33)
BISECTIONS = 60


def sigma_of(tolerance: float) -> float:
    """The slope error's standard deviation: a tolerance is three of them."""
    return tolerance / 3.0


def _ramp(scene, design) -> WheelNumbers:
    if scene.ground != "ramp":
        raise ValueError("rough-ground statistics are for a ramp (ground = \"ramp\")")
    wh, _, problems = resolve(scene, design)
    if problems:
        raise ValueError("; ".join(problems))
    return wh


def monte_carlo(scene, design, tolerance: float, *, steps: int, samples: int, seed: int = 0,
                chunk: int = 2_000_000) -> dict:
    """Wheels on a rough ramp for up to `steps` steps each: survival[s] = the fraction that made
    at least s steps (s = 0..steps), mean_censored = the mean of min(steps made, steps),
    censored = the wheels still rolling at the end (mean = mean_censored when none, with its
    standard error), failures by kind."""
    wh = _ramp(scene, design)
    rng = np.random.default_rng(seed)
    per = max(1, chunk // max(steps, 1))
    passed, kinds = [], {}
    for start in range(0, samples, per):
        n = min(per, samples - start)
        betas = wh.beta + rng.normal(0.0, sigma_of(tolerance), (n, steps))
        run = step_map(wh, scene.initial.speed, betas, ground=wh.ground)
        passed.append(run.passed)
        for kind in run.kinds():
            if kind:
                kinds[kind] = kinds.get(kind, 0) + 1
    made = np.concatenate(passed)
    counts = np.bincount(made, minlength=steps + 1)
    survival = 1.0 - np.concatenate([[0], np.cumsum(counts)[:-1]]) / samples
    censored = int(np.sum(made >= steps))
    out = {"samples": samples, "steps": steps, "survival": survival,
           "mean_censored": float(made.mean()), "censored": censored, "failures": kinds}
    if censored == 0:
        out.update(mean=float(made.mean()), standard_error=float(made.std(ddof=1)
                                                                  / math.sqrt(samples)))
    return out


def survival_one_step_exact(scene, design, tolerance: float) -> float:
    """P(a wheel on the orbit makes one more step) when only stalling can end it: the next
    stance vaults iff E_1 = eta^2 E* + step_offset(beta_1) > 0, i.e. beta_1 above the root of
    step_offset = -eta^2 E*, found in closed form (`_inverse_offset`)."""
    from scipy.special import ndtr

    wh = _ramp(scene, design)
    orbit = float(phys.periodic_energy(wh.beta, wh.alpha, wh.eta, wh.rate, wh.loss))
    root = _inverse_offset(wh, -wh.eta**2 * orbit)
    return float(ndtr((wh.beta - root) / sigma_of(tolerance)))


def _inverse_offset(wh: WheelNumbers, value):
    """The chord angle beta (below psi0, where step_offset increases) with step_offset(beta) =
    value: step_offset = rate (eta^2 - 1 + R cos(beta - psi0)), R cos psi0 = cos alpha
    (1 - eta^2), R sin psi0 = sin alpha (1 + eta^2)."""
    a = math.cos(wh.alpha) * wh.loss
    b = math.sin(wh.alpha) * (1.0 + wh.eta**2)
    radius, psi0 = math.hypot(a, b), math.atan2(b, a)
    ratio = (np.asarray(value, float) / wh.rate + wh.loss) / radius
    return psi0 - np.arccos(np.clip(ratio, -1.0, 1.0))


def _interval(pass_fn, lo, hi, nominal, count=801):
    """The passing interval of slopes for each state (rows): the first and last passing points
    of a grid over [lo, hi], refined by bisection; (nan, nan) where none passes."""
    grid = np.linspace(lo, hi, count)
    ok = pass_fn(grid[None, :])  # (states, count)
    any_ok = ok.any(axis=1)
    first = np.where(any_ok, ok.argmax(axis=1), 0)
    last = np.where(any_ok, count - 1 - ok[:, ::-1].argmax(axis=1), 0)

    def refine(inside, outside):
        for _ in range(BISECTIONS):
            mid = 0.5 * (inside + outside)
            good = pass_fn(mid[:, None])[:, 0]
            inside, outside = np.where(good, mid, inside), np.where(good, outside, mid)
        return inside

    low = np.where(first > 0, refine(grid[first], grid[np.maximum(first - 1, 0)]), -np.inf)
    high = np.where(last < count - 1, refine(grid[last], grid[np.minimum(last + 1, count - 1)]),
                    np.inf)
    return np.where(any_ok, low, np.nan), np.where(any_ok, high, np.nan)


def _prob(a, b, mean, sigma):
    """P(a < beta < b) for beta ~ N(mean, sigma), accurate in either tail."""
    from scipy.special import ndtr

    za, zb = (np.asarray(a) - mean) / sigma, (np.asarray(b) - mean) / sigma
    upper = ndtr(-za) - ndtr(-zb)
    return np.maximum(np.where(za > 0.0, upper, ndtr(zb) - ndtr(za)), 0.0)


def _rows(wh: WheelNumbers, states, edges, sigma):
    """Transitions of states E (n,) to bins (edges, n+1: the first and last open-ended),
    and their failure probabilities (pre: the stance ends or the impact fails, no new step;
    post: the next stance fails at its start, after the step)."""
    mean = wh.beta
    span = (mean - SIGMAS * sigma, mean + SIGMAS * sigma)
    e = states[:, None]

    def pre_ok(beta):
        return _pre(wh, e, beta)

    def all_ok(beta):
        return _pre(wh, e, beta) & _post(wh, e, beta)

    plo, phi_ = _interval(pre_ok, *span, mean)
    lo, hi = _interval(all_ok, *span, mean)
    none = np.isnan(lo)
    lo, hi = np.where(none, 0.0, lo), np.where(none, 0.0, hi)
    plo, phi_ = np.where(np.isnan(plo), 0.0, plo), np.where(np.isnan(plo), 0.0, phi_)
    survive = np.where(none, 0.0, _prob(lo, hi, mean, sigma))
    pre_pass = _prob(plo, phi_, mean, sigma)
    post = np.maximum(pre_pass - survive, 0.0)
    pre = 1.0 - pre_pass
    # the slope that takes each state to each inner edge
    cut = _inverse_offset(wh, edges[None, 1:-1] - wh.eta**2 * e)
    a = np.concatenate([np.full((len(states), 1), -np.inf), cut], axis=1)
    b = np.concatenate([cut, np.full((len(states), 1), np.inf)], axis=1)
    a, b = np.maximum(a, lo[:, None]), np.minimum(b, hi[:, None])
    q = np.where((b > a) & ~none[:, None], _prob(a, b, mean, sigma), 0.0)
    return q, pre, post


def _pre(wh, e, beta):
    """Stance ends at beta + alpha and its impact passes (E, beta: broadcast arrays)."""
    ok = point_failures(wh, e, beta + wh.alpha, wh.ground) == OK
    normal, tangential = phys.impact_impulses(wh.eta, wh.alpha, beta, wh.ground)
    return ok & (normal > 0.0) & (np.abs(tangential) <= wh.friction * normal)


def _post(wh, e, beta):
    """The next stance (energy E' after a step on chord beta) starts: `starts`."""
    nxt = wh.eta**2 * e + phys.step_offset(beta, wh.alpha, wh.eta, wh.rate)
    return starts(wh, nxt, beta)


def starts(wh, energy, beta_prev):
    """A stance of energy E starting on chord beta_prev: it vaults (E > 0 when it starts behind
    the vertical) and its forces hold at its start and at its top (the spoke's vertical, when it
    passes it)."""
    phi0 = beta_prev - wh.alpha
    ok = ~((phi0 < 0.0) & (energy <= 0.0))
    ok &= point_failures(wh, energy, phi0, wh.ground) == OK
    top = np.where(phi0 < 0.0, 0.0, phi0)
    return ok & (point_failures(wh, energy, top, wh.ground) == OK)


def chain_mfpt(wh: WheelNumbers, start_energy: float, sigma: float, bins: int) -> float:
    """Mean steps before failure from start_energy by the chain of `bins` energy bins."""
    orbit_low = _orbit(wh, wh.beta - 8 * sigma)
    orbit_high = _orbit(wh, wh.beta + 8 * sigma)
    low = min(orbit_low, 0.0, start_energy)
    high = max(orbit_high, start_energy)
    edges = np.linspace(low, high, bins + 1)
    centres = 0.5 * (edges[:-1] + edges[1:])
    q, pre, post = _rows(wh, centres, edges, sigma)
    # I - Q with its diagonal from the failures and the other bins (row sums kept exact)
    off = q.copy()
    np.fill_diagonal(off, 0.0)
    lhs = -off
    np.fill_diagonal(lhs, pre + post + off.sum(axis=1))
    m = np.linalg.solve(lhs, q.sum(axis=1) + post)
    if not starts(wh, np.array([start_energy]), wh.beta)[0]:
        return 0.0  # the first stance fails whatever the ground
    q0, _, post0 = _rows(wh, np.array([start_energy]), edges, sigma)
    return float(q0[0] @ (1.0 + m) + post0[0])


def _orbit(wh, beta):
    return float(phys.periodic_energy(beta, wh.alpha, wh.eta, wh.rate))


def mfpt(scene, design, tolerance: float, *, bins: int = 400) -> dict:
    """{estimate, ci_low, ci_high, method, coarse, fine}: the mean steps before failure on a
    rough ramp (slope errors of sigma = tolerance / 3), by the Markov chain at `bins` and
    2 bins, extrapolated (module docstring)."""
    wh = _ramp(scene, design)
    start = float(phys.stance_energy(scene.initial.speed, wh.beta - wh.alpha, wh.rate))
    sigma = sigma_of(tolerance)
    if sigma <= 0.0:
        raise ValueError("a rough ramp needs a slope tolerance > 0")
    coarse = chain_mfpt(wh, start, sigma, bins)
    fine = chain_mfpt(wh, start, sigma, 2 * bins)
    if not max(coarse, fine) < MFPT_LIMIT:  # (nan too)
        return {"estimate": math.inf, "ci_low": MFPT_LIMIT, "ci_high": math.inf,
                "method": f"markov chain: beyond {MFPT_LIMIT:g} steps, past the reach of "
                          "double precision", "coarse": coarse, "fine": fine}
    estimate = (4.0 * fine - coarse) / 3.0
    spread = abs(fine - coarse)
    return {"estimate": estimate, "ci_low": min(coarse, fine, estimate) - spread,
            "ci_high": max(coarse, fine, estimate) + spread,
            "method": f"markov chain on stance-energy bins ({bins} and {2 * bins}), Richardson",
            "coarse": coarse, "fine": fine}


def longest_lasting(scene, counts, slope_range, leg_length: float, tolerance: float, *,
                    bins: int = 200) -> dict:
    """The design that lasts longest on a rough ramp (slope errors sigma = tolerance / 3): for
    each spoke count, the slope in slope_range (min, max) of the largest mean first-passage
    time, by a bounded golden-section search on log(mfpt) (the chain at `bins`), then the
    best count's mfpt at bins and 2 bins. {spokes, slope, mfpt (mfpt's dict), by_count:
    {count: (slope, mfpt estimate)}}."""
    from scipy.optimize import minimize_scalar

    from .model import RimlessWheelDesign

    def lasting(n, slope):
        design = RimlessWheelDesign(spokes=n, leg_length=leg_length, slope=float(slope))
        try:
            wh = _ramp(scene, design)
        except ValueError:
            return 0.0
        start = float(phys.stance_energy(scene.initial.speed, wh.beta - wh.alpha, wh.rate))
        return min(chain_mfpt(wh, start, sigma_of(tolerance), bins), MFPT_LIMIT)

    by_count = {}
    for n in counts:
        found = minimize_scalar(lambda s, n=n: -math.log(max(lasting(n, s), 1e-300)),
                                bounds=slope_range, method="bounded",
                                options={"xatol": 1e-5 * (slope_range[1] - slope_range[0])})
        by_count[n] = (float(found.x), float(math.exp(-found.fun)))
    best = max(by_count, key=lambda n: by_count[n][1])
    slope = by_count[best][0]
    design = RimlessWheelDesign(spokes=best, leg_length=leg_length, slope=slope)
    return {"spokes": best, "slope": slope, "mfpt": mfpt(scene, design, tolerance, bins=bins),
            "by_count": by_count}
