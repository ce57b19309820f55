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
BISECTIONS = 52  # from the grid's spacing (0.5 sigma) to below a rounding of the slope
FULL = (16, BISECTIONS)  # a state passing nowhere on the grid is looked at 16 times finer


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
    (1 - eta^2), R sin psi0 = sin alpha (1 + eta^2). The wheel's numbers may be columns."""
    a = np.cos(wh.alpha) * wh.loss
    b = np.sin(wh.alpha) * (1.0 + wh.eta**2)
    radius, psi0 = np.hypot(a, b), np.arctan2(b, a)
    ratio = (np.asarray(value, float) / wh.rate + wh.loss) / radius
    return psi0 - np.arccos(np.clip(ratio, -1.0, 1.0))


NUMBERS = ("alpha", "leg", "k2", "eta", "loss", "rate", "beta", "ground")  # WheelNumbers' arrays


def stacked(wheels, repeat: int = 1) -> WheelNumbers:
    """The wheels as one WheelNumbers whose numbers are columns (len(wheels) * repeat, 1): each
    wheel's repeated `repeat` times (the physics broadcasts over them)."""
    import dataclasses

    first = wheels[0]
    return dataclasses.replace(first, **{
        name: np.repeat([float(getattr(w, name)) for w in wheels], repeat)[:, None]
        for name in NUMBERS})


def _take(wh: WheelNumbers, rows) -> WheelNumbers:
    """The rows of a stacked WheelNumbers (a wheel of plain numbers as it is)."""
    import dataclasses

    if np.ndim(wh.beta) == 0:
        return wh
    return dataclasses.replace(wh, **{name: getattr(wh, name)[rows] for name in NUMBERS})


def _ends(ok, grid):
    """For each row of ok (tests on the grid): its first and last passing points, their
    neighbours outside, whether they are the grid's ends, and whether any passes."""
    count = len(grid)
    any_ok = ok.any(axis=1)
    first = np.where(any_ok, ok.argmax(axis=1), 0)
    last = np.where(any_ok, count - 1 - ok[:, ::-1].argmax(axis=1), 0)
    return (np.stack([grid[first], grid[last]], axis=1),
            np.stack([grid[np.maximum(first - 1, 0)], grid[np.minimum(last + 1, count - 1)]],
                     axis=1),
            np.stack([first == 0, last == count - 1], axis=1), any_ok)


def _grid_ends(pass_fn, count, fine):
    """_ends of each test on a grid of `count` standardised slope errors z over [-SIGMAS,
    SIGMAS]; the states where a test passes nowhere on it are looked at again on a grid `fine`
    times as fine (a passing interval narrower than the coarse spacing, 2 SIGMAS /
    (count - 1), is not missed)."""
    grid = np.linspace(-SIGMAS, SIGMAS, count)
    ends = [list(_ends(ok, grid)) for ok in pass_fn(grid[None, :])]
    missing = ~np.logical_and.reduce([found for *_, found in ends])
    if fine > 1 and missing.any():
        rows = np.flatnonzero(missing)
        finer = np.linspace(-SIGMAS, SIGMAS, (count - 1) * fine + 1)
        for each, ok in zip(ends, pass_fn(finer[None, :], rows)):
            for part, value in zip(each, _ends(ok, finer)):
                part[rows] = value
    return ends


