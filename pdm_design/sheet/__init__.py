"""Build sheets: `sheet_for(path)` makes one, `write_sheet` writes its Markdown, CSV and drawing
(PNG, SVG), each file whole or not at all."""

from __future__ import annotations

from pathlib import Path

from .build import BuildSheet, make_sheet, sheet_csv, sheet_for, sheet_markdown

STEM = "sheet"


def write_sheet(sheet: BuildSheet, folder, *, drawing: bool = True) -> tuple[Path, ...]:
    """Write sheet.md, sheet.csv and (unless drawing=False) sheet.png and sheet.svg: all of them
    or, when one cannot be written, none."""
    from ..io import write_all

    folder = Path(folder)
    files = {folder / f"{STEM}.md": sheet_markdown(sheet, f"{STEM}.svg" if drawing else None),
             folder / f"{STEM}.csv": sheet_csv(sheet)}
    if drawing:
        from .drawing import drawing_files

        files |= {folder / name: payload
                  for name, payload in drawing_files(sheet, STEM).items()}
    write_all(files)
    return tuple(files)


__all__ = ["BuildSheet", "make_sheet", "sheet_csv", "sheet_for", "sheet_markdown",
           "write_sheet"]
