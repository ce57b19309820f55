"""Time stepping of the object among the palms: the contacts no phase of the event simulator
follows (a corner on a palm's side, three contacts, an impact with no consistent mode).

The object is a rigid rectangle (centre (x, y), rotation phi clockwise), each palm a slab that
translates along its link's arc (angle th, clockwise from the vertical, between its back and
front stops). Velocities v = (x', y', phi', th_1', ...) with the diagonal mass matrix
diag(m, m, I_c, felt_1 l_1^2, ...) are stepped by the velocity-level scheme of Stewart and
Trinkle / Moreau (docs/physics.md, section 2.2e):

    M (v+ - v) = dt f(q, v) + J^T lambda,     q+ = q + dt v+,

where every contact within MARGIN of touching is a row: its normal impulse lambda_n >= 0 keeps
the gap from closing past zero in the step (g / dt + J_n v+ >= 0, complementary: a plastic
contact, restitution 0; a penetration is given back by a displacement kept out of v), its
tangential impulse |lambda_t| <= mu lambda_n opposes the slip (in the plane the friction cone
is exactly these two bounds); a palm's stop is a row on th_k; a pivot's Coulomb torque a row
with |lambda| <= torque dt. The impulses solve that complementarity problem by projected
Gauss-Seidel (sequential impulses).

The contacts of the object with a palm's slab: by separating axes, the face of either rectangle
that separates them most is the reference, and the other's edge most against it, clipped to
that face's span, gives up to two contact points with their gaps along the face's normal (the
normal points from the palm to the object).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .rocking import rotate

MARGIN = 2e-3  # m: a contact closer than this (plus what the step may close) is a row
PUSH_OUT = 0.2  # of a penetration removed per step (the gap's rows ask for it back)
SWEEPS, PUSH_SWEEPS = 200, 20  # sequential impulses: sweeps at most (the push-out's fewer:
TOLERANCE = 1e-10  # it need not be exact), until no row changes a speed by TOLERANCE (m/s)


@dataclass(frozen=True)
class Block:
    """The object: mass, inertia about its centre, width and height (of the face it lies on)."""

    mass: float
    inertia: float
    width: float
    height: float


@dataclass(frozen=True)
class Slab:
    """A palm: pivot, link length, felt mass along the swing, mass whose weight turns it,
    pivot Coulomb torque and damping, back and front stop angles, width and thickness."""

    pivot: tuple[float, float]
    link: float
    felt: float
    weight: float
    torque: float
    damping: float
    low: float
    high: float
    width: float
    thickness: float

    def top(self, theta):
        """Top-surface centre at angle theta."""
        return (self.pivot[0] + self.link * math.sin(theta),
                self.pivot[1] + self.link * math.cos(theta))


@dataclass(frozen=True)
class Stepper:
    """The object, the palms, gravity, the palms' friction and the step (s)."""

    block: Block
    slabs: tuple[Slab, ...]
    gravity: float
    mu: float
    dt: float

    @property
    def inverse_mass(self) -> np.ndarray:
        b = self.block
        return np.array([1.0 / b.mass, 1.0 / b.mass, 1.0 / b.inertia]
                        + [1.0 / (s.felt * s.link * s.link) for s in self.slabs])


@dataclass(frozen=True)
class Contact:
    """A contact row: the palm, the gap, the normal (palm to object), the world point, the
    object's lever (its point minus its centre) and the reference face ("palm_face": points of
    the object's edge against a face of the palm; "object_face": the palm's against the
    object's) with the point's index."""

    slab: int
    gap: float
    normal: tuple[float, float]
    point: tuple[float, float]
    lever: tuple[float, float]
    kind: str
    corner: int


def block_corners(q, block):
    """World corners of the object (rear-bottom, front-bottom, front-top, rear-top)."""
    return _outline(q[0], q[1], rotate(q[2], 1.0, 0.0), rotate(q[2], 0.0, 1.0),
                    0.5 * block.width, 0.5 * block.height)[0]


