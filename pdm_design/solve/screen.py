"""The screened multistart: IPOPT only from the sampled designs that can lead somewhere new.

Where every IPOPT iteration walks a long chain (a row's linearised yield, docs/optimizer.md
section 10) the 8 starts of the plain multistart, each run to convergence, are most of the
cost, and on the yield's smooth landscape they end at one optimum. Multi-level single linkage
(Rinnooy Kan and Timmer 1987) keeps the multistart's reach at the cost of a sample: SAMPLE
designs (the guess, then the multistart's own scrambled-Sobol points and more of them) are
evaluated (the objective and the rows, no derivatives), and a local search starts from a
sampled design only when no better one lies within the critical distance

    r = pi^(-1/2) (Gamma(1 + n / 2) SIGMA log N / N)^(1 / n)

of it (in units of each variable's bounds; n free variables, N designs sampled; SIGMA = 4,
above which the method's expected number of local searches stays finite as N grows): a
design with a better one that near lies in a basin a better start already reaches. The guess
(and a `start_from` design) always runs, better designs first, at most `starts` runs in all.
Deterministic: the sample is fixed by the seed, so one spec gives one set of starts and one
answer every run (the tie-break still picks one design of a flat optimum).

A yield target's objective is its scale s (formulation/yield_target.py), which a sampled
design does not carry: each is scored, and started, at its own largest s meeting the target
(target_scales), and ranked by that.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..formulation.yield_target import AUX, CONDITION

SAMPLE = 32  # designs sampled
SIGMA = 4.0
ROOT = 1e-9  # a sampled design's score: its nines row within this of its bound
ITERATIONS = 100  # at most, of the root find
EVALUATIONS = 20  # of the rows, about, in a root find (to judge its cost)
SPLIT_SECONDS = 1.0  # root finds longer than this in one process are split among the cores


def radius(n: int, sampled: int) -> float:
    """MLSL's critical distance in the unit cube (module docstring)."""
    if n == 0 or sampled < 2:
        return math.inf
    volume = math.gamma(1.0 + n / 2.0) * SIGMA * math.log(sampled) / sampled
    return volume ** (1.0 / n) / math.sqrt(math.pi)


def screened(form, p, sample: list[np.ndarray], always: int, starts: int) -> list[np.ndarray]:
    """The NLP start points to run of `sample` (NLP start vectors; the first `always` run
    whatever the sample shows): MLSL's rule (module docstring), better designs first."""
    from .tiebreak import form_objective

    n = form.n_design
    sample = at_target_scales(form, p, sample)  # scored at its own largest scale
    xs = np.column_stack(sample)
    f = np.asarray(form_objective(form).map(len(sample))(xs, p), float).ravel()
    g = np.asarray(_rows(form).map(len(sample))(xs, p), float)
    violation = np.max(np.maximum(form.lbg[:, None] - g, g - form.ubg[:, None]), axis=0,
                       initial=0.0)
    usable = np.isfinite(f) & np.isfinite(violation)
    # better: feasible (to IPOPT's scale of a row) first, then the lower objective
    order = sorted(range(len(sample)), key=lambda k: (not usable[k], violation[k] > 1e-6,
                                                       violation[k] if violation[k] > 1e-6
                                                       else f[k]))
    rank = np.empty(len(sample), int)
    rank[order] = np.arange(len(sample))
    span = form.ubx[:n] - form.lbx[:n]
    span = np.where(np.isfinite(span) & (span > 0.0), span, 1.0)
    unit = (xs[:n] - form.lbx[:n, None]) / span[:, None]
    r = radius(n, len(sample))
    chosen = list(range(min(always, len(sample))))
    for k in order:
        if len(chosen) >= starts:
            break
        if k in chosen or not usable[k]:
            continue
        near = np.sqrt(np.sum((unit - unit[:, [k]]) ** 2, axis=0)) <= r
        if not np.any(near & (rank < rank[k])):
            chosen.append(k)
    return [sample[k] for k in chosen]


def at_target_scales(form, p, starts: list[np.ndarray]) -> list[np.ndarray]:
    """The start points `starts` (NLP start vectors), a yield target's scale s in each set to
    that design's largest s meeting the target (target_scales); unchanged without a target.
    The designs are split among the local cores (forked processes: the same scales) where
    their root finds would take more than SPLIT_SECONDS in one."""
    if target_row(form) is None or not starts:
        return starts
    from ..tolerances.parallel import forked_map, local_workers

    xs = np.column_stack(starts)
    tic = time.perf_counter()  # one design's row, to judge whether splitting pays
    _rows(form)(xs[:, 0], p)
    cost = EVALUATIONS * len(starts) * (time.perf_counter() - tic)
    workers = local_workers() if cost > SPLIT_SECONDS else 1
    parts = [c for c in np.array_split(np.arange(len(starts)), workers) if len(c)]
    scales = forked_map(lambda cols: target_scales(form, p, xs[:, cols]), parts, workers)
    xs[form.x_names.index(AUX)] = np.log(np.concatenate(scales))  # the NLP's z = log s
    return [xs[:, k].copy() for k in range(len(starts))]


