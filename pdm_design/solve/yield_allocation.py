"""Tolerances allocated for a yield target: the largest common scale s of the tolerances to
allocate (each t_q = s * w_min / w_q, SI: tolerance_model.allocation_shares) at which a design's
linearised yield still reaches the target: the scene's own (`linearised_yield_function`): a
union bound 1 - sum_i Phi(-beta_i), or Hunter's bound (Scene.linearised_yield, the scene's
formulation/statistical.py).

The design is fixed (the spec's, or the optimizer's answer). The linearised yield falls as the
tolerances grow (every row's spread grows with s; the second-order mean shift with s^2), so s
is found on a grid in log s (the largest grid scale that meets it), then by bisection up to
the next grid scale. The yield need not fall monotonically with s: with the pivots exact, a
design sized for their drift can drift the other way and fail sooner.
Check the answer by Monte Carlo (tolerances.yield_.yield_of on `Allocation.tolerances`): the
union bound is conservative where several rows can fail (Hunter's bound less so), and first
order (with a second-order mean) in the deviations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..tolerance_model import Tolerance, Tolerances, allocation_shares

BISECTIONS = 60
SCALE_RANGE = (1e-9, 1e3)  # s searched within (SI units)
GRID = 49  # scales tried first, evenly in log s (the yield need not fall monotonically)


@dataclass(frozen=True)
class Allocation:
    """The scale found, the tolerances with every allocated value set, and the linearised
    yield there (statistical.linearised_yield's dict)."""

    scale: float
    target: float
    tolerances: Tolerances
    linearised: dict


def with_scale(tolerances: Tolerances, scale: float) -> Tolerances:
    """The tolerances with every one to allocate given its value at this scale
    (scale * w_min / w_q: tolerance_model.allocation_shares)."""
    shares = allocation_shares(tolerances)
    items = tuple(Tolerance(t.quantity, t.applies_to, scale * shares[t.quantity], t.weight,
                            t.distribution) if t.allocate else t for t in tolerances)
    return replace(tolerances, items=items)


def linearised_yield_function(scene):
    """The scene's linearised yield of a fixed design, (scene, design, tolerances, stages) ->
    dict with "yield" (Scene.linearised_yield)."""
    from ..plugin import of

    return of(scene).linearised_yield


def allocate_for_yield(scene, design, tolerances: Tolerances, *, stages: int,
                       target: float | None = None) -> Allocation:
    """The largest scale s whose allocated tolerances keep the linearised yield >= target
    (default: tolerances.yield_target). ValueError in words when nothing is to be allocated,
    no target is given, or no scale meets it."""
    linearised_yield = linearised_yield_function(scene)
    target = tolerances.yield_target if target is None else target
    if target is None or not 0.0 < target < 1.0:
        raise ValueError(f"a yield target in (0, 1) is needed, got {target!r}")
    if not any(t.allocate for t in tolerances):
        raise ValueError("no tolerance to allocate (allocate = true)")

    def meets(scale):
        lin = linearised_yield(scene, design, with_scale(tolerances, scale), stages)
        return lin["yield"] >= target, lin

    lo, hi = SCALE_RANGE
    grid = [lo * (hi / lo) ** (i / (GRID - 1)) for i in range(GRID)]
    meeting = [i for i, scale in enumerate(grid) if meets(scale)[0]]
    if not meeting:
        best = max(meets(scale)[1]["yield"] for scale in grid)
        raise ValueError(f"the yield target {target} is out of reach: the linearised yield is "
                         f"at most {best:.6f} for any scale of the allocated tolerances")
    last = meeting[-1]
    lo = grid[last]
    if last + 1 < GRID:  # the target is crossed between this grid point and the next
        hi = grid[last + 1]
        for _ in range(BISECTIONS):
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if meets(mid)[0] else (lo, mid)
            if hi / lo < 1.0 + 1e-9:
                break
    allocated = with_scale(tolerances, lo)
    return Allocation(lo, target, allocated, meets(lo)[1])


def out_of_reach_words(spec, design) -> str:
    """Why an optimisation sized for the spec's yield target found no design, in words, when
    the target is out of reach at `design` (the least-violation answer, valued): the linearised
    yield with the allocated tolerances at the smallest scale, the given tolerances alone near
    enough, and what fails most; "" when that yield reaches the target (the cause is then
    elsewhere: the design's own rows)."""
    tolerances = with_scale(spec.tolerances, SCALE_RANGE[0])
    stages, target = spec.verification.stages, spec.tolerances.yield_target
    best = linearised_yield_function(spec.scene)(spec.scene, design, tolerances, stages)["yield"]
    if best >= target:
        return ""
    limits = "; ".join(f"{e['condition']} {100.0 * e['share']:.0f} % ({e['where']})"
                       for e in dominant_rows(spec.scene, design, tolerances, stages)[:3])
    return (f"the yield target {100.0 * target:g} % is out of reach: at the best design found "
            f"the linearised yield over {stages} stages is {100.0 * best:.4g} % with the "
            f"allocated tolerances at the smallest scale ({SCALE_RANGE[0]:g}), so the given "
            f"tolerances alone fail more often than the target allows"
            + (f" (the failures: {limits})" if limits else "")
            + ": tighten the given tolerances, lower the target or run fewer stages")


def dominant_rows(scene, design, tolerances: Tolerances, stages: int, *,
                  floor: float = 0.01) -> list[dict]:
    """What limits tolerances sized for a yield: the failures that make up the union bound
    sum_i Phi(-beta_i) at this design and these (valued) tolerances, by name, each with its
    share of the bound and where along the row its rows are (`_rows_placed`: "step k", or the
    scene's own name of place 0, PlacedRows.word), the largest
    first; those holding less than `floor` of it left out."""
    import numpy as np
    from scipy.special import ndtr

    g, sd, names, weight, place, word = _rows_placed(scene, design, tolerances, stages)
    with np.errstate(invalid="ignore", divide="ignore"):
        tail = ndtr(-g / sd) * weight
    total = float(np.sum(tail))
    if not total > 0.0:
        return []
    out = []
    for name in dict.fromkeys(names):
        mine = np.array([n == name for n in names]) & (tail > 0.0)
        share = float(tail[mine].sum()) / total
        if share < floor:
            continue
        out.append({"condition": name, "where": _places(place[mine], tail[mine], total, word),
                    "share": share})
    return sorted(out, key=lambda e: -e["share"])


def _rows_placed(scene, design, tolerances, stages):
    """(g, sd, names, the union bound's weight of each row, its place, word(place)) of the
    scene's linearised rows (Scene.linearised_rows: place k is stage k, place 0 the scene's
    own, such as a first landing)."""
    from ..plugin import of

    rows = of(scene).linearised_rows(scene, design, tolerances, stages)
    return rows.g, rows.sd, rows.names, rows.weight, rows.place, rows.word


def _places(places, tails, total, word) -> str:
    """Where one failure's share of the union bound lies, in words: the places whose rows
    hold at least a thousandth of it, and the largest. word: (a place's noun, its plural,
    place 0's name or None)."""
    import numpy as np

    noun, plural, zero = word

    def one(k):
        return zero if k == 0 and zero else f"{noun} {k}"

    kept = places[tails >= 1e-3 * total] if np.any(tails >= 1e-3 * total) else places
    top = int(places[int(np.argmax(tails))])
    lo, hi = int(kept.min()), int(kept.max())
    if lo == hi:
        return one(top)
    return f"{one(lo) if lo == 0 and zero else f'{plural} {lo}'}-{hi}, the most at {one(top)}"


def limits_at_target(spec, solution, entries) -> list[dict]:
    """optimize's tolerance list of a spec sized for a yield target (formulation/
    yield_target.py), each allocated entry limited by the dominant rows of the union bound at
    the answer (dominant_rows); [] for a given tolerance."""
    import numpy as np

    from ..formulation import formulate

    form = formulate(spec)
    values = form.design_values(np.asarray(solution.x, dtype=float))
    design = spec.design_at({n: values[n] for n in spec.free_variables})
    valued = {e["quantity"]: e["value"] for e in entries}
    sized = replace(spec.tolerances, items=tuple(
        replace(t, value=valued[t.quantity]) if t.allocate else t for t in spec.tolerances))
    limits = dominant_rows(spec.scene, design, sized, spec.verification.stages)
    return [dict(e) | {"limited_by": limits if e["allocated"] else []} for e in entries]
