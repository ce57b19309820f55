"""Geometry of the manipulators row: pivots, palm slabs, and where a moving object first meets one.

Frame: origin at the first pivot's nominal place, x along the row, y up. The object is a
translating rectangle of width w and height h whose reference point is its bottom centre (x, y).
A palm is a horizontal slab of width W and thickness T whose top-surface centre is (cx, cy).

The interiors of object and palm intersect iff the object's reference point is inside the open
*contact box* of that palm

    |x - cx| < (w + W) / 2,      cy - T - h < y < cy,

so "the object meets a palm" is "its reference point enters the palm's contact box". Entering
through the top face (y falls through cy while |x - cx| < (w + W)/2) is a landing on the palm;
entering through any other face (the object's side hits the slab's end, or the object's top
hits the slab's underside) is a collision the model does not carry on from: `blocked`.

Along a ballistic flight x is linear and y quadratic in time, and along a carry arc x and y are
l sin(theta) and l cos(theta) plus constants, so every face crossing is a closed-form root; the
first entry into a box is found exactly by splitting the path at those roots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ....sim.core import SimulationRefused
from .. import physics as phys


@dataclass(frozen=True)
class Row:
    """The row of manipulators and the sizes that matter for contact (all SI, 0-based palms)."""

    pivots: tuple[tuple[float, float], ...]
    link_length: float
    alpha: float
    beta: float
    front_stop: float
    palm_width: float
    palm_thickness: float
    body_width: float
    body_height: float
    # every palm's own link length and back stop (build_row fills them), and palm mass (empty:
    # the design's for every palm)
    link_lengths: tuple[float, ...] = ()
    back_stops: tuple[float, ...] = ()
    palm_masses: tuple[float, ...] = ()
    # every manipulator's own link mass (kg, each link) and pivot friction torque (N m); empty:
    # the scene's
    link_masses: tuple[float, ...] = ()
    pivot_frictions: tuple[float, ...] = ()

    def __len__(self) -> int:
        return len(self.pivots)

    def palm_top(self, k: int, theta: float) -> tuple[float, float]:
        """Top-surface centre of palm k (0-based) at angle theta."""
        px, py = self.pivots[k]
        l = self.link_lengths[k]
        return px + l * math.sin(theta), py + l * math.cos(theta)

    def box(self, k: int, theta: float) -> Box:
        """Contact box of palm k at angle theta (see the module docstring)."""
        cx, cy = self.palm_top(k, theta)
        return Box(k, cx, 0.5 * (self.body_width + self.palm_width),
                   cy - self.palm_thickness - self.body_height, cy)

    def slab(self, k: int, theta: float) -> Box:
        """Palm k's own slab at angle theta (its top face at palm_top, palm_thickness deep)."""
        cx, cy = self.palm_top(k, theta)
        return Box(k, cx, 0.5 * self.palm_width, cy - self.palm_thickness, cy)

    def support(self, offset: float) -> tuple[float, float]:
        """Part of the object's base (relative to its centre) resting on a palm when the object's
        centre is `offset` ahead of the palm's centre."""
        w, W = self.body_width, self.palm_width
        return max(-0.5 * w, -0.5 * W - offset), min(0.5 * w, 0.5 * W - offset)


def support_words(point: float, support: tuple[float, float]) -> str:
    """Where a force line meets the object's base, against the part of the base a palm
    supports (from its centre, + ahead), in words that rounding cannot make contradict
    themselves: the edge it reaches (a located event lies on it, to the event tolerance) or
    passes, and by how much."""
    low, high = support
    edge, beyond = ("front", point - high) if point - high > low - point else ("rear", low - point)
    place = f"{point:+.6g} m from the base's centre; support [{low:+.6g}, {high:+.6g}] m"
    if beyond <= 1e-9 * max(high - low, abs(point)):
        return f"reaches the {edge} edge of the supported base ({place})"
    return f"passes the {edge} edge of the supported base by {beyond:.3g} m ({place})"


