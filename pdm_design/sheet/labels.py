"""Labels and dimension lines of the build-sheet drawing, and the pass that keeps labels apart.

Every label is an annotation placed at an offset in points from the point it labels, so that it
can be moved without moving what it points at. `Labels.settle` measures each label's extent
with the figure's renderer (in the order they were made: the first ones stay where they are),
moves a label that runs into one already placed (or into any other text of the figure: tick
labels, titles, notes) to the nearest free place around its point (with a thin line back to
it), and hides an optional label (an item's number) instead. A label that is not optional also
keeps off the drawing's lines (the device's parts, dimension and leader lines, the axes'
frame) where a place free of them is found near its point; else it keeps off the texts only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

FONT = 7.5
SHIFTS = 40   # places tried around a label's point: rings of 8, 1.1 text heights apart
LINE_SHIFTS = 20  # of those, the rings searched for a place off the drawing's lines too
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
        leaders = {id(note): note.arrow_patch.get_visible() for note, _ in self.made}
        for note, _ in self.made:  # a leader is a line to keep off once its label is placed
            note.arrow_patch.set_visible(False)
        for note, optional in self.made:
            note.arrow_patch.set_visible(leaders[id(note)])
            lines = drawn_segments(figure, renderer, skip=note) if not optional else None
            box = _extent(note, renderer)
            clear = not _hits(box, placed, -GAP) and _inside(box, frame)
            if clear and (optional or not _text_crosses(note, box, lines)):
                placed.append(box)
                continue
            spot = None if optional else self._free_spot(note, renderer, placed, frame, lines)
            if spot is None and clear:  # no place off the lines near it: where it is
                placed.append(box)
                continue
            if spot is None and not optional:
                spot = (self._free_spot(note, renderer, placed, frame)
                        or _nearest_free(note, renderer, placed, frame))
            if spot is None:
                if optional:
                    note.set_visible(False)
                    continue
                _within(note, renderer, frame)  # kept near where it was, on the page
            else:
                _leader(note)
            placed.append(_extent(note, renderer))

    @staticmethod
    def _free_spot(note, renderer, placed, frame, lines=None):
        x0, y0 = note.xyann
        box = _extent(note, renderer)
        step = 1.1 * box.height * 72.0 / note.figure.dpi
        for ring in range(1, (SHIFTS if lines is None else LINE_SHIFTS) + 1):
            for k in range(8):
                angle = math.pi / 2 + k * math.pi / 4
                note.xyann = (x0 + ring * step * 2.5 * math.cos(angle),
                              y0 + ring * step * math.sin(angle))
                box = _within(note, renderer, frame)
                if (not _hits(box, placed, -GAP) and _inside(box, frame)
                        and (lines is None or not _text_crosses(note, box, lines))
                        and not _leader_crosses(note, box, placed)):
                    return note.xyann
        note.xyann = (x0, y0)
        return None


def _nearest_free(note, renderer, placed, frame, steps: int = 24):
    """The nearest place on the page, on a grid of steps x steps offsets, where the label
    runs into no text placed (lines and its leader not minded: a last resort before a label
    off the page); None when there is none."""
    x0, y0 = note.xyann
    points = 72.0 / note.figure.dpi
    dx, dy = frame.width * points / steps, frame.height * points / steps
    offsets = sorted(((i * dx, j * dy) for i in range(-steps, steps + 1)
                      for j in range(-steps, steps + 1)), key=lambda o: math.hypot(*o))
    for ox, oy in offsets:
        note.xyann = (x0 + ox, y0 + oy)
        box = _extent(note, renderer)
        if _inside(box, frame) and not _hits(box, placed, -GAP):
            return note.xyann
    note.xyann = (x0, y0)
    return None


def _within(note, renderer, frame):
    """The label's extent, the label first moved the least that brings it inside the page
    (`frame`, GAP in) where its place runs over an edge: a long label beside the page's edge
    has a place near its point there too. (A label wider or taller than the page stays put.)"""
    box = _extent(note, renderer)
    dx = max(frame.x0 + GAP - box.x0, 0.0) - max(box.x1 - frame.x1 + GAP, 0.0)
    dy = max(frame.y0 + GAP - box.y0, 0.0) - max(box.y1 - frame.y1 + GAP, 0.0)
    if (dx or dy) and box.width + 2 * GAP <= frame.width and box.height + 2 * GAP <= frame.height:
        points = 72.0 / note.figure.dpi  # xyann is in points
        x, y = note.xyann
        note.xyann = (x + dx * points, y + dy * points)
        box = _extent(note, renderer)
    return box


def _leader_crosses(note, box, placed) -> bool:
    """Whether the line from the label (its centre) back to its point runs through a label
    placed before it."""
    import numpy as np

    px, py = note.axes.transData.transform(note.xy) if note.axes else note.xy
    cx, cy = (box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2
    segment = np.array([[cx, cy, px, py]])
    return any(_crosses(b, segment) for b in placed)


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


def drawn_segments(figure, renderer, skip=None):
    """Every straight piece of the axes' lines, patches (outlines), annotation arrows and
    frames, in display pixels: an (n, 4) array x0, y0, x1, y1 (curves as polylines); the
    annotation `skip`'s own leader left out."""
    import numpy as np
    from matplotlib.text import Annotation

    pieces = []
    for ax in figure.axes:
        if not ax.get_visible():
            continue
        paths = [line.get_transform().transform_path(line.get_path()) for line in ax.lines
                 if line.get_visible() and line.get_linestyle() not in ("None", "", " ")]
        paths += [p.get_transform().transform_path(p.get_path()) for p in ax.patches
                  if p.get_visible()]
        for t in ax.texts:
            if (isinstance(t, Annotation) and t is not skip and t.get_visible()
                    and t.arrow_patch is not None and t.arrow_patch.get_visible()):
                t.update_positions(renderer)
                paths.append(t.arrow_patch.get_path())
        for path in paths:
            for poly in path.to_polygons(closed_only=False):
                if len(poly) > 1:
                    pieces.append(np.hstack([poly[:-1], poly[1:]]))
        b = ax.bbox
        corners = np.array([[b.x0, b.y0], [b.x1, b.y0], [b.x1, b.y1], [b.x0, b.y1], [b.x0, b.y0]])
        pieces.append(np.hstack([corners[:-1], corners[1:]]))
    return np.vstack(pieces) if pieces else np.zeros((0, 4))


