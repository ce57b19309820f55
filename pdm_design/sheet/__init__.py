"""Build sheets: `sheet_for(path)` makes one, `write_sheet` writes its Markdown, CSV and drawing
(PNG, SVG), each file whole or not at all."""

from __future__ import annotations

from pathlib import Path

from .build import BuildSheet, make_sheet, sheet_csv, sheet_for, sheet_markdown

STEM = "sheet"


def write_sheet(sheet: BuildSheet, folder, *, drawing: bool = True) -> tuple[Path, ...]:
    """Write sheet.md, sheet.csv and (unless drawing=False) sheet.png and sheet.svg."""
    from ..io import write_atomic

    folder = Path(folder)
    files = []
    if drawing:
        from .drawing import drawing_files

        for name, payload in drawing_files(sheet, STEM).items():
            write_atomic(folder / name, payload)
            files.append(folder / name)
    write_atomic(folder / f"{STEM}.csv", sheet_csv(sheet))
    write_atomic(folder / f"{STEM}.md",
                 sheet_markdown(sheet, f"{STEM}.svg" if drawing else None))
    return (folder / f"{STEM}.md", folder / f"{STEM}.csv", *files)


__all__ = ["BuildSheet", "make_sheet", "sheet_csv", "sheet_for", "sheet_markdown",
           "write_sheet"]
