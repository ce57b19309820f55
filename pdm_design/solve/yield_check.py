"""Tolerances sized for a yield target, checked by Monte Carlo (docs/optimizer.md section 10).

The linearised yield that sizes the allocated tolerances (solve/yield_allocation.py at a fixed
design, formulation/yield_target.py with the design) is a model: a union bound (or Hunter's
bound) of first-order spreads with a second-order mean. The Monte Carlo yield is the judge: the
yield engine of `pdm-design yield` (tolerances.yield_.yield_of: the closed-form map, the event
simulator on every build outside it and on `confirm` random others) with the spec's `builds`,
`seed` and `confirm`, so that `pdm-design yield` of the answer is the same run.

Where the 95 % interval's lower end is below the target, every allocated tolerance is shrunk
by one common factor c (the given ones kept), the design fixed. c = 1 is checked first; then
the factors of LADDER in turn, down to TINY (the design with its given tolerances alone, near
enough), until one meets the target; then STEPS bisections of c between it and the factor above
it that did not. The ladder, not a bisection from TINY, because the yield need not rise as the
tolerances shrink: a design centred for the pivots' drift can drift the other way with the
pivots exact (solve/yield_allocation.py), and the 100-stage row passes fewer builds with its
pivots exact than at their linearised size. When no factor meets the target, `words` say why
and the factor reported is the one whose lower end came nearest. The builds are the same at
every c (common random numbers: build i's uniform numbers are fixed by the seed, and an
allocated quantity's deviation is c times the one at c = 1), so the estimate moves with c only
through the builds whose verdict c changes, and the bisection does not chase sampling noise.
The answer is always a factor that was checked: its run is the one reported.

On long runs (SCREEN_ENTRIES builds x stages and more) a run costs seconds of the event
simulator, and the search runs on a screen instead (_screen): the builds at risk at c = 1,
mapped at a rung and its bisection grid at once; one run judges the factor it finds, and the
ladder goes on below that factor only where that run does not meet the target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

TINY = 1e-3  # the factor that stands for the design with its given tolerances alone
LADDER = (0.875, 0.75, 0.5, 0.25, TINY)  # factors tried after 1, until one meets the target
STEPS = 4  # bisections between that factor and the one above it: 1/128 of the size near 1
SCREEN_ENTRIES = 1_000_000  # builds x stages from which the search runs on the screen
SCREEN_SHARE = 0.02  # of the builds passing in closed form at 1, those the screen maps too
_CACHE: dict = {}  # the last few checks, by their inputs (optimize, then yield, of one spec)
_CACHE_SIZE = 4


@dataclass(frozen=True)
class CheckedAllocation:
    """The tolerances after the check (every allocated value times `factor`), whether the
    target is met, optimize's `tolerances_yield` record and, when not met, why in words."""

    tolerances: object
    factor: float
    met: bool
    record: dict
    words: str = ""


def shrunk(tolerances, allocated, factor: float):
    """The tolerances with every allocated quantity's value times factor."""
    items = tuple(t.scaled(factor) if t.quantity in allocated else t for t in tolerances)
    return replace(tolerances, items=items)


def check_allocation(scene, design, tolerances, allocated, *, target: float, stages: int,
                     accuracy="default") -> CheckedAllocation:
    """Check `tolerances` (every one valued; `allocated`: the names sized for the target) by
    Monte Carlo and shrink the allocated ones until the interval's lower end reaches the target
    (module docstring). Cached by its inputs."""
    key = repr((scene, design, tolerances, sorted(allocated), target, stages, accuracy))
    if key not in _CACHE:
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = _check(scene, design, tolerances, frozenset(allocated), target, stages,
                             accuracy)
    return _CACHE[key]


