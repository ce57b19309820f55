"""Build sheets: `sheet_for(path)` makes one, `write_sheet` writes its Markdown, CSV, drawing
(PNG, SVG, PDF) and DXF (with a PNG rendering of it), each file whole or not at all."""

from __future__ import annotations

import stat
from pathlib import Path

from .build import BuildSheet, make_sheet, sheet_for
from .drawing import DRAWING_FORMATS
from .markdown import sheet_csv, sheet_markdown

STEM = "sheet"
DRAWING_FILES = (*(f"{STEM}.{fmt}" for fmt in DRAWING_FORMATS), f"{STEM}.dxf",
                 f"{STEM}_dxf.png")


def write_sheet(sheet: BuildSheet, folder, *, drawing: bool = True) -> tuple[Path, ...]:
    """Write sheet.md, sheet.csv and (unless drawing=False) the drawing (sheet.png, sheet.svg,
    sheet.pdf) and the DXF (sheet.dxf, rendered as sheet_dxf.png): all of them or, when one
    cannot be written, none. Without the drawing, an earlier sheet's drawing and DXF in the
    folder are removed once the new files are in place (they would show another design)."""
    from ..io import write_all

    folder = Path(folder)
    files = {folder / f"{STEM}.md": sheet_markdown(sheet, f"{STEM}.svg" if drawing else None),
             folder / f"{STEM}.csv": sheet_csv(sheet)}
    if drawing:
        from .drawing import drawing_files
        from .dxf import dxf_bytes, dxf_png

        files |= {folder / name: payload
                  for name, payload in drawing_files(sheet, STEM).items()}
        files |= {folder / f"{STEM}.dxf": dxf_bytes(sheet),
                  folder / f"{STEM}_dxf.png": dxf_png(sheet)}
    write_all(files)
    for stale in (folder / name for name in DRAWING_FILES):
        if stale not in files:
            _remove_stale(stale)
    return tuple(files)


def _remove_stale(path: Path) -> None:
    """Remove an earlier sheet's drawing: a file or a link by the drawing's own name, never a
    folder, a device or a pipe (as write_all writes into those rather than replace them)."""
    from ..errors import PdmError

    try:
        mode = path.lstat().st_mode
        if stat.S_ISREG(mode) or stat.S_ISLNK(mode):
            path.unlink()
    except FileNotFoundError:
        return
    except OSError as error:
        raise PdmError(f"cannot remove {path}, an earlier sheet's drawing (it shows another "
                       f"design): {error.strerror or error}") from error


__all__ = ["BuildSheet", "make_sheet", "sheet_csv", "sheet_for", "sheet_markdown",
           "write_sheet"]
