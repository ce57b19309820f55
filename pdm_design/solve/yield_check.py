"""Tolerances sized for a yield target, checked by Monte Carlo (docs/optimizer.md section 10).

The linearised yield that sizes the allocated tolerances (solve/yield_allocation.py at a fixed
design, formulation/yield_target.py with the design) is a model: a union bound (or Hunter's
bound) of first-order spreads with a second-order mean. The Monte Carlo yield is the judge: the
yield engine of `pdm-design yield` (tolerances.yield_.yield_of: the closed-form map, the event
simulator on every build outside it and on `confirm` random others) with the spec's `builds`,
`seed` and `confirm`, so that `pdm-design yield` of the answer is the same run.

Where the 95 % interval's lower end is below the target, every allocated tolerance is shrunk
by one common factor c (the given ones kept), the design fixed: c = 1 is checked first; then a
tiny factor (TINY: the design with its given tolerances alone, near enough), which must meet the
target, else the target cannot be met and `words` say why; then STEPS bisections of c between
the largest factor known to meet the target and the smallest known not to. The builds are the
same at every c (common random numbers: build i's uniform numbers are fixed by the seed, and an
allocated quantity's deviation is c times the one at c = 1), so the estimate moves with c only
through the builds whose verdict c changes, and the bisection does not chase sampling noise.
The answer is always a factor that was checked: its estimate is the one reported.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

STEPS = 6  # bisections of the factor: the answer within 1/64 of the linearised allocation's
TINY = 1e-3  # the factor that stands for the design with its given tolerances alone
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
    from ..tolerances.yield_ import yield_of
    from .yield_allocation import linearised_yield_function

    linearised = linearised_yield_function(scene)
    runs = {}

    def judge(factor):
        sized = shrunk(tolerances, allocated, factor)
        runs[factor] = yield_of(scene, design, sized, builds=tolerances.builds, stages=stages,
                                seed=tolerances.seed, confirm=tolerances.confirm,
                                accuracy=accuracy, scales=(), sensitivity_samples=0)
        return runs[factor].ci_low >= target

    if judge(1.0):
        best, met = 1.0, True
    elif not judge(TINY):
        best, met = TINY, False
    else:
        good, bad = TINY, 1.0
        for _ in range(STEPS):
            mid = 0.5 * (good + bad)
            good, bad = (mid, bad) if judge(mid) else (good, mid)
        best, met = good, True
    sized = shrunk(tolerances, allocated, best)
    record = _record(runs, best, target, stages, tolerances,
                     linearised(scene, design, sized, stages)["yield"],
                     linearised(scene, design, tolerances, stages)["yield"], met)
    words = "" if met else _unmet_words(runs[TINY], target, tolerances.builds, stages)
    return CheckedAllocation(sized, best, met, record, words)


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


def _unmet_words(tiny, target, builds, stages) -> str:
    """Why no scale of the allocated tolerances meets the target, in words: too few builds to
    show it (the estimate at the tiny factor reaches it, its interval does not), or the design
    with its given tolerances fails more often than the target allows."""
    from ..tolerances.yield_ import Z95

    head = (f"the yield target {_pct(target)} cannot be met: with the allocated tolerances at "
            f"{TINY:g} of their linearised size, {_pct(tiny.estimate)} of {builds} builds pass "
            f"all {stages} stages (95 % interval from {_pct(tiny.ci_low)})")
    if tiny.estimate >= target:
        return (head + f": {builds} builds cannot show {_pct(target)} (with none failing the "
                f"lower end is {_pct(builds / (builds + Z95 ** 2))}); raise tolerances.builds")
    failures = ", ".join(f"{k} {v}" for k, v in tiny.failures.items())
    return (head + f"; the design with its given tolerances fails too often ({failures}): "
            "tighten the given tolerances, change the design, or lower the target")


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