def _check(scene, design, tolerances, allocated, target, stages, accuracy):
    from .yield_allocation import linearised_yield_function

    runs = _Runs(scene, design, tolerances, allocated, target, stages, accuracy)
    best, met = _search(runs.judge, runs.showable, runs.screen if runs.screening else None)
    if not met:  # the factor whose lower end came nearest the target
        best = max(runs.done, key=lambda f: (runs.done[f].ci_low, f))
    sized = shrunk(tolerances, allocated, best)
    linearised = linearised_yield_function(scene)
    record = _record(runs.done, best, target, stages, tolerances,
                     linearised(scene, design, sized, stages)["yield"],
                     linearised(scene, design, tolerances, stages)["yield"], met)
    if runs.screened:
        record["screened"] = [{"scale": f, "failures": n} for f, n in runs.screened.items()]
    words = "" if met else _unmet_words(runs.done, best, target, tolerances.builds, stages)
    return CheckedAllocation(sized, best, met, record, words)


class _Runs:
    """The Monte Carlo runs of one check: `done` (factor -> YieldResult), judge(factor) (a
    run there; whether its lower end reaches the target) and, on long runs (`screening`),
    screen() (_screen's factor, found while the run at 1 simulates)."""

    def __init__(self, scene, design, tolerances, allocated, target, stages, accuracy):
        self.scene, self.design, self.tolerances, self.allocated = (scene, design, tolerances,
                                                                    allocated)
        self.target, self.stages, self.accuracy = target, stages, accuracy
        self.screening = tolerances.builds * stages >= SCREEN_ENTRIES
        self.showable = _showable(target, tolerances.builds)
        self.done, self.screened, self.mapped, self.found = {}, {}, None, None

    def run(self, factor, confirm, meanwhile=None, known=None) -> bool:
        from ..tolerances.yield_ import yield_of

        sized = shrunk(self.tolerances, self.allocated, factor)
        if self.screening and factor == 1.0 and self.mapped is None:  # the screen's margins
            from ..tolerances.parallel import local_workers
            from ..tolerances.yield_ import map_builds

            self.mapped = map_builds(self.scene, self.design, sized, sized.builds,
                                     self.stages, sized.seed,
                                     workers=local_workers(getattr(sized, "workers", None)))
        self.done[factor] = yield_of(
            self.scene, self.design, sized, builds=sized.builds, stages=self.stages,
            seed=sized.seed, confirm=confirm, accuracy=self.accuracy, scales=(),
            sensitivity_samples=0, mapped=self.mapped if factor == 1.0 else None,
            meanwhile=meanwhile, known=known)
        return self.done[factor].ci_low >= self.target

    def judge(self, factor) -> bool:
        if not (self.screening and factor == 1.0):
            return self.run(factor, self.tolerances.confirm)
        # screening: the run at 1 without the random confirmations, the screen meanwhile;
        # where it meets the target (it is the answer then) they are simulated too
        return (self.run(1.0, 0, meanwhile=self.screen if self.showable else None)
                and self.run(1.0, self.tolerances.confirm, known=self.done[1.0].verdicts))

    def screen(self) -> tuple[float, bool]:
        if self.found is None:
            self.found = _screen(self.scene, self.design, self.tolerances, self.allocated,
                                 self.mapped, self.target, self.stages, self.screened,
                                 self.accuracy)
        return self.found


def _showable(target: float, builds: int) -> bool:
    """Whether `builds` builds can show `target` at all: the interval's lower end with every
    build passing (the most any factor can give) reaches it."""
    from ..tolerances.yield_ import wilson

    return float(wilson(builds, builds)[0]) >= target


def _search(judge, showable: bool = True, screen=None) -> tuple[float, bool]:
    """(the largest factor found that meets the target, True), or (0, False) when none of 1
    and LADDER does: the ladder down from 1, then STEPS bisections below the rung above. When
    the builds cannot show the target (not showable), the run at 1 alone, for the record.
    screen: () -> (a factor, whether found) of the same ladder and the bisections' grid on a
    cheaper judge (_screen), asked after the run at 1; that factor is judged once, and where
    that run does not meet the target the ladder goes on below it."""
    if judge(1.0):
        return 1.0, True
    if not showable:
        return 0.0, False
    if screen is None:
        return _ladder(judge, 1.0, LADDER)
    guess, found = screen()
    if not found or guess >= 1.0:
        return _ladder(judge, 1.0, LADDER)
    if judge(guess):
        return guess, True
    return _ladder(judge, guess, [r for r in LADDER if r < guess])