def _outline(cx, cy, ex, ey, hx, hy):
    """Corners (counter-clockwise) and outward face normals (face i from corner i to i + 1) of
    the rectangle of centre c, unit axes ex, ey and half sizes hx, hy."""
    corners = [(cx + sx * hx * ex[0] + sy * hy * ey[0], cy + sx * hx * ex[1] + sy * hy * ey[1])
               for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    normals = [(-ey[0], -ey[1]), ex, ey, (-ex[0], -ex[1])]
    return corners, normals


def _separation(a, b):
    """Largest separation of outline b beyond a face of outline a: (separation, face)."""
    best, face = -math.inf, 0
    for i, (nx, ny) in enumerate(a[1]):
        vx, vy = a[0][i]
        sep = min((wx - vx) * nx + (wy - vy) * ny for wx, wy in b[0])
        if sep > best:
            best, face = sep, i
    return best, face


def _clipped(ref, face, inc):
    """The points of inc's edge most against ref's face normal, clipped to that face's span:
    [(point, separation along the normal)]."""
    (v1x, v1y), (v2x, v2y) = ref[0][face], ref[0][(face + 1) % 4]
    nx, ny = ref[1][face]
    edge = min(range(4), key=lambda i: inc[1][i][0] * nx + inc[1][i][1] * ny)
    points = [inc[0][edge], inc[0][(edge + 1) % 4]]
    tx, ty = v2x - v1x, v2y - v1y
    span = tx * tx + ty * ty
    for lo_side in (True, False):  # clip against the face's two ends
        ds = [((px - v1x) * tx + (py - v1y) * ty) if lo_side
              else (span - (px - v1x) * tx - (py - v1y) * ty) for px, py in points]
        kept = [p for p, d in zip(points, ds) if d >= 0.0]
        if len(points) == 2 and len(kept) == 1 and ds[0] * ds[1] < 0.0:
            f = ds[0] / (ds[0] - ds[1])
            (ax, ay), (bx, by) = points
            kept.append((ax + f * (bx - ax), ay + f * (by - ay)))
        points = kept
    return [((px, py), (px - v1x) * nx + (py - v1y) * ny) for px, py in points]


def contacts(stepper: Stepper, q, reach) -> list[Contact]:
    """Every contact within `reach` (m) of touching, by the separating axes of the two
    rectangles (the face of either that separates them most is the reference, the other's
    edge most against it is clipped to its span), so that a slab crossing the object with no
    corner inside it is a contact too."""
    block, out = stepper.block, []
    cx, cy, phi = q[0], q[1], q[2]
    ex, ey = rotate(phi, 1.0, 0.0), rotate(phi, 0.0, 1.0)
    body = _outline(cx, cy, ex, ey, 0.5 * block.width, 0.5 * block.height)
    size = 0.5 * math.hypot(block.width, block.height) + reach  # (the object's half diagonal)
    for i, slab in enumerate(stepper.slabs):
        tx, ty = slab.top(q[3 + i])
        mid, half = ty - 0.5 * slab.thickness, 0.5 * slab.thickness
        if abs(tx - cx) > 0.5 * slab.width + size or abs(mid - cy) > half + size:
            continue
        palm = _outline(tx, mid, (1.0, 0.0), (0.0, 1.0), 0.5 * slab.width, half)
        sep_palm, face_palm = _separation(palm, body)
        sep_body, face_body = _separation(body, palm)
        if max(sep_palm, sep_body) > reach:
            continue
        if sep_palm >= sep_body - 1e-9:  # the palm's face: points of the object's edge
            n = palm[1][face_palm]
            for c, ((px, py), gap) in enumerate(_clipped(palm, face_palm, body)):
                if gap < reach:
                    out.append(Contact(i, gap, n, (px, py), (px - cx, py - cy), "palm_face", c))
        else:  # the object's face: points of the palm's edge
            nx, ny = body[1][face_body]
            for c, ((px, py), gap) in enumerate(_clipped(body, face_body, palm)):
                if gap < reach:
                    ox, oy = px - gap * nx, py - gap * ny  # the object's point facing it
                    out.append(Contact(i, gap, (-nx, -ny), (px, py), (ox - cx, oy - cy),
                                       "object_face", c))
    return out


def _row(stepper, q, contact, direction):
    """Sparse Jacobian row [(coordinate, coefficient)] of the object's velocity relative to the
    palm at the contact, along direction: (d, v_c + phi' (ry, -rx)) - (d, l th' (cos th,
    -sin th))."""
    nx, ny = direction
    rx, ry = contact.lever
    i = contact.slab
    theta, link = q[3 + i], stepper.slabs[i].link
    return [(0, nx), (1, ny), (2, nx * ry - ny * rx),
            (3 + i, -link * (nx * math.cos(theta) - ny * math.sin(theta)))]


def forces(stepper: Stepper, q, v) -> np.ndarray:
    """Generalized forces other than the contacts: the object's weight, the palms' weight
    torque and pivot damping."""
    f = np.zeros(len(q))
    f[1] = -stepper.block.mass * stepper.gravity
    for i, s in enumerate(stepper.slabs):
        f[3 + i] = (s.weight * stepper.gravity * s.link * math.sin(q[3 + i])
                    - s.damping * v[3 + i])
    return f


@dataclass
class _Rows:
    """The step's complementarity rows: sparse J rows, targets (J v+ >= target for a
    unilateral row, = for a friction row within its bounds), bounds, and for a friction row
    the index of its normal row (else -1)."""

    jac: list
    target: list
    lo: list
    hi: list
    normal_of: list

    def add(self, jac, target, lo=0.0, hi=math.inf, normal_of=-1):
        self.jac.append(jac), self.target.append(target), self.lo.append(lo)
        self.hi.append(hi), self.normal_of.append(normal_of)


def _gap_target(gap, dt, push=0.0):
    """A unilateral row's speed bound: close the gap in the step, not past zero; a penetration
    not deeper (push: given back at that fraction of it a step)."""
    return -gap / dt if gap > 0.0 else -push * gap / dt


def step(stepper: Stepper, q, v, previous=()):
    """One step from (q, v): (q+, v+, [(contact, normal impulse, tangential impulse)]).
    previous: the last step's contacts and impulses, the start of this step's iteration for
    the same contacts (the same palm, reference face and point)."""
    dt = stepper.dt
    w = stepper.inverse_mass
    v_free = v + dt * w * forces(stepper, q, v)
    reach = MARGIN + dt * (math.hypot(v_free[0], v_free[1])
                           + abs(v_free[2]) * 0.5 * math.hypot(stepper.block.width,
                                                               stepper.block.height)
                           + max((abs(v_free[3 + i]) * s.link
                                  for i, s in enumerate(stepper.slabs)), default=0.0))
    found = contacts(stepper, q, reach)
    rows = _Rows([], [], [], [], [])
    for c in found:
        rows.add(_row(stepper, q, c, c.normal), _gap_target(c.gap, dt))
    for n_index, c in enumerate(found):
        rows.add(_row(stepper, q, c, (-c.normal[1], c.normal[0])), 0.0, 0.0, 0.0, n_index)
    for i, s in enumerate(stepper.slabs):
        theta = q[3 + i]
        for sign, gap in ((1.0, theta - s.low), (-1.0, s.high - theta)):
            if gap < 0.05:
                rows.add([(3 + i, sign)], _gap_target(gap, dt))
        if s.torque > 0.0:
            rows.add([(3 + i, 1.0)], 0.0, -s.torque * dt, s.torque * dt)
    warm = {(c.slab, c.kind, c.corner): (pn, pt) for c, pn, pt in previous}
    start = [warm.get((c.slab, c.kind, c.corner), (0.0, 0.0)) for c in found]
    start = [pn for pn, _ in start] + [pt for _, pt in start]
    lam, v_new = solve(rows, w.tolist(), v_free.tolist(), stepper.mu, start, 2 * len(found))
    v_new = np.array(v_new)
    n = len(found)
    return (q + dt * (v_new + _push_out(stepper, q, found, rows, w)), v_new,
            [(c, lam[i], lam[n + i]) for i, c in enumerate(found)])


def _push_out(stepper, q, found, rows, w):
    """Where the object has sunk into a palm (or a palm past a stop), a displacement rate that
    gives back PUSH_OUT of it in the step, kept out of the velocities (split impulses: a wedge
    that cannot give back both sides asks no impossible speed of the contacts, and no energy
    is added)."""
    dt = stepper.dt
    if all(c.gap >= 0.0 for c in found) and all(
            s.low <= q[3 + i] <= s.high for i, s in enumerate(stepper.slabs)):
        return 0.0
    pseudo = _Rows([], [], [], [], [])
    for i, c in enumerate(found):
        pseudo.add(rows.jac[i], _gap_target(c.gap, dt, PUSH_OUT))
    for i, s in enumerate(stepper.slabs):
        for sign, gap in ((1.0, q[3 + i] - s.low), (-1.0, s.high - q[3 + i])):
            if gap < 0.05:
                pseudo.add([(3 + i, sign)], _gap_target(gap, dt, PUSH_OUT))
    _, shift = solve(pseudo, w.tolist(), [0.0] * len(q), 0.0, sweeps=PUSH_SWEEPS)
    return np.array(shift)


def solve(rows: _Rows, w, v, mu, start=(), coupled=None, sweeps=SWEEPS):
    """Projected Gauss-Seidel (sequential impulses): row by row, the impulse that brings its
    speed to its target, clamped to its bounds (a friction row's to +-mu times its normal
    row's), applied to v at once; until no row changes a speed by TOLERANCE (_sweep).
    start: the first rows' impulses to begin from (the rest from 0). coupled: the number of
    first rows (the contacts'); the rest (stops, pivot torques) of a palm no contact row moves
    are solved on their own first, and only the others iterated with the contacts. Returns
    (impulses, v+)."""
    scaled = [[(k, c, c * w[k]) for k, c in jac] for jac in rows.jac]
    diag = [sum(c * cw for _, c, cw in row) for row in scaled]
    reach = [max(abs(cw) for _, _, cw in row) for row in scaled]
    lam = list(start) + [0.0] * (len(scaled) - len(start))
    for row, impulse in zip(scaled, start):
        for j, _, cw in row:
            v[j] += cw * impulse
    coupled = len(scaled) if coupled is None else coupled
    moved = {k for row in scaled[:coupled] for k, _, _ in row}
    alone = [i for i in range(coupled, len(scaled)) if scaled[i][0][0] not in moved]
    together = list(range(coupled)) + [i for i in range(coupled, len(scaled))
                                        if scaled[i][0][0] in moved]
    _sweep(alone, scaled, diag, reach, lam, v, rows, mu, sweeps)
    _sweep(together, scaled, diag, reach, lam, v, rows, mu, sweeps)
    return lam, v


def _sweep(order, scaled, diag, reach, lam, v, rows, mu, sweeps):
    """Sweeps of the rows in `order` until no row changes a speed by TOLERANCE (m/s, rad/s:
    where contacts are redundant the impulses need not settle, the speeds do)."""
    plan = [(i, scaled[i], rows.target[i], diag[i], reach[i], rows.normal_of[i], rows.lo[i],
             rows.hi[i]) for i in order]
    for _ in range(sweeps):
        change = 0.0
        for i, row, target, d, r, k, lo, hi in plan:
            speed = 0.0
            for j, c, _ in row:
                speed += c * v[j]
            old = lam[i]
            new = old - (speed - target) / d
            if k >= 0:
                lo = -mu * lam[k]
                hi = -lo
            if new < lo:
                new = lo
            elif new > hi:
                new = hi
            delta = new - old
            if delta:
                for j, _, cw in row:
                    v[j] += cw * delta
                lam[i] = new
                moved = (delta if delta > 0.0 else -delta) * r
                if moved > change:
                    change = moved
        if change < TOLERANCE:
            break
