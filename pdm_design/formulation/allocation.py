"""Worst-case tolerance allocation: which quantities of a spec's `[tolerances]` the robust NLP
allocates, and the box half-width each gets (docs/optimizer.md section 4a).

The rule: one scale variable s (the NLP's `tolerance`, maximised by `max_offset_tolerance`) and

    t_q = s * w_min / w_q        for every quantity q with `allocate = true`, weight w_q,

w_min the smallest of those weights: a quantity twice as cheap to hold tight (weight 2) gets half
the tolerance, and s is the tolerance of the quantity that is dearest to hold tight (the
smallest weight). With equal weights every allocated quantity gets t = s, whatever the weight's
value, so pivot_x and pivot_y allocated alike are today's pivot box, the same NLP. Quantities
with a given `value` enter the bounds as fixed half-widths t_q = value. The weights compare
half-widths in SI units: between a length and a ratio (friction) a weight is also a choice of
scale (weight 1000 on pivot_x against 1 on friction: a millimetre of pivot costs as much as 0.001
of friction).

A quantity enters the NLP only where a sound outer bound of every condition over its box is
proven (docs/optimizer.md section 4a): ALLOCATABLE. A spec that allocates, or gives a value to,
any other quantity while allocating is refused in words (exit 2), never guessed.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca

from ..errors import SpecError
from ..tolerance_model import allocation_shares

# Why the others are refused: what a sound bound of them would need (the words of the error).
NOT_YET = "no outer bound over its box is derived yet"


def allocating(spec) -> bool:
    """Whether the spec's [tolerances] asks the optimizer to allocate a worst-case tolerance
    (not one sized for a yield target: formulation/yield_target.py)."""
    from .yield_target import active

    return any(t.allocate for t in getattr(spec, "tolerances", ())) and not active(spec)


def coefficients(spec) -> dict[str, float]:
    """{quantity: w_min / w_q} of every allocated quantity (t_q = s * coefficient)."""
    return allocation_shares(spec.tolerances)


def given(spec) -> dict[str, float]:
    """{quantity: value} of the quantities with a given tolerance (fixed half-widths)."""
    return {t.quantity: float(t.value) for t in spec.tolerances if not t.allocate}


def check(spec) -> None:
    """Refuse (SpecError, exit 2) an allocation the robust rows cannot bound soundly."""
    source = spec.source or "<spec>"
    if float(spec.objective.get("max_offset_tolerance", 0.0)) <= 0.0:
        name = next(t.quantity for t in spec.tolerances if t.allocate)
        raise SpecError(source, f"tolerances.{name}.allocate",
                        "an [objective] with max_offset_tolerance > 0 (allocation maximises "
                        "the weighted tolerances)", found="no max_offset_tolerance")
    from ..plugin import of

    scene = of(spec)
    allowed = scene.allocatable
    refusal = scene.allocation_refusal(spec)
    if refusal is not None:
        raise SpecError(source, *refusal[:2], found=refusal[2])
    for tol in spec.tolerances:
        if tol.quantity in allowed:
            continue
        key = "allocate" if tol.allocate else "value"
        raise SpecError(source, f"tolerances.{tol.quantity}.{key}",
                        "a quantity the worst-case allocation can bound: "
                        + ", ".join(allowed) + f" ({NOT_YET})",
                        found=tol.quantity)


def half_widths(spec, s) -> dict[str, object]:
    """{quantity: half-width} of every toleranced quantity of an allocating spec: s times its
    coefficient when allocated, its value when given (quantities not listed: exact)."""
    out = {q: s * c if c != 1.0 else s for q, c in coefficients(spec).items()}
    out.update(given(spec))
    return out


def values_at(spec, s: float) -> list[dict]:
    """The tolerance list of an answer with scale s: one entry per toleranced quantity, the
    allocated first ({quantity, applies_to, value (SI), unit, allocated})."""
    from ..tolerance_model import quantities_of

    coeff = coefficients(spec)
    entries = []
    for tol in sorted(spec.tolerances, key=lambda t: not t.allocate):
        value = s * coeff[tol.quantity] if tol.allocate else float(tol.value)
        entries.append({"quantity": tol.quantity, "applies_to": tol.applies_to,
                        "value": float(value), "unit": quantities_of(spec.kind)[tol.quantity].unit,
                        "allocated": tol.allocate})
    return entries


def pivot_box(spec, entries) -> dict[str, float]:
    """{axis: half-width} of the scene's explicit-offset box (Scene.box_axes: {"dx", "dy"} of a
    pivot, {"rise", "tread"} of a step) of a tolerance list, 0 where exact: the box the
    per-stage build errors are checked in."""
    from ..plugin import of

    value = {e["quantity"]: e["value"] for e in entries}
    return {axis: float(value.get(q, 0.0)) for axis, q in of(spec).box_axes_of(spec).axes}


def box_conditions(spec, rows_of, today: dict, s) -> list:
    """The conditions over the tolerance box: rows_of(box) with box = `today` (the scene's box
    of max_offset_tolerance alone, every axis s), or, when the spec allocates, one half-width
    per quantity (half_widths). Allocated, each row is first built on a symbol per quantity, to
    record which quantities it depends on (Condition.quantities: the rows that can limit each
    quantity), then the symbols are replaced by their half-widths."""
    if not allocating(spec):
        return rows_of(today)
    widths = half_widths(spec, s)
    symbols = {q: ca.SX.sym(f"t_{q}") for q in widths}
    subs = [list(symbols.values()), [ca.SX(widths[q]) for q in symbols]]
    out = []
    for c in rows_of(symbols):
        slack, scale = (ca.SX(e) for e in (c.slack, c.scale))
        used = tuple(q for q, t in symbols.items()
                     if ca.depends_on(slack, t) or ca.depends_on(scale, t))
        out.append(replace(c, slack=ca.substitute([slack], *subs)[0],
                           scale=ca.substitute([scale], *subs)[0], quantities=used))
    return out