@dataclass(frozen=True)
class Parts:
    """Every manipulator's own link length (m), back stop alpha (rad), palm mass (kg), link mass
    (kg, each of its links) and pivot friction torque (N m, its joints together), as built: one
    value per manipulator of the row, or () for the design's (the scene's) everywhere."""

    link_length: tuple[float, ...] = ()
    back_stop: tuple[float, ...] = ()
    palm_mass: tuple[float, ...] = ()
    link_mass: tuple[float, ...] = ()
    pivot_friction: tuple[float, ...] = ()

    # what each may be: (low, high, inclusive low?)
    _RANGES = {"link_length": (0.0, math.inf, False), "back_stop": (-0.5 * math.pi,
                                                                   0.5 * math.pi, False),
               "palm_mass": (0.0, math.inf, False), "link_mass": (0.0, math.inf, True),
               "pivot_friction": (0.0, math.inf, True)}

    def check(self, stages: int) -> None:
        for name, (low, high, closed) in self._RANGES.items():
            values = getattr(self, name)
            if values and len(values) != stages:
                raise SimulationRefused(f"{len(values)} values of {name} for a row of {stages} "
                                        "manipulators")
            bad = [i + 1 for i, v in enumerate(values)
                   if not ((low <= v if closed else low < v) and v < high)]
            if bad:
                raise SimulationRefused(f"manipulator {bad[0]}'s {name} = {values[bad[0] - 1]:g}"
                                        " cannot be built (a back stop within +-pi/2, a "
                                        "positive link length and palm mass, a link mass and "
                                        "pivot friction torque >= 0)")


def build_row(scene, design, stages: int, offsets=(), parts: Parts | None = None) -> Row:
    """Pivots of `stages` manipulators: pivot_k = pivot_1 + (k-1) (pitch_x, -pitch_y) + offset_k.

    offsets: objects with .manipulator (1-based), .dx, .dy (m, y up). Offsets of manipulators
    beyond the row are an error (they would silently do nothing). parts: every manipulator's
    own link length, back stop, palm mass, link mass and pivot friction (default: the
    design's and the scene's)."""
    if stages < 1:
        raise SimulationRefused(f"stages must be at least 1, not {stages}")
    l = design.link_length
    pitch_x, pitch_y = (float(p) for p in phys.pitch(design.alpha, design.beta, l))
    shift = [[0.0, 0.0] for _ in range(stages)]
    for off in offsets:
        k = int(off.manipulator)
        if not 1 <= k <= stages:
            raise SimulationRefused(f"offset for manipulator {k} but the row has {stages} "
                                    "manipulators")
        shift[k - 1][0] += float(off.dx)
        shift[k - 1][1] += float(off.dy)
    pivots = tuple(
        (design.first_pivot_x + i * pitch_x + shift[i][0],
         design.first_pivot_y - i * pitch_y + shift[i][1])
        for i in range(stages)
    )
    parts = parts or Parts()
    parts.check(stages)
    return Row(pivots=pivots, link_length=l, alpha=design.alpha, beta=design.beta,
               front_stop=scene.palm.front_stop, palm_width=scene.palm.width,
               palm_thickness=scene.palm.thickness, body_width=scene.body.width,
               body_height=scene.body.height,
               link_lengths=tuple(map(float, parts.link_length)) or (l,) * stages,
               back_stops=tuple(map(float, parts.back_stop)) or (design.alpha,) * stages,
               palm_masses=tuple(map(float, parts.palm_mass)),
               link_masses=tuple(map(float, parts.link_mass)),
               pivot_frictions=tuple(map(float, parts.pivot_friction)))


@dataclass(frozen=True)
class Box:
    """Open contact box of one palm for the object's reference point."""

    palm: int
    cx: float
    half_width: float
    y_low: float
    y_high: float

    def inside(self, x: float, y: float) -> bool:
        return abs(x - self.cx) < self.half_width and self.y_low < y < self.y_high


@dataclass(frozen=True)
class Entry:
    """First entry of a path into a contact box: parameter (time or angle), palm, and how."""

    tau: float
    palm: int
    kind: str  # "top" (a landing), "side" (blocked), "start" (already inside at the start)


