"""The dimensioned drawing of a build sheet, in millimetres and degrees (matplotlib Figure + Agg
canvas; no pyplot state).

`draw(sheet)` draws the whole device, every stage's item, scaled to fit one page, with the
parts list and the tolerances below it; `drawing_files` writes it as PNG and SVG, and as a PDF
whose first page is that drawing, followed by pages of PAGE_ITEMS items each at a larger scale
and the table of every item. The device itself is drawn by its scene
(Scene.draw_sheet: scenes/<kind>/drawing.py), with its words (Scene.sheet_words). Labels never
overlap (sheet/labels.py).
"""

from __future__ import annotations

import io
import math
import textwrap

from ..plugin import of
from ..report.render import render_figure
from .build import BuildSheet
from .labels import FONT, Labels
from .parts import parts_list, tolerance_entries

DRAWING_FORMATS = ("png", "svg", "pdf")
PAGE_ITEMS = 6          # items (one a stage) on each detail page of the PDF
TABLE_ROWS = 60         # rows of the items' table on each of its PDF pages
WIDTH = 13.0            # inches
DPI = 120               # of the PNG, and of the text extents that keep labels apart
WARNING_WIDTH, WARNING_LINES = 110, 3  # characters a line, lines: the drawing's warning
NOTE_WIDTH = 170        # characters a line of the notes below the drawing


def drawing_files(sheet: BuildSheet, stem: str = "sheet") -> dict[str, bytes]:
    """{file name: bytes}: the whole device as PNG and SVG, and the PDF of it page by page."""
    figure = draw(sheet)
    return {f"{stem}.png": render_figure(figure, "png", dpi=DPI),
            f"{stem}.svg": render_figure(figure, "svg"),
            f"{stem}.pdf": drawing_pdf(sheet, figure)}


