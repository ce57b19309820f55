"""The object tumbling in free flight after it leaves its edge, and its landing on a corner or
on a palm's edge. Mixed into run.Run (TumblingPhases); docs/physics.md, section 2.2b.

When the rocking object's pin force vanishes (rocking.py's `lost`), it leaves its palm as a
free rigid body: its centre C moves on a parabola, C'' = -g y, and it turns at a constant rate,
phi' = const (no moment acts on it in flight). The palm it left swings on alone (its swing
integrated with the flight until it reaches a stop; `run.Run._release` gives that stop).

The flight ends where the two convex outlines first meet: a corner of the object enters a
palm's slab, or a corner of a palm's slab enters the object. A corner of the object entering a
slab's top, or a top corner of a slab (the palm's edge) entering the object's base (or its top
face: the rectangle turned over, the same body) is a landing: a plastic impact about that
contact point (rocking.impact_onto_pin, the object's spin included), after which the object
rocks about it (rocking.py). It is followed when the contact's impulse is inside the friction
cone and the face that comes down about the contact is the base (or the top): the rest of the
base lies on the contact's far side from the palm, so the object turns back flat onto the palm
or over its edge. Any other contact is not followed: an object corner on a slab's side or
underside (`blocked`), a palm's corner on the object's side face, a sliding landing (`tip`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from . import phases as ph
from .edgeslide import slide_frame, slide_impact, slip_speed
from .geometry import Box, face_guards
from .rocking import body_point, centre_velocity, impact_onto_pin, rotate

# the object's corners from its base centre, in units of (width, height)
CORNERS = ((-0.5, 0.0), (0.5, 0.0), (0.5, 1.0), (-0.5, 1.0))
STEP_TURN = 0.05  # largest turn of the object per integration step (rad), so no corner skips a face
END_TOL = 1e-9  # link lengths: a corner this near a palm's end meets the palm's corner
SEGMENT = 0.25  # the flight is followed in segments of this many sqrt(l / g), each with the
# contact guards of the palms within reach in it


def wrap(phi):
    """phi in [-pi, pi)."""
    return (phi + math.pi) % (2.0 * math.pi) - math.pi


def body_to_world(cx, cy, phi, bx, by, h):
    """World point of the object's point (bx, by) (from its base centre) with centre (cx, cy)."""
    dx, dy = rotate(phi, bx, by - 0.5 * h)
    return cx + dx, cy + dy


def world_to_body(cx, cy, phi, x, y, h):
    """The object's own coordinates (from its base centre) of the world point (x, y)."""
    bx, by = rotate(-phi, x - cx, y - cy)
    return bx, by + 0.5 * h


def last_value(fun):
    """fun(z) kept for the last state it was asked for: the guards of one step all ask for the
    same state, and share what it costs."""
    memo = [None, None]

    def remembered(z):
        key = tuple(z)
        if key != memo[0]:
            memo[0], memo[1] = key, fun(z)
        return memo[1]

    return remembered


def turned(turn, bx, by, w, h):
    """The object's point (bx, by) (from the base centre of its w x h outline) in the frame of
    its face `turn` quarter turns clockwise on: (bx', by', w', h'). Its centre-relative
    coordinates turn by R(turn pi / 2): R(pi/2) (x, y) = (y, -x)."""
    x, y = bx, by - 0.5 * h
    for _ in range(turn % 4):
        x, y, w, h = y, -x, h, w
    return x, y + 0.5 * h, w, h


def landing_frame(phi, bx, by, w, h, side=None):
    """The face the object comes down on about its contact point (bx, by): of the faces that
    hold the point, one turned (phi' = phi - turn pi/2) within pi/2 of lying flat the way that
    the rest of it is above the palm (side phi' > 0, side the way the contact is from the
    face's centre, or the given side: +1 the palm's front edge), the nearest to flat. Returns
    (turn, phi', d' along that face, side) or None."""
    best = None
    for turn in range(4):
        x, y, w2, _ = turned(turn, bx, by, w, h)
        if abs(y) > 1e-9 * max(w, h) or abs(x) > 0.5 * w2 * (1.0 + 1e-12):
            continue
        phi2 = wrap(phi - 0.5 * math.pi * turn)
        way = math.copysign(1.0, x) if side is None else side
        if way * phi2 > 0.0 and abs(phi2) < 0.5 * math.pi:
            if best is None or abs(phi2) < abs(best[1]):
                best = (turn, phi2, x, way)
    return best