class Ballistic:
    """Free flight from (x0, y0) with (vx, vy) at time t0; the path parameter is time."""

    def __init__(self, t0, x0, y0, vx, vy, gravity):
        self.t0, self.x0, self.y0, self.vx, self.vy, self.g = t0, x0, y0, vx, vy, gravity

    def at(self, t):
        d = t - self.t0
        return (self.x0 + self.vx * d, self.y0 + self.vy * d - 0.5 * self.g * d * d,
                self.vx, self.vy - self.g * d)

    def point(self, t):
        x, y, _, _ = self.at(t)
        return x, y

    def bounds(self, a, b):
        """(x_min, x_max, y_min, y_max) of the path over [a, b] (b may be inf: no bound)."""
        xa, ya, _, _ = self.at(a)
        if not math.isfinite(b):
            return -math.inf, math.inf, -math.inf, math.inf
        xb, yb, _, _ = self.at(b)
        apex = self.t0 + self.vy / self.g
        y_top = self.at(apex)[1] if a < apex < b else max(ya, yb)
        return min(xa, xb), max(xa, xb), min(ya, yb), y_top

    def roots_x(self, c, a, b):
        if self.vx == 0.0:
            return []
        t = self.t0 + (c - self.x0) / self.vx
        return [t] if a < t < b else []

    def roots_y(self, c, a, b):
        # y0 + vy d - g d^2 / 2 = c  ->  (g/2) d^2 - vy d + (c - y0) = 0
        qa, qb, qc = 0.5 * self.g, -self.vy, c - self.y0
        disc = qb * qb - 4.0 * qa * qc
        if disc < 0.0:
            return []
        sq = math.sqrt(disc)
        q = -0.5 * (qb + math.copysign(sq, qb)) if qb != 0.0 else -0.5 * sq
        roots = {q / qa}
        if q != 0.0:
            roots.add(qc / q)
        else:
            roots.add(-q / qa)
        return sorted(self.t0 + d for d in roots if a < self.t0 + d < b)


class Arc:
    """The object carried on a palm: reference point (X0 + l sin th, Y0 + l cos th), by th."""

    def __init__(self, x0, y0, link_length):
        self.x0, self.y0, self.l = x0, y0, link_length

    def point(self, th):
        return self.x0 + self.l * math.sin(th), self.y0 + self.l * math.cos(th)

    def bounds(self, a, b):
        """(x_min, x_max, y_min, y_max) of the arc over [a, b]: its ends and the angles where
        x (th = +-pi/2) or y (th = 0, +-pi) is extreme."""
        x0, y0, l = self.x0, self.y0, self.l
        sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
        x_lo, x_hi = x0 + l * min(sa, sb), x0 + l * max(sa, sb)
        y_lo, y_hi = y0 + l * min(ca, cb), y0 + l * max(ca, cb)
        if a < 0.0 < b:
            y_hi = y0 + l
        if a < -0.5 * math.pi < b:
            x_lo = x0 - l
        if a < 0.5 * math.pi < b:
            x_hi = x0 + l
        if a < -math.pi < b or a < math.pi < b:
            y_lo = y0 - l
        return x_lo, x_hi, y_lo, y_hi

    @staticmethod
    def _in(values, a, b):
        return [v for v in values if a < v < b]  # (first_entry sorts and merges the cuts)

    def roots_x(self, c, a, b):
        q = (c - self.x0) / self.l
        if not -1.0 <= q <= 1.0:
            return []
        s = math.asin(q)
        return self._in([s, math.pi - s, -math.pi - s, s - 2 * math.pi, s + 2 * math.pi], a, b)

    def roots_y(self, c, a, b):
        q = (c - self.y0) / self.l
        if not -1.0 <= q <= 1.0:
            return []
        s = math.acos(q)
        return self._in([s, -s, s - 2 * math.pi, 2 * math.pi - s], a, b)


