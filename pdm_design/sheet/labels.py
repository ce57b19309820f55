"""Labels and dimension lines of the build-sheet drawing, and the pass that keeps labels apart.

Every label is an annotation placed at an offset in points from the point it labels, so that it
can be moved without moving what it points at. `Labels.settle` measures each label's extent
with the figure's renderer (in the order they were made: the first ones stay where they are),
moves a label that runs into one already placed (or into any other text of the figure: tick
labels, titles, notes) to the nearest free place around its point (with a thin line back to
it), and hides an optional label (an item's number) instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

FONT = 7.5
SHIFTS = 40   # places tried around a label's point: rings of 8, 1.1 text heights apart
GAP = 3.0     # pixels: labels are placed this far apart (another renderer's fonts may differ)


@dataclass
class Labels:
    """The labels of one figure, in the order they were made (that is their priority)."""

    made: list = field(default_factory=list)   # (annotation, optional)

    def add(self, ax, text, at, offset=(0.0, 0.0), *, optional=False, line=False, **style):
        """A label `text` at the data point `at`, `offset` points away (a thin line back to the
        point when `line`)."""
        style = {"fontsize": FONT, "ha": "center", "va": "center", **style}
        style["arrowprops"] = {"arrowstyle": "-", "lw": 0.4, "color": style.get("color", "0.3")}
        note = ax.annotate(text, at, xytext=offset, textcoords="offset points",
                           annotation_clip=False, **style)
        note.arrow_patch.set_visible(line)  # the line back to the point: shown when moved
        note.set_in_layout(False)
        self.made.append((note, optional))
        return note

    def settle(self, figure) -> None:
        """Move (or, if optional, hide) every label that overlaps one placed before it or any
        other text of the figure."""
        figure.draw_without_rendering()  # axes limits as drawn (equal aspect adjusts them)
        renderer = figure.canvas.get_renderer()
        mine = {id(note) for note, _ in self.made}
        placed = [_extent(t, renderer) for t in figure_texts(figure)
                  if id(t) not in mine]
        frame = figure.bbox
        for note, optional in self.made:
            box = _extent(note, renderer)
            if not _hits(box, placed, -GAP) and _inside(box, frame):
                placed.append(box)
                continue
            spot = None if optional else self._free_spot(note, renderer, placed, frame)
            if spot is None:
                if optional:
                    note.set_visible(False)
                    continue
                note.xyann = note.xyann  # kept where it was: the test will say so
            else:
                _leader(note)
            placed.append(_extent(note, renderer))

    @staticmethod
    def _free_spot(note, renderer, placed, frame):
        x0, y0 = note.xyann
        box = _extent(note, renderer)
        step = 1.1 * box.height * 72.0 / note.figure.dpi
        for ring in range(1, SHIFTS + 1):
            for k in range(8):
                angle = math.pi / 2 + k * math.pi / 4
                note.xyann = (x0 + ring * step * 2.5 * math.cos(angle),
                              y0 + ring * step * math.sin(angle))
                box = _extent(note, renderer)
                if not _hits(box, placed, -GAP) and _inside(box, frame):
                    return note.xyann
        note.xyann = (x0, y0)
        return None


def _leader(note) -> None:
    """Show a moved label's thin line back to its point."""
    note.arrow_patch.set_visible(True)


def _extent(text, renderer):
    """The extent of a text's own letters (an annotation's line back to its point left out)."""
    from matplotlib.text import Text

    return Text.get_window_extent(text, renderer)


def _inside(box, frame) -> bool:
    return (frame.x0 + GAP <= box.x0 and box.x1 <= frame.x1 - GAP and frame.y0 + GAP <= box.y0
            and box.y1 <= frame.y1 - GAP)


def _hits(box, boxes, pad=1.0) -> bool:
    return any(box.x0 < b.x1 - pad and b.x0 < box.x1 - pad and box.y0 < b.y1 - pad
               and b.y0 < box.y1 - pad for b in boxes)


def figure_texts(figure) -> list:
    """Every text of the figure that is drawn: visible, not empty, in a visible axes."""
    from matplotlib.text import Text

    ticks = set()
    shown = []
    for ax in figure.axes:
        for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
            lo, hi = sorted((lo, hi))
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                ticks.update((id(tick.label1), id(tick.label2)))
                if ax.get_visible() and lo <= tick.get_loc() <= hi:
                    shown += [t for t in (tick.label1, tick.label2) if t.get_visible()]
    out = []
    for text in figure.findobj(Text):
        if id(text) in ticks or not (text.get_visible() and text.get_text().strip()):
            continue
        ax = text.axes
        if ax is not None and not ax.get_visible():
            continue
        out.append(text)
    return out + [t for t in shown if t.get_text().strip()]


def overlapping_texts(figure) -> list[tuple[str, str]]:
    """Pairs of drawn texts whose extents (from the figure's renderer) overlap."""
    renderer = figure.canvas.get_renderer()
    texts = figure_texts(figure)
    boxes = [_extent(t, renderer) for t in texts]
    pairs = []
    for i in range(len(texts)):
        for j in range(i):
            if _hits(boxes[i], [boxes[j]]):
                pairs.append((texts[i].get_text(), texts[j].get_text()))
    return pairs


def dimension(ax, labels, p, q, text, *, offset=0.0, side=1.0, color="black"):
    """A dimension line from p to q, drawn `offset` (data units) along its left normal, with
    arrows at both ends and its label along the line on `side` (+1 left, -1 right)."""
    (x1, y1), (x2, y2) = p, q
    length = math.hypot(x2 - x1, y2 - y1) or 1.0
    nx, ny = -(y2 - y1) / length, (x2 - x1) / length
    a = (x1 + nx * offset, y1 + ny * offset)
    b = (x2 + nx * offset, y2 + ny * offset)
    if offset:
        for start, end in ((p, a), (q, b)):
            ax.plot([start[0], end[0]], [start[1], end[1]], color="0.55", lw=0.5, ls=":")
    ax.update_datalim([a, b])  # the view holds the whole dimension line
    ax.annotate("", xy=b, xytext=a, arrowprops={"arrowstyle": "<->", "lw": 0.8, "color": color,
                                                 "shrinkA": 0, "shrinkB": 0})
    angle = math.degrees(math.atan2(y2 - y1, x2 - x1))
    if angle > 90 or angle < -90:  # text reads left to right
        angle -= 180 * math.copysign(1, angle)
    mid = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
    shift = 7 * side
    return labels.add(ax, text, mid, (nx * shift, ny * shift), rotation=angle,
                      rotation_mode="anchor", color=color)