def _text_crosses(text, box, segments) -> bool:
    """Whether any segment runs through the text's letters: its extent `box` for level text;
    for a rotated text the rectangle of its letters, turned with it (the extent, a box around
    that rectangle, is larger)."""
    import numpy as np
    from matplotlib.transforms import Bbox

    angle = math.radians(text.get_rotation())
    c, s = abs(math.cos(angle)), abs(math.sin(angle))
    if abs(c * c - s * s) < 0.2 or s < 1e-6 or not len(segments):  # near 45 degrees or level
        return _crosses(box, segments)
    w = (box.width * c - box.height * s) / (c * c - s * s)
    h = (box.height * c - box.width * s) / (c * c - s * s)
    if w <= 0 or h <= 0:
        return _crosses(box, segments)
    cx, cy = (box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2
    ca, sa = math.cos(-angle), math.sin(-angle)
    turned = np.empty_like(segments)
    for i in (0, 2):
        x, y = segments[:, i] - cx, segments[:, i + 1] - cy
        turned[:, i], turned[:, i + 1] = ca * x - sa * y, sa * x + ca * y
    return _crosses(Bbox([[-w / 2, -h / 2], [w / 2, h / 2]]), turned)


def _crosses(box, segments, pad: float = 1.0) -> bool:
    """Whether any segment runs through the box (shrunk by pad pixels): an end inside it, or
    a crossing of one of its sides (Liang-Barsky clipping, vectorised)."""
    import numpy as np

    if not len(segments):
        return False
    x0, y0, x1, y1 = box.x0 + pad, box.y0 + pad, box.x1 - pad, box.y1 - pad
    if x1 <= x0 or y1 <= y0:
        return False
    px, py = segments[:, 0], segments[:, 1]
    dx, dy = segments[:, 2] - px, segments[:, 3] - py
    lo, hi = np.zeros(len(px)), np.ones(len(px))
    ok = np.ones(len(px), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for p, q in ((-dx, px - x0), (dx, x1 - px), (-dy, py - y0), (dy, y1 - py)):
            parallel = p == 0
            ok &= ~(parallel & (q < 0))
            t = q / p
            lo = np.where(~parallel & (p < 0), np.maximum(lo, t), lo)
            hi = np.where(~parallel & (p > 0), np.minimum(hi, t), hi)
    return bool(np.any(ok & (lo <= hi)))


def labels_on_lines(figure, labels) -> list[str]:
    """The texts of the shown, not optional labels that a drawn line runs through."""
    renderer = figure.canvas.get_renderer()
    out = []
    for note, optional in labels.made:
        if optional or not note.get_visible():
            continue
        lines = drawn_segments(figure, renderer, skip=note)  # its own leader ends at its edge
        if _text_crosses(note, _extent(note, renderer), lines):
            out.append(note.get_text())
    return out


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