def first_entry(path, box: Box, a: float, b: float) -> Entry | None:
    """First parameter in [a, b) where `path` enters `box` (exact: splits at face crossings)."""
    kinds: dict[float, set[str]] = {a: {"start"}, b: {"end"}}
    for c in (box.cx - box.half_width, box.cx + box.half_width):
        for t in path.roots_x(c, a, b):
            kinds.setdefault(t, set()).add("side")
    for t in path.roots_y(box.y_low, a, b):
        kinds.setdefault(t, set()).add("side")
    for t in path.roots_y(box.y_high, a, b):
        kinds.setdefault(t, set()).add("top")
    cuts = sorted(kinds)
    for p, q in zip(cuts, cuts[1:]):
        if p == a and q - p <= 1e-12 * (1.0 + abs(p)):
            continue  # a start on a face line, rounded to its inner side
        if box.inside(*path.point(0.5 * (p + q))):
            found = kinds[p]
            if "start" in found:
                kind = _start_kind(box, *path.point(a))
            else:
                kind = "side" if "side" in found else "top"
            return Entry(p, box.palm, kind)
    return None


def _start_kind(box: Box, x: float, y: float) -> str:
    """How a path that is inside the box right after its start entered it: from on the top face
    (a landing at the start), from another face (a side hit), or it started inside."""
    if box.inside(x, y):
        return "start"
    if abs(x - box.cx) < box.half_width and y >= box.y_high - 1e-12 * max(1.0, abs(y)):
        return "top"
    return "side"


def first_contact(path, boxes, a: float, b: float) -> Entry | None:
    """Earliest entry of `path` into any of `boxes` on [a, b). Boxes the path's bounding box
    stays clear of (by more than a rounding margin) are skipped unexamined, and once an entry
    is found the later boxes are searched only before it (a tie keeps the earlier box)."""
    best = None
    x_lo, x_hi, y_lo, y_hi = path.bounds(a, b)
    for box in boxes:
        margin = 1e-9 * (box.half_width + box.y_high - box.y_low)
        if (x_hi < box.cx - box.half_width - margin or x_lo > box.cx + box.half_width + margin
                or y_hi < box.y_low - margin or y_lo > box.y_high + margin):
            continue
        e = first_entry(path, box, a, b)
        if e is not None:
            best, b = e, e.tau
            if b <= a:
                break
            x_lo, x_hi, y_lo, y_hi = path.bounds(a, b)
    return best


def palm_outline(row: Row, k: int, theta: float) -> np.ndarray:
    """Corners of palm k's slab at angle theta (closed polygon, for drawing)."""
    cx, cy = row.palm_top(k, theta)
    hw, t = 0.5 * row.palm_width, row.palm_thickness
    return np.array([[cx - hw, cy], [cx + hw, cy], [cx + hw, cy - t], [cx - hw, cy - t],
                     [cx - hw, cy]])


def face_guards(box_of, point_of):
    """Guards of the four faces of a contact box for a numerically integrated path.

    box_of(z) gives the Box at state z (a moving palm's box moves), point_of(z) the object's
    reference point. Each guard is (g(t, z), direction, valid(z), kind): g changes sign where the
    point crosses the face's line, and the crossing is a contact only where valid(z) holds
    (the point is within the face's extent). A face line cannot be passed between two steps
    without a sign change, unlike a penetration depth, which a fast path can skip."""

    def top(t, z):
        return point_of(z)[1] - box_of(z).y_high

    def bottom(t, z):
        return point_of(z)[1] - box_of(z).y_low

    def left(t, z):
        b = box_of(z)
        return point_of(z)[0] - (b.cx - b.half_width)

    def right(t, z):
        b = box_of(z)
        return point_of(z)[0] - (b.cx + b.half_width)

    def within_x(z):
        b = box_of(z)
        return abs(point_of(z)[0] - b.cx) < b.half_width

    def within_y(z):
        b = box_of(z)
        return b.y_low < point_of(z)[1] < b.y_high

    return [(top, -1, within_x, "top"), (bottom, 1, within_x, "side"),
            (left, 1, within_y, "side"), (right, -1, within_y, "side")]
