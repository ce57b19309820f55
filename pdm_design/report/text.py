"""The human-readable report of `pdm-design optimize`."""

from __future__ import annotations

import math

from ..analysis.result import required
from ..api import DesignOutcome
from ..status import Status
from .units import built_parts as _built_parts
from .units import units_of


def _rows(values: dict, units: dict) -> list[str]:
    width = max((len(k) for k in values), default=0)
    out = []
    for name, value in values.items():
        if value is None:
            shown = "-"
        elif isinstance(value, float) or hasattr(value, "__float__"):
            shown = f"{float(value):.6g} {units.get(name, '')}".rstrip()
        else:
            shown = str(value)
        out.append(f"  {name:<{width}}  {shown}")
    return out


def _box_size(axis: str, value: float, units: dict) -> str:
    """A box's half-width in build units: mm, or degrees for an angle (a slope)."""
    if units.get(axis) == "rad":
        return f"{value:.4g} rad ({math.degrees(value):.3g} deg)"
    return f"{value * 1e3:.2f} mm"


def _tolerance_rows(tolerance: dict, units: dict) -> list[str]:
    box = {k: v for k, v in tolerance.items() if k not in ("linearised", "limited_by")}
    lines = [f"  {axis:<6} +-{_box_size(axis, value, units)} (robust NLP)"
             for axis, value in box.items()]
    linear = tolerance.get("linearised")
    if linear:
        parts = []
        if linear["square"] or linear["box"]:  # neither: not computed (the status says why)
            parts.append(f"square +-{linear['square'] * 1e3:.2f} mm")
        if linear["box"]:
            parts.append("widest box " + ", ".join(f"{k} +-{v * 1e3:.2f} mm"
                                                   for k, v in linear["box"].items()))
        if "min_semi_axis" in linear["ellipsoid"]:
            parts.append("ellipsoid with its smallest semi-axis "
                         f"{linear['ellipsoid']['min_semi_axis'] * 1e3:.2f} mm")
        if linear["status"] != "optimal":
            parts.append(linear["status"])
        lines.append("  linearised safe set (cvxpy): " + "; ".join(parts))
    return lines


def _free_label(status: Status) -> str:
    """What a free variable's value is: an optimum, the least-violation design, or the point
    the solver stopped at."""
    if status is Status.INFEASIBLE:
        return "least violation"
    if status in (Status.OPTIMAL, Status.ACCEPTABLE, Status.UNVERIFIED):
        return "optimised"
    return "where the solver stopped"


def _limited_by(entries: list[dict]) -> str:
    parts = [f"{e['condition']}" + (f" ({e['where']})" if e["where"] else "")
             + (f" {100 * e['share']:.0f} %" if e["share"] is not None else "")
             for e in entries]
    return "  limited by: " + "; ".join(parts)