def _intervals(pass_fn, look=None, count=49):
    """The passing intervals of standardised slope errors z for each state (rows) of the tests
    pass_fn gives ((states, m) z, rows -> a tuple of (states, m) booleans, one a test): for
    each test the first and last passing points of a grid (`_grid_ends`), refined by bisection
    (all the ends of all the tests at once); (nan, nan) where none passes, -inf / inf where the
    grid's end passes. [(low, high) a test]."""
    fine, bisections = look or FULL
    ends = _grid_ends(pass_fn, count, fine)
    inside = np.concatenate([e[0] for e in ends], axis=1)
    outside = np.concatenate([e[1] for e in ends], axis=1)
    for _ in range(bisections):
        mid = 0.5 * (inside + outside)
        results = pass_fn(mid)
        good = np.stack([results[j // 2][:, j] for j in range(mid.shape[1])], axis=1)
        inside, outside = np.where(good, mid, inside), np.where(good, outside, mid)
    out = []
    for t, (_, _, open_end, any_ok) in enumerate(ends):
        low = np.where(open_end[:, 0], -np.inf, inside[:, 2 * t])
        high = np.where(open_end[:, 1], np.inf, inside[:, 2 * t + 1])
        out.append((np.where(any_ok, low, np.nan), np.where(any_ok, high, np.nan)))
    return out


def _prob(za, zb):
    """P(za < z < zb) for a standard normal z, accurate in either tail."""
    from scipy.special import ndtr

    za, zb = np.asarray(za), np.asarray(zb)
    upper = ndtr(-za) - ndtr(-zb)
    return np.maximum(np.where(za > 0.0, upper, ndtr(zb) - ndtr(za)), 0.0)


def _rows(wh: WheelNumbers, states, edges, sigma, look=None):
    """Transitions of states E (n,) to bins (edges, (n, B + 1) or (B + 1,): the first and last
    open-ended), and their failure probabilities (pre: the stance ends or the impact fails, no
    new step; post: the next stance fails at its start, after the step). wh: one wheel, or
    one a state (`stacked`), each on its own ramp (wh.beta, the errors' mean)."""
    mean = wh.beta
    e = states[:, None]

    def tests(z, rows=slice(None)):
        at = _take(wh, rows)
        beta = at.beta + sigma * z
        pre = _pre(at, e[rows], beta)
        return pre, pre & _post(at, e[rows], beta)

    (plo, phi_), (lo, hi) = _intervals(tests, look)
    none = np.isnan(lo)
    lo, hi = np.where(none, 0.0, lo), np.where(none, 0.0, hi)
    plo, phi_ = np.where(np.isnan(plo), 0.0, plo), np.where(np.isnan(plo), 0.0, phi_)
    survive = np.where(none, 0.0, _prob(lo, hi))
    pre_pass = _prob(plo, phi_)
    post = np.maximum(pre_pass - survive, 0.0)
    pre = 1.0 - pre_pass
    # the slope error that takes each state to each inner edge
    edges = np.atleast_2d(edges)
    cut = (_inverse_offset(wh, edges[:, 1:-1] - wh.eta**2 * e) - mean) / sigma
    a = np.concatenate([np.full((len(states), 1), -np.inf), cut], axis=1)
    b = np.concatenate([cut, np.full((len(states), 1), np.inf)], axis=1)
    a, b = np.maximum(a, lo[:, None]), np.minimum(b, hi[:, None])
    q = np.where((b > a) & ~none[:, None], _prob(a, b), 0.0)
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
    return float(chain_mfpts([wh], np.array([start_energy]), sigma, bins)[0])


def chain_mfpts(wheels, start_energies, sigma: float, bins: int, look=None):
    """chain_mfpt of each wheel (WheelNumbers on its own ramp, wh.beta = wh.ground) from its
    start energy, all the chains built at once. look: (fine, bisections) of the passing
    intervals (`_grid_ends`, `_intervals`): FULL by default, coarser for a search."""
    starts_e = np.asarray(start_energies, float)
    k = len(wheels)
    each = stacked(wheels)  # (K, 1) columns
    slopes = each.beta[:, 0]
    low = np.minimum(np.minimum(_orbit(each, each.beta - 8 * sigma)[:, 0], 0.0), starts_e)
    high = np.maximum(_orbit(each, each.beta + 8 * sigma)[:, 0], starts_e)
    edges = np.linspace(low, high, bins + 1, axis=1)  # (K, bins + 1)
    centres = 0.5 * (edges[:, :-1] + edges[:, 1:])
    q, pre, post = _rows(stacked(wheels, bins), centres.ravel(), np.repeat(edges, bins, axis=0),
                         sigma, look)
    q, pre, post = q.reshape(k, bins, bins), pre.reshape(k, bins), post.reshape(k, bins)
    # I - Q with its diagonal from the failures and the other bins (row sums kept exact)
    diagonal = np.arange(bins)
    off = q.copy()
    off[:, diagonal, diagonal] = 0.0
    lhs = -off
    lhs[:, diagonal, diagonal] = pre + post + off.sum(axis=2)
    with _blas_one_thread():
        m = np.linalg.solve(lhs, (q.sum(axis=2) + post)[..., None])[..., 0]
    # the first stance fails whatever the ground: 0 steps
    vaults = starts(each, starts_e[:, None], slopes[:, None])[:, 0]
    q0, _, post0 = _rows(each, starts_e, edges, sigma, look)
    return np.where(vaults, np.einsum("kb,kb->k", q0, 1.0 + m) + post0, 0.0)


def _blas_one_thread():
    """numpy's BLAS on one thread for the chain's solve, then as it was (threadpoolctl): a
    system of a few hundred unknowns gains nothing from a second thread, and a woken worker
    that spins after the call takes a core from the numpy work that follows (several times
    slower on a busy machine)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def _orbit(wh, beta):
    return phys.periodic_energy(beta, wh.alpha, wh.eta, wh.rate)


def mfpt(scene, design, tolerance: float, *, bins: int = 400, coarse=None) -> dict:
    """{estimate, ci_low, ci_high, method, coarse, fine}: the mean steps before failure on a
    rough ramp (slope errors of sigma = tolerance / 3), by the Markov chain at `bins` and
    2 bins, extrapolated (module docstring). coarse: the chain at `bins`, when known."""
    wh = _ramp(scene, design)
    start = float(phys.stance_energy(scene.initial.speed, wh.beta - wh.alpha, wh.rate))
    sigma = sigma_of(tolerance)
    if sigma <= 0.0:
        raise ValueError("a rough ramp needs a slope tolerance > 0")
    coarse = chain_mfpt(wh, start, sigma, bins) if coarse is None else coarse
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


# The search for the longest-lasting slope of each spoke count (longest_lasting): a look over
# COARSE_SLOPES slopes of every count on coarse chains, then a zoom on finer chains about the
# best slope of each count that comes within REFINE_WITHIN of the best count's coarse figure.
# The search's passing intervals are bisected 12 and 20 times (ends to 0.5 sigma / 2^12 and
# / 2^20: a probability within 2e-7 in the zoom), and the zoom looks again 4 times finer (not 16)
# where a state passes nowhere (it can miss an interval narrower than sigma / 8, a survival below
# 0.05 from a state at a bin's edge): enough to rank slopes; the chosen design's mfpt is then
# computed with the full look (FULL, ends to rounding).
COARSE_SLOPES, COARSE_BINS, COARSE_LOOK = 17, 30, (1, 12)
ZOOM_SLOPES, ZOOMS, ZOOM_LOOK = 5, 2, (4, 20)
REFINE_WITHIN = 1e-2


def _wheel_at(scene, spokes, leg_length, slope):
    """WheelNumbers of a wheel on a ramp, or None where the design is refused."""
    from .model import RimlessWheelDesign

    try:
        return _ramp(scene, RimlessWheelDesign(spokes=spokes, leg_length=leg_length,
                                               slope=float(slope)))
    except ValueError:
        return None


def _lasting(scene, pairs, sigma, bins, look=None):
    """The chain's mean steps of each (wheel, slope) of `pairs`, all at once (at least 1e-300,
    at most MFPT_LIMIT: log-friendly)."""
    import dataclasses

    wheels = [dataclasses.replace(wh, beta=float(s), ground=float(s)) for wh, s in pairs]
    starts_e = [phys.stance_energy(scene.initial.speed, w.beta - w.alpha, w.rate)
                for w in wheels]
    found = chain_mfpts(wheels, starts_e, sigma, bins, look)
    return np.clip(np.nan_to_num(found, nan=0.0), 1e-300, MFPT_LIMIT)


def _zoom(scene, wheels, brackets, sigma, bins):
    """{count: (slope, mean steps)}: the largest mean steps in each count's bracket: ZOOMS
    rounds of ZOOM_SLOPES slopes spanning it on the chain of `bins` bins (every count at once),
    each narrowing it to the best one's neighbours (a count whose best falls below
    REFINE_WITHIN of the round's best count's stops there), then the vertex of the parabola
    through log(mean steps) at the last round's best three (kept when it is better)."""
    counts, out, last = list(brackets), {}, {}
    for round_ in range(ZOOMS):
        grids = {n: np.linspace(*brackets[n], ZOOM_SLOPES) for n in counts}
        values = _lasting(scene, [(wheels[n], s) for n in counts for s in grids[n]], sigma,
                          bins, ZOOM_LOOK).reshape(len(counts), ZOOM_SLOPES)
        for n, row in zip(counts, values):
            i = int(np.argmax(row))
            out[n] = (float(grids[n][i]), float(row[i]))
            last[n] = (i, row, grids[n])
            brackets[n] = (grids[n][max(i - 1, 0)], grids[n][min(i + 1, ZOOM_SLOPES - 1)])
        if round_ + 1 < ZOOMS:
            top = max(out[n][1] for n in counts)
            counts = [n for n in counts if out[n][1] >= REFINE_WITHIN * top]
    vertices = {}
    for n in counts:
        i, row, grid = last[n]
        y = np.log(row[max(i - 1, 0): i + 2])
        if 0 < i < ZOOM_SLOPES - 1 and (bend := y[0] - 2.0 * y[1] + y[2]) < 0.0:
            vertices[n] = grid[i] + 0.5 * (grid[1] - grid[0]) * (y[0] - y[2]) / bend
    if vertices:
        values = _lasting(scene, [(wheels[n], v) for n, v in vertices.items()], sigma, bins)
        for (n, v), value in zip(vertices.items(), values):
            if value > out[n][1]:
                out[n] = (float(v), float(value))
    return out


def longest_lasting(scene, counts, slope_range, leg_length: float, tolerance: float, *,
                    bins: int = 200) -> dict:
    """The design that lasts longest on a rough ramp (slope errors sigma = tolerance / 3): for
    each spoke count, the slope in slope_range (min, max) of the largest mean first-passage
    time: the chain at COARSE_BINS bins over COARSE_SLOPES slopes of every count, then, for
    each count whose best there is within REFINE_WITHIN of the best count's, a zoom about it on
    the chain at bins / 2 (`_zoom`); then the best count's mfpt at bins and 2 bins.
    {spokes, slope, mfpt (mfpt's dict), by_count: {count: (slope, mfpt at bins / 2, or at
    COARSE_BINS for a count not zoomed on)}, refined: the counts zoomed on}."""
    from .model import RimlessWheelDesign

    sigma = sigma_of(tolerance)
    grid = np.linspace(slope_range[0], slope_range[1], COARSE_SLOPES)
    wheels = {n: wh for n in counts
              if (wh := _wheel_at(scene, n, leg_length, grid[0])) is not None}
    if not wheels:
        raise ValueError("no spoke count of the range makes a wheel")
    coarse = _lasting(scene, [(wh, s) for wh in wheels.values() for s in grid], sigma,
                      COARSE_BINS, COARSE_LOOK).reshape(len(wheels), COARSE_SLOPES)
    top = float(coarse.max())
    by_count, brackets = {}, {}
    for n, values in zip(wheels, coarse):
        i = int(np.argmax(values))
        by_count[n] = (float(grid[i]), float(values[i]))
        if values[i] >= REFINE_WITHIN * top:
            brackets[n] = (grid[max(i - 1, 0)], grid[min(i + 1, COARSE_SLOPES - 1)])
    by_count.update(_zoom(scene, wheels, brackets, sigma, max(bins // 2, 2)))
    best = max(brackets, key=lambda n: by_count[n][1])
    slope = by_count[best][0]
    design = RimlessWheelDesign(spokes=best, leg_length=leg_length, slope=slope)
    return {"spokes": best, "slope": slope, "mfpt": mfpt(scene, design, tolerance, bins=bins),
            "by_count": by_count, "refined": sorted(brackets)}
