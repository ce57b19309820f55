"""The human-readable report of `pdm-design simulate`."""

from __future__ import annotations

from ..plugin import of
from ..units import counted

_SHOWN_STAGES = 20


def _cell(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)) or hasattr(value, "__float__"):
        return f"{float(value):.6g}"
    return str(value)


def simulation_text(spec, result) -> str:
    outcome = result.outcome
    verdict = "completed" if outcome.completed else "FAILED"
    lines = [f"{spec.name or spec.source} ({spec.kind}): {verdict}, "
             f"{counted(outcome.stages_passed, 'stage')} passed "
             f"(accuracy {result.accuracy.describe()})"]
    if outcome.failure is not None:
        f = outcome.failure
        lines.append(f"failure: {f.kind} at stage {f.stage}, t = {f.time:.6g} s: {f.detail}")
    columns = of(spec).stage_columns or tuple(result.stages[0] if result.stages else ())
    rows = [[_cell(stage.get(c)) for c in columns] for stage in result.stages[:_SHOWN_STAGES]]
    widths = [max(len(c), *(len(r[i]) for r in rows)) if rows else len(c)
              for i, c in enumerate(columns)]
    lines += ["", "  ".join(c.rjust(w) for c, w in zip(columns, widths))]
    lines += ["  ".join(v.rjust(w) for v, w in zip(row, widths)) for row in rows]
    if len(result.stages) > _SHOWN_STAGES:
        lines.append(f"... {len(result.stages) - _SHOWN_STAGES} more stages (--format json)")
    lines += ["", f"events ({len(result.events)}):"]
    for event in result.events[:40]:
        mark = "  FAILURE" if event.failure else ""
        lines.append(f"  t={event.time:10.6f}  stage {event.stage:>3}  {event.kind}{mark}"
                     + (f"  {event.detail}" if event.detail else ""))
    if len(result.events) > 40:
        lines.append(f"  ... {len(result.events) - 40} more (--format json)")
    return "\n".join(lines) + "\n"