def target_row(form) -> int | None:
    """The index in g of a yield target's nines row (formulation/yield_target.py), or None."""
    if AUX not in getattr(form, "x_names", ()):
        return None
    return next((c.index for c in form.conditions if CONDITION in c.keys), None)


def target_scales(form, p, xs: np.ndarray) -> np.ndarray:
    """Each sampled design's (the columns of NLP start vectors `xs`) largest scale s at which
    its nines row holds, to ROOT of the row: the yield falls as s grows, so a root find in
    log s bracketed by the scale's bounds, narrowed first halfway in log s, every design at
    once (regula falsi, Illinois' halving of a kept end's value; bisection where an end's row
    is not finite). The lower bound where the row does not hold there (the design then ranks
    by its violation), the upper where it holds there."""
    from ..formulation.yield_target import SCALE_BOUNDS

    k, row = form.x_names.index(AUX), target_row(form)
    fn, maps = _rows(form), {}
    xs = np.array(xs, float)

    def value(logs, busy=None):
        """The row at the scales exp(logs), of the `busy` designs only (NaN elsewhere)."""
        busy = np.ones(xs.shape[1], bool) if busy is None else busy
        out = np.full(xs.shape[1], np.nan)
        m = int(busy.sum())
        if m:
            x = xs[:, busy]
            x[k] = logs[busy]  # the NLP's variable is log s
            rows = maps.setdefault(m, fn.map(m))
            with np.errstate(all="ignore"):  # a chain undefined at a large scale: NaN
                # the row is log(nines / need): its exp - 1, nines / need - 1, has no
                # logarithm's steep fall where the nines are few, which regula falsi likes
                out[busy] = np.expm1(np.asarray(rows(x, p), float)[row] - form.lbg[row])
        return out

    ends = [np.full(xs.shape[1], math.log(b)) for b in SCALE_BOUNDS]
    lo, hi = ends
    glo, ghi = value(lo), value(hi)
    mid = 0.5 * (lo + hi)
    lo, hi, glo, ghi = _narrowed(lo, hi, glo, ghi, mid, value(mid))
    true = glo.copy()  # the row at lo (glo is halved as Illinois' rule asks)
    last = np.zeros(xs.shape[1])  # the end kept by the last step: 1 hi, -1 lo
    for _ in range(ITERATIONS):
        busy = (glo >= 0.0) & ~(ghi >= 0.0) & (true > ROOT) & (hi - lo > 1e-14)
        if not busy.any():
            break
        finite = np.isfinite(glo) & np.isfinite(ghi)
        with np.errstate(all="ignore"):
            falsi = (lo * -ghi + hi * glo) / (glo - ghi)
        mid = np.where(finite & np.isfinite(falsi), falsi, 0.5 * (lo + hi))
        mid = np.clip(mid, lo + 1e-3 * (hi - lo), hi - 1e-3 * (hi - lo))
        gmid = np.where(busy, value(mid, busy), np.nan)
        mid = np.where(busy, mid, np.where(glo >= 0.0, lo, hi))
        gmid = np.where(busy, gmid, np.where(glo >= 0.0, glo, ghi))
        held = gmid >= 0.0
        kept = np.where(held, 1.0, -1.0)
        lo, hi, glo, ghi = _narrowed(lo, hi, glo, ghi, mid, gmid)
        true = np.where(held & busy, gmid, true)
        again = kept == last  # the same end kept twice: its value halved (Illinois)
        ghi = np.where(again & held, 0.5 * ghi, ghi)
        glo = np.where(again & ~held, 0.5 * glo, glo)
        last = kept
    low, high = (math.log(b) for b in SCALE_BOUNDS)
    out = np.where(glo >= 0.0, lo, low)
    return np.exp(np.where(ghi >= 0.0, high, out))


def _narrowed(lo, hi, glo, ghi, mid, gmid):
    """The bracket [lo, hi] (row held at lo, not at hi) with `mid` in place of its end."""
    held = gmid >= 0.0
    return (np.where(held, mid, lo), np.where(held, hi, mid), np.where(held, gmid, glo),
            np.where(held, ghi, gmid))


def _rows(form):
    """The NLP's rows as a Function (x, p) (cached per formulation)."""
    import casadi as ca

    from .tiebreak import _OBJECTIVES

    key = form.key + " rows"
    fn = _OBJECTIVES.get(key)
    if fn is None:
        fn = ca.Function("g", [form.nlp["x"], form.nlp["p"]], [form.nlp["g"]])
        _OBJECTIVES[key] = fn
    return fn
