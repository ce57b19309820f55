"""Which conditions bind at an optimum, read from IPOPT's multipliers.

At an optimum of the NLP (formulation/common.py) the multiplier of a row is its shadow price:
how fast the objective would improve if that row were relaxed. The rows are normalised (a unit
of a row is a unit of its margin), so the multipliers of the physical rows (margins and validity
conditions; the model rows only define auxiliary quantities and pass the price on to them) can
be compared: each row's share of their sum says how much of what holds the objective back is
that condition at that place. An inactive row's multiplier is zero (IPOPT's interior point
leaves about 1e-10), so the shares name the active rows only.

For `max_offset_tolerance` these are the conditions that limit the tolerance. A design variable
whose bound binds holds it back as well: it is listed after them, without a share (its multiplier
is per unit of the variable, not comparable with the rows').

`limiting_rows` and `limiting_bounds` take plain arrays and ConditionInfo rows, so that another
NLP (one tolerance variable per quantity, say) can ask the same of its own solution.
"""

from __future__ import annotations

import numpy as np

from ..formulation.common import MODEL
from ..spec.model import at_bound

SHARE_FLOOR = 0.01  # rows holding less than this share of the sum are not listed
BOUND_FLOOR = 1e-6  # a bound binds when its multiplier exceeds this fraction of the rows' sum


def limiting_rows(conditions, lam_g, *, floor: float = SHARE_FLOOR) -> list[dict]:
    """{"condition", "where", "share"} of each physical row (ConditionInfo) holding at least
    `floor` of the rows' summed multipliers, the largest share first."""
    lam = np.abs(np.asarray(lam_g, dtype=float).ravel())
    rows = [(info, float(lam[info.index])) for info in conditions
            if info.kind != MODEL and not info.equality]
    total = sum(price for _, price in rows)
    if not total > 0.0:
        return []
    picked = sorted(((price / total, info) for info, price in rows if price / total >= floor),
                    key=lambda pair: -pair[0])
    return [{"condition": info.name, "where": info.where, "share": share}
            for share, info in picked]


def limiting_bounds(names, x, lam_x, lbx, ubx, rows_total: float) -> list[dict]:
    """{"condition": "bound", "where": "NAME at its min|max VALUE", "share": None} of each
    variable at a bound whose multiplier exceeds BOUND_FLOOR of the rows' summed multipliers."""
    out = []
    for i, name in enumerate(names):
        side = at_bound(float(x[i]), float(lbx[i]), float(ubx[i]))
        if side and abs(float(lam_x[i])) > BOUND_FLOOR * rows_total:
            bound = float(lbx[i] if side == "min" else ubx[i])
            out.append({"condition": "bound", "where": f"{name} at its {side} {bound:g}",
                        "share": None})
    return out


def limited_by(spec, solution) -> list[dict]:
    """The conditions (and bounds) that hold back `optimize(spec)`'s answer, whose Solution
    (x and multipliers) is given: limiting_rows, then limiting_bounds."""
    from ..formulation import formulate
    from ..formulation.build import FULL

    form = formulate(spec, full=solution.key.endswith(FULL))
    lam_g = np.asarray(solution.lam_g, dtype=float).ravel()
    rows = limiting_rows(form.conditions, lam_g)
    total = sum(abs(lam_g[i.index]) for i in form.conditions
                if i.kind != MODEL and not i.equality)
    n = form.n_design
    x, lam_x = (np.asarray(v, dtype=float).ravel() for v in (solution.x, solution.lam_x))
    return rows + limiting_bounds(form.design_names, x[:n], lam_x[:n], form.lbx[:n],
                                  form.ubx[:n], total)


def limits_of_quantities(spec, solution, entries) -> list[dict]:
    """The tolerance list of an allocated answer (formulation/allocation.py values_at), each
    entry with its `limited_by`: of the rows and bounds that hold the allocation back
    (limited_by), those whose outer bound involves the quantity (Condition.quantities), and the
    binding bounds (they hold every allocated quantity back); [] for a given tolerance."""
    from ..formulation import formulate
    from ..formulation.build import FULL
    from ..formulation.yield_target import active

    if active(spec):  # sized for a yield target: the union bound's dominant rows
        from .yield_allocation import limits_at_target

        return limits_at_target(spec, solution, entries)
    form = formulate(spec, full=solution.key.endswith(FULL))
    uses: dict[tuple[str, str], set] = {}
    for info in form.conditions:
        uses.setdefault((info.name, info.where), set()).update(info.quantities)
    limits = limited_by(spec, solution)
    out = []
    for entry in entries:
        q = entry["quantity"]
        mine = [r for r in limits if r["condition"] == "bound"
                or q in uses.get((r["condition"], r["where"]), ())] if entry["allocated"] else []
        if entry["allocated"] and not mine:  # held back by the others, through its weight
            mine = [dict(WEIGHT_SHARE)]
        out.append({k: v for k, v in entry.items()} | {"limited_by": mine})
    return out


# an allocated quantity no binding row involves: only the weights' proportion holds it back
SHARED = "its weight's share of the others' (no binding row involves it)"
# ... and its limited_by entry in JSON (docs/json-schema.md)
WEIGHT_SHARE = {"condition": "weight_share", "where": "", "share": None}


def in_words(limits: list[dict]) -> str:
    """A limited_by list in one line: 'lift_off (at the handover) 58 %; alpha at its min 0'."""
    return "; ".join(
        SHARED if e["condition"] == WEIGHT_SHARE["condition"] else
        (e["where"] if e["condition"] == "bound" else
         e["condition"] + (f" ({e['where']})" if e["where"] else ""))
        + (f" {100 * e['share']:.0f} %" if e.get("share") is not None else "") for e in limits)