def draw(sheet: BuildSheet, first: int = 1, last: int | None = None, *, notes: bool = True):
    """The figure of items first..last (1-based, default all) with, when `notes`, the parts
    list and the tolerances below the drawing."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    last = sheet.count if last is None else last
    items = sheet.items[first - 1:last]
    lines = _notes(sheet) if notes else []
    figure = Figure(figsize=(WIDTH, 6.0), dpi=DPI)  # labels are kept apart at this dpi
    FigureCanvasAgg(figure)
    ax = figure.add_axes((0, 0, 1, 1))
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.2)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    labels = Labels()
    detail = len(items) <= PAGE_ITEMS  # a longer view: the PDF's pages carry the dimensions
    of(sheet.spec).draw_sheet(ax, labels, sheet, items, detail)
    notes_top = _layout(figure, ax, len(lines), bool(sheet.failures))
    _title(figure, sheet, first, last)
    if lines:
        figure.text(0.01, notes_top, "\n".join(lines), fontsize=FONT - 0.5,
                    family="monospace", va="top", ha="left")
    labels.settle(figure)
    figure.sheet_labels = labels  # the labels placed (tests check them against the lines)
    return figure


def _title(figure, sheet, first, last):
    name = sheet.spec.name or sheet.spec.source
    scene = of(sheet.spec)
    what = scene.stage_noun[1]
    shown = (f"{sheet.count} {what}" if (first, last) == (1, sheet.count) else
             f"{what} {first} to {last} of {sheet.count}")
    units = scene.sheet_words().units
    title = f"{name}: {shown} ({units})"
    if sheet.failures:  # the workshop sees it on the drawing too, not only in sheet.md
        warning = textwrap.wrap(f"DOES NOT WORK - DO NOT BUILD: {sheet.failures[0]}",
                                WARNING_WIDTH, max_lines=WARNING_LINES)
        figure.suptitle("\n".join([title, *warning]), color="tab:red", fontweight="bold",
                        y=1 - 0.1 / figure.get_figheight(), va="top")
    else:
        figure.suptitle(title, y=1 - 0.1 / figure.get_figheight(), va="top")


def _layout(figure, ax, note_lines: int, warning: bool) -> float:
    """Size the figure to the drawing's aspect (equal scales) plus the notes, and place the axes
    (inches: 0.9 left, 0.3 right, title and warning on top, x label 0.6 below); returns where
    the notes start (figure fraction)."""
    ax.autoscale_view()
    x_lo, x_hi = ax.get_xlim()
    y_lo, y_hi = ax.get_ylim()
    draw_w = WIDTH - 1.2
    draw_h = min(max(draw_w * (y_hi - y_lo) / max(x_hi - x_lo, 1e-12), 3.0), 8.5)
    notes_h = 0.125 * note_lines + (0.2 if note_lines else 0.0)
    top = 0.55 + (0.22 * WARNING_LINES if warning else 0.0)
    height = top + draw_h + 0.6 + notes_h
    figure.set_size_inches(WIDTH, height)
    ax.set_position((0.9 / WIDTH, (notes_h + 0.6) / height, draw_w / WIDTH, draw_h / height))
    return (notes_h + 0.05) / height


def _notes(sheet) -> list[str]:
    """The lines below the drawing: the legend, the parts list and every tolerance."""
    scene = of(sheet.spec)
    words = scene.sheet_words()
    legend = words.legend
    if sheet.count > PAGE_ITEMS:
        pages = math.ceil(sheet.count / PAGE_ITEMS)
        what, where = scene.stage_noun[0], f"{words.item}'s"
        legend += (f". Each {what} dimensioned: sheet.pdf, pages 2 to {pages + 1} "
                   f"({PAGE_ITEMS} a page); every {where} coordinates: the pages after them "
                   "and sheet.csv")
    lines = textwrap.wrap(legend, NOTE_WIDTH) + ["", "PARTS"]
    parts, other = parts_list(sheet)
    for part in parts:
        tol = "; ".join(f"{e.quantity} {e.shown()}" for e in part.tolerances)
        text = f"{part.quantity:>4} x {part.name}: {part.dimensions}" + (
            f"   TOLERANCE {tol}" if tol else "")
        lines += textwrap.wrap(text, NOTE_WIDTH, subsequent_indent=" " * 9)
    entries = tolerance_entries(sheet)
    lines += ["", "TOLERANCES (+-, build each part within this of its nominal). (spec): the "
              "spec's statistical tolerances; (box): the worst-case box the optimizer computed"]
    if not entries:
        lines += textwrap.wrap(f"none: {sheet.tolerance_note}", NOTE_WIDTH)
    for e in entries:
        lines += textwrap.wrap(f"{e.quantity} {e.shown()}: {e.applies_to}; {e.limited_by}",
                               NOTE_WIDTH, subsequent_indent="    ")
    if other:
        lines.append("(tolerances above that name no part of the list apply as stated)")
    from .build_to import build_to_sentence  # which of two tolerances on a part

    lines += textwrap.wrap(build_to_sentence(sheet), NOTE_WIDTH)
    return lines


# --------------------------------------------------------------------------- PDF

def drawing_pdf(sheet: BuildSheet, overview=None) -> bytes:
    """The PDF: the whole device, then PAGE_ITEMS items a page, then the table of every pivot
    or step (TABLE_ROWS rows a page)."""
    from matplotlib.backends.backend_pdf import PdfPages

    buffer = io.BytesIO()
    with PdfPages(buffer, metadata={"CreationDate": None, "Producer": "pdm-design",
                                    "Creator": "pdm-design"}) as pdf:
        pdf.savefig(overview if overview is not None else draw(sheet))
        if sheet.count > PAGE_ITEMS:
            for first in range(1, sheet.count + 1, PAGE_ITEMS):
                last = min(sheet.count, first + PAGE_ITEMS - 1)
                pdf.savefig(draw(sheet, first, last, notes=False))
        for figure in _table_pages(sheet):
            pdf.savefig(figure)
    return buffer.getvalue()


def _table_pages(sheet):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rows = of(sheet.spec).table_rows(sheet)
    header, body = rows[0], rows[1:]
    for start in range(0, len(body), TABLE_ROWS):
        figure = Figure(figsize=(8.27, 11.69))
        FigureCanvasAgg(figure)
        what = of(sheet.spec).sheet_words().item
        figure.text(0.05, 0.97, f"{sheet.spec.name or sheet.spec.source}: every {what} "
                    f"(mm)", fontsize=10, va="top")
        chunk = [header, *body[start:start + TABLE_ROWS]]
        figure.text(0.05, 0.94, "\n".join(chunk), fontsize=7, family="monospace", va="top")
        yield figure
