"""Which tolerance the workshop builds to when one part carries two: the optimizer's
worst-case box (box) and the spec's statistical tolerance (spec) of the same quantity (a
pivot's x and y, a step's rise and tread). One sentence, for the sheet's Markdown, the text
under its drawing (PNG, SVG, PDF) and the report page."""

from __future__ import annotations

BOX, SPEC = " (box)", " (spec)"


def build_to_sentence(sheet) -> str:
    """The sentence, or "" when no quantity carries both tolerances."""
    from .parts import tolerance_entries

    entries = tolerance_entries(sheet)
    spec = {e.quantity[: -len(SPEC)]: e for e in entries if e.quantity.endswith(SPEC)}
    pairs = [(e, spec[e.quantity[: -len(BOX)]]) for e in entries
             if e.quantity.endswith(BOX) and e.quantity[: -len(BOX)] in spec]
    if not pairs:
        return ""
    stated = ", ".join(f"{s.quantity[: -len(SPEC)]} {s.shown()}" for _, s in pairs)
    boxed = ", ".join(f"{b.quantity[: -len(BOX)]} {b.shown()}" for b, _ in pairs)
    if all(s.value <= b.value for b, s in pairs):
        return (f"Build to the spec's tolerances (spec): {stated}. They lie inside the "
                f"worst-case box (box), {boxed}, so every build made to them works.")
    return (f"Build to the spec's tolerances (spec): {stated}; the yield (pdm-design yield) "
            "is the fraction of such builds that work. The worst-case box (box), "
            f"{boxed}, is narrower: a build with every part inside it works without "
            "exception; hold the box instead only where every build must work.")
