"""Steps before failure on rough ground when failures are rare: forward flux sampling (Allen,
Warren & ten Wolde 2005), a multilevel splitting on the distance to failure.

Every step's ground is drawn from the spec's tolerances (its slope; on stairs its rise), the
walker's post-strike state is the chain's state, and a fall ends it. The distance of a state
from the gait is its Mahalanobis distance lam(x) under the covariance of the states a flux run
visits after BURN steps (its null directions dropped: the states lie on a 3-D section). A is
lam < lam_A (the 90 % quantile of those states' distances).

* The flux run: `walkers` walkers from the start state for `steps` steps (a fallen walker stays
  down). At step s: N_s walkers standing, D_s of them falling from a state in A at step s + 1,
  E_s leaving A then (a state in A followed by one with lam >= lam_A; the start counts as in
  A), whose states are kept.
* The levels: `trials` walkers from exit states drawn at random walk until they are back in A
  or fall. The next level is the 80 % quantile of the largest lam each reached (a fall counts as
  beyond every level); f_i: the fraction that fell before reaching it, r_i: that reached it
  (their first states there start the next stage). When a fifth of the trials fall first, the
  last stage's f_n is its fraction of falls. P = P(a fall before A | an exit) = f_0 + r_0 (f_1 +
  r_1 (... + r_{n-1} f_n)).
* The hazard of step s + 1, h_s = (D_s + E_s P) / N_s, over the first BURN steps; beyond, the
  settled hazard k pooled over the rest of the run (the walkers standing then are spread as the
  quasi-stationary law), geometric: survival S_t = prod_{s<t} (1 - h_s), and the mean steps
  before a fall sum_{t>=1} S_t = sum_{t<BURN} S_t + S_BURN / k (`mean_steps`).

`batches` independent runs (each its own flux run, distance and levels; the flux runs walked
side by side) give the estimate (1 / the mean of their 1 / mean) and its 95 % interval
(Student's t on those). The levels are chosen from the trials they split (adaptive): a bias of
the order of 1 / trials per level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import fastmap
from .builds import starts_of
from .ground import params_for

QUANTILE_A = 0.9  # lam_A: this quantile of the flux run's distances
REACH = 0.2  # the fraction of a stage's trials that reach the next level
LAST = 0.2  # a stage where this fraction fall before any next level is the last
MAX_LEVELS = 40
BURN = 20  # flux-run steps before its walkers' states are taken as settled (the QSD)
MAX_TRIAL_STEPS = 400  # a trial still out of A and standing after this many steps: back in A


@dataclass
class Ground:
    """A design's rough ground: each step's slope and rise (per leg length; None on a ramp)
    drawn from the step tolerances, and start states drawn from the start ones."""

    scene: object
    design: object
    tolerances: tuple

    def __post_init__(self):
        self.params = params_for(self.scene, self.design)
        self.each = {t.quantity: t for t in self.tolerances if t.applies_to == "each"}
        self.lots = {t.quantity: t for t in self.tolerances if t.applies_to == "lot"}

    def _noise(self, rng, name, n):
        t = self.each.get(name)
        if t is None:
            return np.zeros(n)
        if t.distribution == "uniform":
            return rng.uniform(-t.value, t.value, n)
        return rng.normal(0.0, t.sigma, n)

    def starts(self, rng, n: int) -> np.ndarray:
        dev = {}
        for name, t in self.lots.items():
            dev[name] = (rng.uniform(-t.value, t.value, n) if t.distribution == "uniform"
                         else rng.normal(0.0, t.sigma, n))
        return starts_of(self.scene, dev, n)

    def step(self, x: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray]:
        """One step of every row of x (n x 4) on its own drawn ground: (after, fell)."""
        n = len(x)
        d = self.design
        if d.slope is not None:
            gamma, rise = d.slope + self._noise(rng, "slope", n), None
        else:
            gamma = self._noise(rng, "slope", n)
            rise = (float(d.rise) + self._noise(rng, "rise", n)) / self.params.l
        after, code = fastmap._step(self.params, x.T.copy(), gamma, self.scene.friction, rise)
        return after.T, code >= 0


class Distance:
    """lam(x): the Mahalanobis distance under the covariance of `states` (rows)."""

    def __init__(self, states):
        self.mean = states.mean(axis=0)
        values, vectors = np.linalg.eigh(np.cov(states.T))
        keep = values > 1e-9 * values.max()
        self.scaled = vectors[:, keep] / np.sqrt(values[keep])

    def __call__(self, x):
        return np.linalg.norm((np.asarray(x) - self.mean) @ self.scaled, axis=-1)


def flux_runs(ground: Ground, rng, walkers: int, steps: int, batches: int) -> list[dict]:
    """`batches` independent flux runs (module docstring), walked side by side: each run's
    per-step counts, its exit states and its distance lam."""
    x = ground.starts(rng, walkers * batches)
    states, alive = [x.copy()], [np.ones(len(x), dtype=bool)]
    for _ in range(steps):
        now = alive[-1].copy()
        idx = np.flatnonzero(now)
        after, down = ground.step(x[idx], rng)
        x[idx] = after
        now[idx[down]] = False
        states.append(x.copy())
        alive.append(now)
    states, alive = np.array(states), np.array(alive)  # (steps + 1, walkers, ...)
    return [_flux(states[:, cols], alive[:, cols])
            for cols in np.split(np.arange(walkers * batches), batches)]


def _flux(states, alive) -> dict:
    """N_s walkers standing after s steps, D_s of them falling from A at step s + 1, E_s leaving
    A then; the exit states, lam and lam_A."""
    lam = Distance(states[BURN:][alive[BURN:]])
    dist = lam(states)
    lam_a = float(np.quantile(dist[BURN:][alive[BURN:]], QUANTILE_A))
    inside = dist < lam_a
    inside[0] = True  # the start counts as in A
    was = alive[:-1] & inside[:-1]
    out = was & alive[1:] & ~inside[1:]
    return {"N": alive[:-1].sum(axis=1), "D": (was & ~alive[1:]).sum(axis=1),
            "E": out.sum(axis=1), "exits": states[1:][out], "lam": lam, "lam_a": lam_a}


def mean_steps(run: dict, p: float) -> tuple[float, float]:
    """(mean steps before a fall, the long-run falls per step k) of one flux run with P(a fall
    before A | an exit) = p: the hazard of step s + 1, h_s = (D_s + E_s p) / N_s, over the first
    BURN steps, k pooled over the rest; survival S_t = prod_{s<t} (1 - h_s) and the mean
    sum_{t>=1} S_t = sum_{t<BURN} S_t + S_BURN / k (geometric beyond BURN)."""
    n, d, e = run["N"], run["D"], run["E"]
    rate = (d + e * p) / np.maximum(n, 1)
    k = float((d[BURN:] + e[BURN:] * p).sum() / max(n[BURN:].sum(), 1))
    survival = np.cumprod(1.0 - rate[:BURN])  # S_1 .. S_BURN
    if k <= 0.0:
        return math.inf, 0.0
    return float(survival[:-1].sum() + survival[-1] / k), k


def _trials(ground, rng, starts, lam, lam_a):
    """Walk every start until back in A or fallen: (states (steps, n, 4), their lam with
    -inf once a trial ended, fell)."""
    x, n = starts.copy(), len(starts)
    alive = np.ones(n, dtype=bool)
    fell = np.zeros(n, dtype=bool)
    path, dist = [x.copy()], [lam(x)]
    for _ in range(MAX_TRIAL_STEPS):
        idx = np.flatnonzero(alive)
        if idx.size == 0:
            break
        after, down = ground.step(x[idx], rng)
        x[idx] = after
        fell[idx[down]] = True
        d = np.full(n, -np.inf)
        d[idx] = np.where(down, -np.inf, lam(after))
        alive[idx] = ~down & (d[idx] >= lam_a)
        path.append(x.copy())
        dist.append(d)
    return np.array(path), np.array(dist), fell


def fall_probability(ground, rng, exits, lam, lam_a, trials: int, *, reach: float = REACH,
                     last: float = LAST) -> tuple[float, int]:
    """P(a fall before A | an exit state) by the nested stages (module docstring), and the
    number of levels."""
    starts = exits[rng.integers(0, len(exits), trials)]
    stages, level = [], lam_a
    for _ in range(MAX_LEVELS):
        path, dist, fell = _trials(ground, rng, starts, lam, lam_a)
        top = np.where(fell, np.inf, dist.max(axis=0))
        nxt = float(np.quantile(top, 1.0 - reach, method="higher"))
        if fell.mean() >= last or not np.isfinite(nxt) or nxt <= level:
            stages.append((float(fell.mean()), 0.0))
            break
        over = dist >= nxt
        reached = over.any(axis=0)
        first = over.argmax(axis=0)
        stages.append((float((fell & ~reached).mean()), float(reached.mean())))
        picked = np.flatnonzero(reached)
        cross = path[first[picked], picked]
        starts, level = cross[rng.integers(0, len(cross), trials)], nxt
    p = 0.0
    for f, r in reversed(stages):
        p = f + r * p
    return p, len(stages)


def mfpt(scene, design, tolerances, *, walkers: int = 200, steps: int = 60,
         trials: int = 1000, batches: int = 4, seed: int = 0, reach: float = REACH,
         last: float = LAST) -> dict:
    """{estimate, ci_low, ci_high, method, rates, levels}: the mean steps a walker makes before a
    fall on the rough ground of `tolerances` (module docstring); reach and last: the levels'
    REACH and LAST."""
    from scipy.stats import t as student

    if steps <= BURN:
        raise ValueError(f"a flux run needs more than {BURN} steps")
    ground = Ground(scene, design, tuple(tolerances))
    rng = np.random.default_rng([seed, 7])
    rates, levels = [], []
    for run in flux_runs(ground, rng, walkers, steps, batches):
        p, n = (fall_probability(ground, rng, run["exits"], run["lam"], run["lam_a"], trials,
                                 reach=reach, last=last) if len(run["exits"]) else (0.0, 0))
        rates.append(1.0 / mean_steps(run, p)[0])
        levels.append(n)
    r = float(np.mean(rates))
    half = float(student.ppf(0.975, batches - 1) * np.std(rates, ddof=1) / math.sqrt(batches))
    return {"estimate": 1.0 / r if r > 0 else math.inf,
            "ci_low": 1.0 / (r + half),
            "ci_high": 1.0 / (r - half) if r - half > 0 else math.inf,
            "method": f"forward flux sampling on the distance from the gait ({batches} runs "
                      f"of {walkers} walkers x {steps} steps, {trials} trials a level, up to "
                      f"{max(levels)} levels)",
            "rates": rates, "levels": levels}
