"""The build sheet as text: the Markdown page (millimetres and degrees, with the parts list and
the tolerances by part) and the CSV (every stage's item, SI units, exact floats)."""

from __future__ import annotations

import math
from pathlib import Path

from ..plugin import of
from .build import MARKDOWN_ROWS, BuildSheet


def sheet_csv(sheet: BuildSheet) -> str:
    """Every stage's item, one row each (exact floats)."""
    from ..sweep.tables import cell, csv_line

    header = list(sheet.items[0])
    return csv_line(header) + "".join(csv_line([cell(item[c]) for c in header])
                                      for item in sheet.items)


def sheet_markdown(sheet: BuildSheet, drawing: str | None = None) -> str:
    spec = sheet.spec
    unit_word = of(spec).stage_noun[0]
    lines = [f"# Build sheet: {spec.name or Path(spec.source).stem}", ""]
    if sheet.failures:
        lines += ["## WARNING: this design does not work. Do not build it.", "",
                  *(f"- {f}" for f in sheet.failures), ""]
    lines += [f"Spec: `{spec.source}` ({sheet.kind}); from `{sheet.source}`; status: "
              f"{sheet.status}.", ""]
    v = sheet.verification
    if v is not None:
        verdict = "passed" if v.get("passed") else "FAILED"
        lines += [f"Verification (the event simulator): {verdict}: {v.get('summary')}.", ""]
    lines += [f"Tolerance: {sheet.tolerance_note}"
              + (" (half-widths: build each within +- this of its nominal)." if sheet.tolerance
                 else "."), ""]
    limit = tolerance_limit(sheet)
    if limit:
        lines += [limit, ""]
    if drawing:
        lines += [f"![drawing]({drawing})", ""]
    covered = (f" ({unit_word}s 1 to {sheet.tolerance_covers} only)"
               if sheet.tolerance and sheet.tolerance_covers < sheet.count else "")
    from .parts import workshop_column, workshop_value

    lines += ["Millimetres and degrees (the CSV and the JSON are in SI units).", "",
              "| quantity | value | unit | tolerance (+-) |", "|---|---|---|---|"]
    for name, value, unit, tol in sheet.summary:
        shown_value, shown_unit = (workshop_value(value, unit) if isinstance(value, float)
                                   else (value, unit))
        shown = (_show(workshop_value(tol, unit)[0]) + covered if tol is not None
                 else "-")  # 0: build it exactly
        lines.append(f"| {name} | {_show_in(shown_value, shown_unit)} | {shown_unit} | "
                     f"{shown} |")
    lines += _parts_markdown(sheet)
    header = list(sheet.items[0])
    shown_header = [workshop_column(c)[0] for c in header]
    lines += ["", f"## Every {unit_word}", "",
              "| " + " | ".join(shown_header) + " |",
              "|" + "|".join("---" for _ in header) + "|"]
    for item in sheet.items[:MARKDOWN_ROWS]:
        cells = (workshop_column(c, item[c]) for c in header)
        lines.append("| " + " | ".join(_show_in(value, heading.rsplit("(", 1)[-1][:-1])
                                       for heading, value in cells) + " |")
    if sheet.count > MARKDOWN_ROWS:
        lines.append(f"\n... {sheet.count - MARKDOWN_ROWS} more {unit_word}s in the CSV.")
    if sheet.notes:
        lines += ["", "## Problems", "", *(f"- {n}" for n in sheet.notes)]
    return "\n".join(lines) + "\n"


def _parts_markdown(sheet: BuildSheet) -> list[str]:
    """The parts list and every tolerance by part (sheet/parts.py), as Markdown lines."""
    from .parts import parts_list, tolerance_entries

    parts, _ = parts_list(sheet)
    lines = ["", "## Parts", "", "| qty | part | dimensions | tolerance (+-) |",
             "|---|---|---|---|"]
    lines += [f"| {p.quantity} | {p.name} | {p.dimensions} | "
              + ("; ".join(f"{e.quantity} {e.shown()}" for e in p.tolerances) or "-") + " |"
              for p in parts]
    entries = tolerance_entries(sheet)
    if entries:
        lines += ["", "## Tolerances", "", "(spec): the spec's statistical tolerances; (box): "
                  "the worst-case box the optimizer computed.", "",
                  "| quantity | applies to | value | what it is |",
                  "|---|---|---|---|"]
        lines += [f"| {e.quantity} | {e.applies_to} | {e.shown()} | {e.limited_by} |"
                  for e in entries]
        from .build_to import build_to_sentence  # which of two tolerances on a part

        sentence = build_to_sentence(sheet)
        lines += ["", sentence] if sentence else []
    return lines


def tolerance_limit(sheet: BuildSheet) -> str:
    """In words, when more items are listed than the tolerance holds for: which ones carry it
    and how to get it for all (empty otherwise)."""
    covers, count = sheet.tolerance_covers, sheet.count
    if not sheet.tolerance or covers >= count:
        return ""
    unit_word = of(sheet.spec).stage_noun[1]
    # the most stages a tolerance is solved for (Scene.stage_limit: an NLP with rows for every
    # stage, a simulator that keeps every stage's record)
    most = of(sheet.spec).stage_limit(True)[0]
    how = (f"For a tolerance on all {count}, set `verification.stages = {count}` in the spec "
           "and make the sheet again." if count <= most else
           f"A tolerance is solved for at most {most} {unit_word} (`verification.stages` = "
           f"{most}): a longer device cannot be given one.")
    return (f"The tolerance holds for a device of the first {covers} {unit_word} only: it was "
            f"solved for the spec's `verification.stages` = {covers}. For {unit_word} "
            f"{covers + 1} to {count} none is known (blank in the CSV): the errors it allows "
            f"may add up over more {unit_word} to a device that fails, even when those are "
            f"built exactly. {how}")


def _show_in(value, unit: str) -> str:
    """A value in mm to 0.001 mm, in degrees to 0.0001 degree, others as _show."""
    if isinstance(value, float) and math.isfinite(value) and unit in ("mm", "deg", "mm/s"):
        return f"{value:.3f}" if unit != "deg" else f"{value:.4f}"
    return _show(value)


def _show(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else "-"
    return str(value)