def optimize_text(outcome: DesignOutcome) -> str:
    spec, analysis = outcome.spec, outcome.analysis
    free, units = set(spec.free_variables), units_of(spec.kind)
    lines = [f"{spec.name or spec.source} ({spec.kind})",
             f"status: {outcome.status.value} - {outcome.status_message}", "", "design:"]
    design = {k: v for k, v in analysis.design.items() if v is not None}
    label = _free_label(outcome.status)
    lines += [row + (f"   ({label})" if name in free else "")
              for name, row in zip(design, _rows(design, units))]
    if outcome.at_bounds:
        lines.append("  at a bound: " + ", ".join(
            f"{name} ({side} {spec.design[name].min if side == 'min' else spec.design[name].max:g}"
            f"{(' ' + units[name]) if units.get(name) else ''})"
            for name, side in outcome.at_bounds.items()))
    lines += ["", "geometry:", *_rows(_built_parts(spec.kind, analysis.geometry), units)]
    lines += ["", "periodic orbit:", *_rows(analysis.periodic, units)]
    lines += ["", "margins (>= 0 holds; 1 - demand/capacity):"]
    width = max((len(k) for k in analysis.margins), default=0)
    for name, value in analysis.margins.items():
        need = required(name, spec.requirements, spec.kind)
        flag = "ok" if value >= need else f"VIOLATED (needs >= {need:g})"
        lines.append(f"  {name:<{width}}  {value:+.4f}  {flag}")
    if outcome.tolerance:
        lines += ["", "tolerance (half-widths of the box every pivot or step may be off by):"]
        lines += _tolerance_rows(outcome.tolerance, units)
        if outcome.tolerance.get("limited_by"):
            lines.append(_limited_by(outcome.tolerance["limited_by"]))
    if outcome.tolerances:
        lines += ["", _allocation_heading(outcome.spec),
                  *allocation_rows(outcome.spec.kind, outcome.tolerances)]
    if outcome.tolerances_yield:
        lines += tolerances_yield_rows(outcome.tolerances_yield)
    if outcome.verification is not None:
        v = outcome.verification
        accuracy = f" (accuracy {outcome.accuracy.describe()})" if outcome.accuracy else ""
        lines += ["", f"verification: {'passed' if v.get('passed') else 'FAILED'}{accuracy}"
                  f" - {v.get('summary', '')}"]
    if outcome.solver:
        stats = outcome.solver
        together = stats.get("stacked_starts", 0)
        starts = f"{stats['starts']} start{'s' if stats['starts'] != 1 else ''}" + (
            f" ({together} solved together)" if together else "")
        lines += ["", f"solver: IPOPT {stats['status']}, {stats['iterations']} iterations; "
                  f"{starts}, {1e3 * stats['total_solve_time']:.1f} ms in IPOPT, "
                  f"{1e3 * stats['wall_time']:.0f} ms in all"]
    if outcome.violations:
        lines += ["", "why it does not work:", *(f"  - {v}" for v in outcome.violations)]
    return "\n".join(lines) + "\n"


def _allocation_heading(spec) -> str:
    """What the allocated tolerances promise: every build inside them works (worst case), or
    the row's linearised yield reaches the target (docs/optimizer.md section 10)."""
    from ..formulation.yield_target import active

    if active(spec):
        return (f"allocated tolerances (sized for a yield of "
                f"{100 * spec.tolerances.yield_target:.4g} %, checked by Monte Carlo):")
    return "allocated tolerances (worst case: every build inside them works):"


def _pct(x: float) -> str:
    return f"{100.0 * x:.2f} %"


def tolerances_yield_rows(r: dict) -> list[str]:
    """The Monte Carlo check of tolerances sized for a yield target (solve/yield_check.py)."""
    first = r["sized_by_linearisation"]
    lines = [f"  yield target {_pct(r['target'])}: Monte Carlo {_pct(r['estimate'])} "
             f"(95 % interval {_pct(r['ci_low'])} to {_pct(r['ci_high'])}) over {r['builds']} "
             f"builds of {r['stages']} stages, seed {r['seed']}; "
             f"linearised {_pct(r['linearised'])}"]
    if r["scale"] != 1.0:
        lines.append(f"  sized by the linearised yield alone, they gave {_pct(first['estimate'])} "
                     f"({_pct(first['ci_low'])} to {_pct(first['ci_high'])}): "
                     + (f"shrunk to {r['scale']:.4g} of that size" if r["met"] else
                        "no size meets the target (see the status)"))
    return lines


def allocation_rows(kind: str, entries) -> list[str]:
    """The allocated tolerance table in build units (mm, degrees, g, %), with what limits each
    (optimize's `tolerances`, docs/optimizer.md section 4a)."""
    from ..solve.binding import SHARED, in_words
    from ..tolerance_model import quantities_of

    rows = []
    for e in entries:
        q = quantities_of(kind)[e["quantity"]]
        value, unit = e["value"] * q.build_factor, q.build_unit
        if unit == "1":  # a ratio (friction): in per cent of itself is no build unit; plain
            shown = f"+-{value:.4g}"
        else:
            shown = f"+-{value:.4g} {unit}"
        how = (("limited by: " + (in_words(e["limited_by"]) or SHARED)) if e["allocated"]
               else "given")
        rows.append(f"  {e['quantity']:<13} {shown:<14} {e['applies_to']:<5} {how}")
    return rows