def _ladder(judge, above: float, rungs) -> tuple[float, bool]:
    """The first of `rungs` (falling, below `above`, which does not meet the target) that
    judge passes, then STEPS bisections between it and the rung above it; (0, False) when none
    does."""
    for rung in rungs:
        if judge(rung):
            good, bad = rung, above
            for _ in range(STEPS):
                mid = 0.5 * (good + bad)
                good, bad = (mid, bad) if judge(mid) else (good, mid)
            return good, True
        above = rung
    return 0.0, False


def _screen(scene, design, tolerances, allocated, mapped, target, stages, screened,
            accuracy="default"):
    """(a factor, whether found): the ladder's on the builds most at risk alone. Those are
    every build the map at factor 1 (`mapped`) fails or leaves to the simulator, and the
    SCREEN_SHARE of the others with the smallest margins; every other build counts as passing.
    At a factor each is drawn as the run draws it (its allocated deviations that factor times
    those at 1) and mapped, a rung of 1 and LADDER and the 2^STEPS factors above it (the
    bisections' grid) in one map. A factor passes where the Wilson interval's lower end of the
    failing count reaches the target; the builds the map leaves there are simulated where
    their verdict decides it (_resolve). The first rung that passes, then a bisection of its
    grid. `screened`: factor -> failures counted, filled."""
    import numpy as np

    from ..tolerances import run_builds
    from ..tolerances.yield_ import drawn, wilson

    builds = mapped.builds
    risky = (mapped.failure != "") | ~mapped.closed_form
    margin = np.where(risky, -np.inf, mapped.min_margin)
    chosen = np.sort(np.argsort(margin, kind="stable")[
        :int(risky.sum()) + math.ceil(SCREEN_SHARE * builds)])
    base = drawn(scene, tolerances, chosen, stages, tolerances.seed)
    rungs = (1.0, *LADDER)
    for above, rung in zip(rungs, rungs[1:]):
        grid = rung + (above - rung) * np.arange(2**STEPS) / 2**STEPS
        stacked = {q: np.concatenate([d * f for f in grid]) if q in allocated
                   else np.concatenate([d] * len(grid)) for q, d in base.items()}
        out = run_builds(scene, design, stacked, stages)
        shape = (len(grid), len(chosen))
        left = (~out.closed_form).reshape(shape)
        failing = ((out.failure != "").reshape(shape) & ~left).sum(axis=1)

        def passes(k, grid=grid, left=left, failing=failing):
            known = failing[k] + (_resolve(scene, design, tolerances, allocated, grid[k],
                                           chosen[left[k]], stages, accuracy)
                                  if left[k].any() else 0)
            screened[float(grid[k])] = int(known)
            return float(wilson(builds - known, builds)[0]) >= target

        if passes(0):
            lo, hi = 0, len(grid)  # passes at lo; the rung above did not
            while hi - lo > 1:
                mid = (lo + hi) // 2
                lo, hi = (mid, hi) if passes(mid) else (lo, mid)
            return float(grid[lo]), True
    return 0.0, False


def _resolve(scene, design, tolerances, allocated, factor, indices, stages, accuracy) -> int:
    """How many of the builds `indices`, the allocated tolerances at `factor`, fail in the
    event simulator, in this process (a few builds; the workers may be simulating the run at
    1 meanwhile)."""
    from ..tolerances.parallel import BuildRun, simulate_builds

    run = BuildRun(scene, design, {float(factor): shrunk(tolerances, allocated, factor)},
                   tolerances.seed, stages, accuracy)
    answers = simulate_builds(run, [(float(factor), int(i)) for i in indices], workers=1)
    return sum(1 for _, failure in answers if failure)