class TumblingPhases:
    """The tumbling flight (expects the attributes and helpers of Run and RockingPhases)."""

    def _leave_edge(self, t, k, z, r, state):
        """The rocking object leaves its pin on palm k (state z = (th, th', phi, phi') of r)."""
        theta, omega, phi, phid = z
        vx, vy = centre_velocity(theta, omega, phi, phid, r)
        cx, cy = body_point(theta, phi, 0.0, 0.5 * self.h, r)
        return self._leave(t, k, theta, omega, (cx, cy, vx, vy, phi, phid), r.link_length,
                           state, "the pin force vanishes")

    def _leave(self, t, k, theta, omega, body, link_length, state, why):
        """The object leaves palm k (at theta, omega) as a free body (centre, its velocity,
        phi, phi'): palm k swings on alone, the object flies tumbling."""
        self._log(t, "leave", k + 1, state, state,
                  f"{why}: the object leaves palm {k + 1} turning at {body[5]:+.4g} rad/s")
        self._left_angle = theta
        planned = None
        if self.rest_since[k] > t:  # (a palm held by its stop stays there)
            events = len(self.palm_events)
            self._release(k, t, theta, link_length * omega)
            planned = self.palm_events[-1] if len(self.palm_events) > events else None
        return lambda: self._tumble(t, k, body, (theta, omega), planned)

    def _tumble_state(self, body):
        """The event state: bottom centre, its velocity, the rotation and spin."""
        cx, cy, vx, vy, phi, phid = (float(v) for v in body)
        bx, by = rotate(phi, 0.0, -0.5 * self.h)  # bottom centre from the centre of mass
        return {"x": cx + bx, "y": cy + by, "vx": vx + phid * by, "vy": vy - phid * bx,
                "phi": phi, "spin": phid}

    def _tumble_guards(self, t0, k, moving, body, horizon):
        """Face guards of every contact the flight may meet by t0 + horizon: palms at rest
        within reach of its path then, and palm k while it swings (its (th, th') at z[6], z[7]
        when `moving`)."""
        w, h, W, T = self.row.body_width, self.h, self.row.palm_width, self.row.palm_thickness
        cx, cy, vx, vy = body[:4]
        half = 0.5 * math.hypot(w, h)  # the object's corners are within this of its centre
        rise = min(max(vy / self.g, 0.0), horizon)
        x_lo, x_hi = cx + min(0.0, vx * horizon) - half, cx + max(0.0, vx * horizon) + half
        y_hi = cy + vy * rise - 0.5 * self.g * rise * rise + half
        y_lo = min(cy, cy + vy * horizon - 0.5 * self.g * horizon * horizon) - half
        slabs = [Box(b.palm, b.cx, 0.5 * W, b.y_high - T, b.y_high)
                 for b in self._obstacles(t0, k if moving else None)
                 if abs(b.cx - 0.5 * (x_lo + x_hi))
                 < 0.5 * (W + x_hi - x_lo) and b.y_high - T < y_hi and b.y_high > y_lo]
        faces = []
        for slab in slabs:
            faces += self._contact_guards(slab.palm, lambda z, b=slab: b)
        if moving:
            faces += self._contact_guards(k, lambda z: self.row.slab(k, z[6]))
        return faces

    def _contact_guards(self, p, slab, pose=None, skip=()):
        """Face guards of the object's corners entering palm p's slab (slab(z): its Box), and
        of the slab's corners entering the object (in the object's own frame). pose(z): the
        object's centre and rotation (the flight's by default); skip: ("corner", i) of
        CORNERS and ("edge", ex, top) of the slab's corners left unguarded (a contact there)."""
        w, h = self.row.body_width, self.h
        pose = pose or (lambda z: (z[0], z[1], z[4]))
        body_box = Box(p, 0.0, 0.5 * w, 0.0, h)
        faces = []
        for i, (bx, by) in enumerate(CORNERS):
            if ("corner", i) in skip:
                continue

            def corner(z, bx=bx * w, by=by * h):
                return body_to_world(*pose(z), bx, by, h)
            faces += [(f, d, v, ("corner", face, p, bx * w, by * h))
                      for f, d, v, face in face_guards(slab, corner)]
        for ex, top in ((-1.0, True), (1.0, True), (1.0, False), (-1.0, False)):
            if ("edge", ex, top) in skip:
                continue

            def edge(z, ex=ex, top=top):
                b = slab(z)
                return world_to_body(*pose(z), b.cx + ex * b.half_width,
                                     b.y_high if top else b.y_low, h)
            faces += [(f, d, v, ("edge", face, p, ex * 0.5 * self.row.palm_width,
                                 0.0 if top else -self.row.palm_thickness))
                      for f, d, v, face in face_guards(lambda z: body_box, edge)]
        return faces

    def _pinned_guards(self, t0, k, pose):
        """Contact guards of a phase where the object turns on palm k, pose(z) its centre and
        rotation, against the palms at rest within reach: its corners entering a slab (kinds
        (face, palm, bx): a base corner on a top is a catch, a top corner anywhere "over") and
        the slabs' corners entering it, in its own frame (kinds ("palm_corner", palm, face of
        the object: "base", "over" (its top) or "side", the corner's x, y))."""
        w, h, W, T = self.row.body_width, self.h, self.row.palm_width, self.row.palm_thickness
        pose = last_value(pose)
        corners = last_value(lambda z: [body_to_world(*pose(z), fx * w, fy * h, h)
                                        for fx, fy in CORNERS])
        boxes = self._obstacles(t0, k, near=self.row.pivots[k][0])
        points = [(b.palm, x, y) for b in boxes
                  for x in (b.cx - 0.5 * W, b.cx + 0.5 * W) for y in (b.y_high, b.y_high - T)]
        local = last_value(lambda z: [world_to_body(*pose(z), x, y, h) for _, x, y in points])
        faces = []
        for b in boxes:
            slab = Box(b.palm, b.cx, 0.5 * W, b.y_high - T, b.y_high)
            for i, (fx, fy) in enumerate(CORNERS):
                faces += [(f, d, v, (kind if not fy else "over", b.palm, fx * w))
                          for f, d, v, kind in face_guards(lambda z, s=slab: s,
                                                           lambda z, i=i: corners(z)[i])]
        body_box = Box(-1, 0.0, 0.5 * w, 0.0, h)
        for i, (p, x, y) in enumerate(points):
            # face_guards' order: the box's top (the object's top), bottom (its base), sides
            faces += [(f, d, v, ("palm_corner", p, name, x, y))
                      for (f, d, v, _), name in zip(face_guards(lambda z: body_box,
                                                                lambda z, i=i: local(z)[i]),
                                                    ("over", "base", "side", "side"))]
        return faces

    def _tumble(self, t0, k, body, palm, planned, passed=None):
        """Free flight of the tumbling object (centre, velocity, phi, phi' = body) from palm k,
        with palm k's (th, th') = palm while it swings alone."""
        g = self.g
        moving = self.rest_since[k] > t0
        sw = self.swings_alone[k]
        z0 = list(body) + (list(palm) if moving else [])

        def rhs(t, z):
            out = [z[2], z[3], 0.0, -g, z[5], 0.0]
            if moving:
                out += [z[7], ph.swing_acceleration(z[6], z[7], sw)]
            return out

        horizon = SEGMENT * math.sqrt(self.l / g)
        faces = [f for f in self._tumble_guards(t0, k, moving, body, horizon)
                 if passed is None or f[3] != ("corner", "top", *passed)]
        physics = [(lambda t, z: z[1] - self.y_floor, "fell_clear")]
        step = min(0.05 * math.sqrt(self.h / g), STEP_TURN / max(abs(body[5]), 1e-9))
        t_split = self._next_arrival(t0, None)
        t_split = t0 + horizon if t_split is None else min(t_split, t0 + horizon)
        te, z, kind, sol = self._integrate(rhs, t0, z0, physics, faces, max_step=step,
                                           t_end=t_split)
        z = [float(v) for v in z]
        state = self._tumble_state(z[:6])
        if self.record and sol is not None:
            for t in np.linspace(t0, te, 40):
                st = self._tumble_state(sol.sol(t)[:6])
                self._rec(t, st["x"], st["y"], st["vx"], st["vy"], np.nan, 0)
        if kind is None and te >= t_split:  # (a palm at rest from then on, or the segment's end)
            return lambda: self._tumble(te, k, z[:6], z[6:8] if moving else (), planned)
        if kind is None:
            return self._fail(te, "timeout", self.passed + 1, state, "no event in flight")
        if kind == "fell_clear":
            return self._fail(te, "fell_clear", self.passed + 1, state,
                              "the tumbling object fell past the row")
        palm_state = (z[6], z[7]) if moving and kind[2] == k else None
        return self._tumble_landing(te, k, z[:6], kind, palm_state, planned, state,
                                    tuple(z[6:8]) if moving else ())

    def _tumble_landing(self, t, k, body, kind, palm_state, planned, state, swing=()):
        """The tumbling object meets palm p (kind from _tumble_guards): a landing on a corner or
        on the palm's edge, followed as a rocking phase about that contact (the face that comes
        down about it its base from then on: _turn_body), or not followed."""
        what, face, p, ax, ay = kind
        cx, cy, vx, vy, phi, phid = body
        moving = {k: tuple(swing)} if swing else {}
        if palm_state is not None:
            moving[p] = palm_state
        swinging = self._swinging_from_rest(t, p)
        if swinging is not None:  # (it may meet that palm in the stepper's time)
            stepped = self._stepped(t, body, moving, state,
                                    f"the object reaches palm {p + 1} while palm {swinging}, "
                                    f"{self._swing_origin(swinging - 1)}, still swings")
            if stepped is not None:
                return stepped
        if (what == "corner" and face != "top") or (what == "edge" and ay < 0.0):
            why = f"the tumbling object hits the side of palm {p + 1}"
            return (self._stepped(t, body, moving, state, why)
                    or self._fail(t, "blocked", self.passed + 1, state, why))
        theta, omega = palm_state if palm_state is not None else (self.rest_angle[p], 0.0)
        top_x, top_y = self.row.palm_top(p, theta)
        if what == "corner":  # the object's corner (ax, ay) on the palm's top
            x_c, _ = body_to_world(cx, cy, phi, ax, ay, self.h)
            e, bx, by, side = x_c - top_x, ax, ay, None
            end = math.copysign(0.5 * self.row.palm_width, e)
            if abs(e - end) <= END_TOL * self.l:  # at the palm's end: a corner on its corner
                out = vx + phid * (body_to_world(0.0, 0.0, phi, ax, ay, self.h)[1]) - (
                    self.ls[p] * omega * math.cos(theta))
                if out * end > 0.0:  # it passes by the palm's end, going off it (that
                    # corner's crossing of the top's line is no contact for a segment)
                    return lambda: self._tumble(t, k, body, swing, planned, (p, ax, ay))
                e, side = end, math.copysign(1.0, end)  # as the palm's edge on that corner
        else:  # the palm's edge (ax along its top) on a face of the object
            bx, by = world_to_body(cx, cy, phi, top_x + ax, top_y, self.h)
            e, side = ax, math.copysign(1.0, ax)
        frame = landing_frame(phi, bx, by, self.row.body_width, self.h, side)
        if frame is None:
            why = (f"the tumbling object comes down on palm {p + 1} with no face turned to come "
                   "down about the contact")
            return (self._stepped(t, body, moving, state, why)
                    or self._fail(t, "tip", self.passed + 1, state, why + " (not followed)"))
        turn, phi_b, d, side = frame
        state = dict(state, face=self.face)  # (phi as it was: in the frame of this face)
        self._turn_body(turn)
        r = self._rocker(p, e - d, d)
        if what == "corner" and side is not None and e == math.copysign(
                0.5 * self.row.palm_width, e):  # (the palm's corner under the object's base)
            r = replace(r, edge=True)
        hold = None
        if palm_state is None:
            hold = "back" if theta <= -self.alphas[p] else "front" if theta >= self.fs else None
        th1, phi1, held, (px, py) = impact_onto_pin(vx, vy, phid, theta, omega, phi_b, r, hold)
        if r.edge:  # the impulse along the object's base and its normal
            px, py = (px * math.cos(phi_b) - py * math.sin(phi_b),
                      px * math.sin(phi_b) + py * math.cos(phi_b))
        if py > 0.0 and abs(px) <= self.mu * py:
            return self._tumble_land(t, k, p, r, (theta, th1, phi_b, phi1), held, side,
                                     planned, state)
        slid = self._tumble_slide_impact(body, p, theta, omega, phi_b, r, hold)
        if slid is None:
            self._turn_body(-turn)  # (back to the frame body is in)
            why = f"the tumbling object lands on palm {p + 1}: no consistent sliding impact"
            return (self._stepped(t, body, moving, state, why)
                    or self._fail(t, "tip", self.passed + 1, state, why + " (not followed)"))
        z, held, slip = slid
        return self._tumble_land(t, k, p, r, z, held, side, planned, state, slip)

    def _turn_body(self, turn):
        """The object's face `turn` quarter turns clockwise on from its base is its base from
        now on (the object lies on it): with an odd turn its width and height change places
        in every phase (they read them from the run)."""
        self.face = (self.face + turn) % 4
        if turn % 2:
            w, h = self.row.body_width, self.h
            self.row = replace(self.row, body_width=h, body_height=w)
            self.h = w
            self._boxes = {}

    def _tumble_slide_impact(self, body, p, theta, omega, phi, r, hold):
        """The landing's sticking impulse lies outside the friction cone: the sliding impact
        (edgeslide.slide_impact), the slip's sign that of the contact point's velocity along
        the contact's tangent relative to the palm before. (z, held, slip), or None where the
        impulse does not push or the slip reverses."""
        cx, cy, vx, vy, _, phid = body
        corner = not r.edge
        px, py = body_point(theta, phi, r.d, 0.0, r)  # the contact point
        l = r.link_length
        rel_x = vx + phid * (py - cy) - l * omega * math.cos(theta)
        rel_y = vy - phid * (px - cx) + l * omega * math.sin(theta)
        _, (tx, ty) = slide_frame(phi, corner)
        rel = rel_x * tx + rel_y * ty
        if rel == 0.0:
            return None
        slip = math.copysign(1.0, rel)
        out = slide_impact((vx, vy), phid, theta, omega, phi, r.d, r, self.mu, slip,
                           corner=corner)
        held = (hold == "back" and out[0] < 0.0) or (hold == "front" and out[0] > 0.0)
        if held:
            out = slide_impact((vx, vy), phid, theta, 0.0, phi, r.d, r, self.mu, slip,
                               corner=corner, held=True)
        th1, phi1, u1, impulse = out
        z = [theta, th1, phi, phi1, r.e if corner else r.d, u1]
        if impulse <= 0.0 or slip * slip_speed(z, corner) < 0.0:
            return None
        return z, held, slip

    def _tumble_land(self, t, k, p, r, z, held, side, planned, state, slip=None):
        """Bookkeeping of a followed landing of the tumbling object on palm p, then its rocking
        (sliding on its contact if `slip`: z then has the slide's u, u')."""
        swinging = self._swinging_from_rest(t, p)
        if swinging is not None:
            return self._fail(t, "swinging_palm", p + 1, state,
                              f"the object reaches palm {p + 1} while palm {swinging}, "
                              f"{self._swing_origin(swinging - 1)}, still swings")
        if p != self.at and self._comes_onto(p):
            return self._fail(t, "skipped_palm", self.at + 2, state,
                              f"the object flew over palm {self.at + 2} and came onto palm "
                              f"{p + 1}")
        after = (self._rock_state(p, z, r) if slip is None
                 else self._slide_state(p, z, r.d, r, not r.edge))
        if p == k and self.rest_since[k] > t and planned in self.palm_events:
            self.palm_events.remove(planned)  # palm k is met before the stop planned for it
        rec = self._stage(p)
        if rec is None:
            prev = self._stage(k)
            if prev is not None:  # (palm k's angle where the object left it)
                prev.update(handover_time=t, handover_angle=self._left_angle,
                            handover_speed=math.hypot(state["vx"], state["vy"]),
                            handover_vx=state["vx"], handover_vy=state["vy"])
            imp = ph.Impact(after["vx"], after["vy"], r.link_length * z[1], 0.0, 0.0, True)
            self._new_stage(p, t, r.e - r.d, state["vx"], state["vy"], imp)
        else:
            rec["bounces"] += 1
        self._log(t, "landing", p + 1, state, dict(after, palm=p + 1),
                  f"the tumbling object comes down on palm {p + 1} on "
                  f"{'its base at the palm' if r.edge else 'its'} "
                  f"{'front' if side > 0 else 'rear'} {'edge' if r.edge else 'corner'}")
        self.rest_since[p] = t if held else math.inf
        if held:
            self.rest_angle[p] = z[0]
        if slip is not None:
            way = 1.0 if z[1] >= 0.0 else -1.0
            return lambda: self._edge_slide(t, p, r, z, held, side, slip, way)
        return lambda: self._rock(t, p, r.e - r.d, r.d, z, held, side=side)