def _record(runs, best, target, stages, tolerances, linearised, first_linearised, met) -> dict:
    """optimize's `tolerances_yield` (docs/json-schema.md)."""
    final, first = runs[best], runs[1.0]
    return {"target": target, "linearised": float(linearised), "estimate": final.estimate,
            "ci_low": final.ci_low, "ci_high": final.ci_high, "builds": final.builds,
            "seed": tolerances.seed, "stages": stages, "met": met, "scale": best,
            "failures": dict(final.failures),
            "sized_by_linearisation": {"linearised": float(first_linearised),
                                       "estimate": first.estimate, "ci_low": first.ci_low,
                                       "ci_high": first.ci_high},
            "steps": [{"scale": f, "estimate": r.estimate, "ci_low": r.ci_low}
                      for f, r in runs.items()]}


def _pct(x: float) -> str:
    return f"{100.0 * x:.2f} %"


def _unmet_words(runs, best, target, builds, stages) -> str:
    """Why no factor of the allocated tolerances meets the target, in words: too few builds to
    show it (the nearest run's estimate reaches it, its interval does not), or the design with
    its given tolerances fails more often than the target allows."""
    from ..tolerances.yield_ import Z95

    near, tiny = runs[best], runs.get(TINY)
    if tiny is None:  # the builds cannot show the target (_showable): the run at 1 alone
        need = math.ceil(Z95 ** 2 * target / (1.0 - target))
        return (f"the yield target {_pct(target)} cannot be shown by {builds} builds: with "
                f"none failing the 95 % interval's lower end is "
                f"{_pct(builds / (builds + Z95 ** 2))} (at the allocated tolerances' "
                f"linearised size {_pct(near.estimate)} of them pass all {stages} stages): "
                f"raise tolerances.builds to at least {need}")
    head = (f"the yield target {_pct(target)} cannot be met: at no common factor of the "
            f"allocated tolerances' linearised size from 1 down to {TINY:g} does the Monte Carlo "
            f"interval's lower end reach it (the nearest at {best:.4g}: {_pct(near.estimate)} "
            f"of {builds} builds pass all {stages} stages, 95 % interval from "
            f"{_pct(near.ci_low)})")
    if near.estimate >= target:
        return (head + f"; {builds} builds cannot show {_pct(target)} (with none failing the "
                f"lower end is {_pct(builds / (builds + Z95 ** 2))}): raise tolerances.builds")
    failures = ", ".join(f"{k} {v}" for k, v in tiny.failures.items())
    return (head + f"; the design with its given tolerances fails too often (at {TINY:g}: "
            f"{_pct(tiny.estimate)} pass; {failures}): tighten the given tolerances, change "
            "the design, or lower the target")


def entries_checked(entries, checked: CheckedAllocation) -> list[dict]:
    """optimize's tolerance entries with every allocated value times the check's factor."""
    return [dict(e) | {"value": e["value"] * checked.factor} if e["allocated"] else dict(e)
            for e in entries]


def valued(spec, entries):
    """The spec's tolerances with every allocated one at its value in `entries`."""
    values = {e["quantity"]: e["value"] for e in entries}
    return replace(spec.tolerances, items=tuple(
        replace(t, value=values[t.quantity]) if t.allocate else t for t in spec.tolerances))


def check_answer(spec, design, entries, accuracy) -> CheckedAllocation:
    """The Monte Carlo check of optimize's allocated `entries` at `design`, the spec's
    builds, seed, confirm and stages."""
    allocated = {t.quantity for t in spec.tolerances if t.allocate}
    return check_allocation(spec.scene, design, valued(spec, entries), allocated,
                            target=spec.tolerances.yield_target,
                            stages=spec.verification.stages, accuracy=accuracy)
