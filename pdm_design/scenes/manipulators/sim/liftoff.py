"""After a lift-off: the object flies, its palm swings on alone, and the run goes on from where
the object lands. Mixed into run.Run.

At a lift-off the palm's normal force is zero (v^2 = g l cos th on a stuck carry, N = 0 on a
sliding one). The object leaves with its velocity on the palm (the palm's, plus its slip) on a
ballistic path; the palm, now empty, swings alone (l th'' = g sin th) to one of its stops. The
object may come down on that same palm while it swings (an impact with the palm at its angle
and speed), on a palm at rest (the next, or any other), or on nothing: `missed`.

On real links and pivots (docs/physics.md, section 2.1) the empty palm swings by Lagrange's
equation with its links' inertia and weight, the Coulomb torque and the damping
(phases.swing_acceleration): no closed form, so object and palm are integrated together with
located events, as a bounce is (ode._bouncing with lifted=True): the palm's stops, its turning
points (where pivot friction may hold it), the faces of every palm's contact box.

Where the object meets the swinging palm is located exactly. Relative to the palm's top centre
c(t) the object moves with the acceleration -g y - c'' = lambda r(th),
lambda = v^2 / l - g cos th = (v0^2 + 2 g l cos th0 - 3 g l cos th) / l, along the palm's
radial direction r = (sin th, cos th). Its components lambda sin th and lambda cos th change sign
only where cos th = (v0^2 + 2 g l cos th0) / (3 g l), at th = 0 or at th = +-pi/2, all closed
form. Between those angles each relative coordinate is convex or concave in time, so its time
derivative is monotone and it has at most two roots, each bracketed: every face crossing of the
palm's contact box is found by Brent's method on closed-form functions of the palm angle (the
time of an angle is the closed form phases.swing_time), never by stepping. The palm angle is
the path's parameter (u = th forward, u = -th swinging back after a turn, so that it grows).
"""

from __future__ import annotations

import math

from ....sim.numerics import brentq
from . import phases as ph
from .geometry import Ballistic, Box, first_contact, first_entry

ROOT_XTOL = 1e-15  # rad: Brent to about the rounding of the angles (and 4 eps relative)


class SwingSegment:
    """The object's reference point relative to a freely swinging palm's top centre, over one
    monotone part of the swing: forward (th = u) or back after a turn (th = -u).

    fly: (t0, x0, y0, vx, vy) of the object; swing: (th0, v0) of the palm at t0 (v0 > 0 the
    speed along t); turn: the turning angle (None: the palm goes over the top); back: the
    segment after the turn."""

    def __init__(self, fly, pivot, swing, turn, back, *, gravity, link_length):
        self.t0, self.x0, self.y0, self.vx, self.vy = fly
        self.px, self.py = pivot
        self.th0, self.v0 = swing
        self.turn, self.sign = turn, -1.0 if back else 1.0
        self.g, self.l = gravity, link_length
        kw = dict(gravity=gravity, link_length=link_length)
        self.offset = (ph.swing_time(self.th0, turn, self.th0, self.v0, turn=turn, **kw)
                       if back else 0.0)
        # where the relative acceleration lambda r(th) changes the sign of a component
        cos_root = (self.v0 ** 2 + 2.0 * gravity * link_length * math.cos(self.th0)) / (
            3.0 * gravity * link_length)
        angles = [0.0, 0.5 * math.pi, -0.5 * math.pi]
        root = math.acos(cos_root) if -1.0 <= cos_root <= 1.0 else None
        if root is not None:
            angles += [root, -root]
        self.breaks = sorted(self.sign * th for th in angles)
        self.clear = self._clear_until(root) if not back else -math.inf

    def _clear_until(self, root):
        """End of the separation: the object leaves the top face with no relative velocity
        across it (gap = gap' = 0) and lambda >= 0, so gap'' = lambda cos th >= 0 keeps it on
        or above the face until lambda cos th turns negative - at the lambda root before the
        top (lambda falls there), else at pi/2. Near the start the gap grows like the cube of
        the time, below the rounding of the heights for a while; it is not searched there."""
        if self.th0 < 0.0 and root is not None:
            return -root
        return 0.5 * math.pi

    # -------------------------------------------------------- the swing and the relative path
    def theta(self, u):
        return self.sign * u

    def elapsed(self, u):
        """Time from t0 to the palm angle of u (closed form)."""
        kw = dict(gravity=self.g, link_length=self.l, turn=self.turn)
        if self.sign < 0.0:
            return self.offset + ph.swing_time(self.turn, self.theta(u), self.th0, self.v0, **kw)
        return ph.swing_time(self.th0, self.theta(u), self.th0, self.v0, **kw)

    def palm_speed(self, u):
        """The palm's velocity along t at u (negative swinging back)."""
        v2 = ph.speed_squared(self.theta(u), self.th0, self.v0, gravity=self.g,
                              link_length=self.l)
        return self.sign * math.sqrt(max(v2, 0.0))

    def point(self, u):
        th, d = self.theta(u), self.elapsed(u)
        x = self.x0 + self.vx * d - (self.px + self.l * math.sin(th))
        y = self.y0 + self.vy * d - 0.5 * self.g * d * d - (self.py + self.l * math.cos(th))
        return x, (max(y, 0.0) if u < self.clear else y)  # (no rounding below the face there)

    def rates(self, u):
        """Time derivatives of the relative point at u."""
        th, w = self.theta(u), self.palm_speed(u)
        return (self.vx - w * math.cos(th),
                self.vy - self.g * self.elapsed(u) + w * math.sin(th))

    # -------------------------------------------------------- the interface of geometry.first_entry
    def roots_x(self, c, a, b):
        return self._roots(0, c, a, b)

    def roots_y(self, c, a, b):
        return self._roots(1, c, a, b)

    def _roots(self, axis, c, a, b):
        """Every u in (a, b) where the relative coordinate `axis` equals c. Between breakpoints
        its time derivative is monotone: its one sign change (if any) splits the piece into
        parts where the coordinate is monotone, each with at most one root."""
        def f(u):
            return self.point(u)[axis] - c

        def df(u):
            return self.rates(u)[axis]

        if axis == 1:  # no crossing of the face lines while the object separates
            a = max(a, min(self.clear, b))
        cuts = [a] + [u for u in self.breaks if a < u < b] + [b]
        found = []
        for p, q in zip(cuts, cuts[1:]):
            parts = [p, q]
            dp, dq = df(p), df(q)
            if dp * dq < 0.0:
                parts.insert(1, brentq(df, p, q, xtol=ROOT_XTOL))
            for r, s in zip(parts, parts[1:]):
                fr, fs = f(r), f(s)
                if fr * fs < 0.0:
                    found.append(brentq(f, r, s, xtol=ROOT_XTOL))
                elif fs == 0.0:
                    found.append(s)
        return [u for u in found if a < u < b]


def swing_segments(fly, pivot, theta0, v0, *, gravity, link_length, back_stop, front_stop):
    """[(segment, u_start, u_end)] of a palm swinging alone from (theta0, v0 > 0 forward) to the
    stop free_palm_arrival names, with the object's flight `fly`."""
    kw = dict(gravity=gravity, link_length=link_length)
    turn = ph.turning_angle(theta0, v0, forward=True, **kw)
    if turn is None:
        if theta0 < 0.0 and ph.energy_gap(theta0, v0, **kw) == 0.0:
            return []  # balanced at the top: never arrives (measure zero; no contact followed)
        return [(SwingSegment(fly, pivot, (theta0, v0), None, False, **kw), theta0, front_stop)]
    return [(SwingSegment(fly, pivot, (theta0, v0), turn, False, **kw), theta0, turn),
            (SwingSegment(fly, pivot, (theta0, v0), turn, True, **kw), -turn, -back_stop)]


class LiftOffPhases:
    """The lift-off and the flight after it (expects the attributes and helpers of Run)."""

    def _lift_off(self, t0, k, theta0, omega0, s, sd, detail):
        """The object lifts off palm k at (theta0, omega0), sitting at s and slipping at sd."""
        g, l = self.g, self.ls[k]  # palm k's own link
        v0 = l * omega0
        # A sliding lift-off is located by solve_ivp's event to its tolerance, perhaps a hair
        # before N = 0: start the free motion where the palm no longer pushes (v^2 >= g l cos th).
        while self.plain and ph.lift_off_guard(theta0, theta0, v0, gravity=g,
                                               link_length=l) < 0.0:
            v0 = max(math.nextafter(v0, math.inf), math.sqrt(g * l * math.cos(theta0)))
        state = self._on_palm(k, theta0, v0 / l, s, sd)
        self._log(t0, "lift_off", k + 1, state, state, detail)
        if not self.plain or self._tracked(t0, k):  # the empty palm on real links and pivots,
            # or palms swinging from rest (swinging.py): integrated (ode.py)
            obj = (state["x"], state["y"], state["vx"], state["vy"])
            return lambda: self._bouncing(t0, k, *obj, theta0, v0 / l, lifted=True)
        planned = len(self.palm_events)
        self._release(k, t0, theta0, v0)
        fly = (t0, state["x"], state["y"], state["vx"], state["vy"])
        contact = self._swing_contact(fly, k, theta0, v0)
        return lambda: self._flight_after_lift_off(t0, k, fly[1:], contact, planned)

    def _swing_contact(self, fly, k, theta0, v0):
        """First entry of the flight `fly` into the contact box of palm k swinging alone from
        (theta0, v0): (time, theta, palm speed, kind) or None."""
        row = self.row
        box = Box(k, 0.0, 0.5 * (row.body_width + row.palm_width),
                  -row.palm_thickness - row.body_height, 0.0)
        for seg, a, b in swing_segments(fly, row.pivots[k], theta0, v0, gravity=self.g,
                                        link_length=self.ls[k], back_stop=-self.alphas[k],
                                        front_stop=self.fs):
            if not a < b:
                continue
            entry = first_entry(seg, box, a, b)
            if entry is not None:
                u = entry.tau
                return fly[0] + seg.elapsed(u), seg.theta(u), seg.palm_speed(u), entry.kind
        return None

    def _flight_after_lift_off(self, t0, k, obj, contact, planned):
        """The flight from a lift-off off palm k, with `contact` (from _swing_contact) where it
        meets palm k while that palm swings. A palm at rest met first, or no contact with the
        swinging palm, is an ordinary flight (palm k is an obstacle once at its stop)."""
        path = Ballistic(t0, *obj, self.g)
        roots = path.roots_y(self.y_floor, t0, math.inf)
        t_floor = roots[-1] if obj[1] > self.y_floor and roots else t0
        if contact is None or not contact[0] < t_floor:
            return self._flight(t0, *obj, stage=k + 1)
        t_c, theta, w, kind = contact
        if first_contact(path, self._obstacles(t0), t0, t_c) is not None:
            return self._flight(t0, *obj, stage=k + 1)
        arriving = [self.rest_since[j] for j in self._arrivals(t0, t_c, k)]
        if arriving:  # another palm comes to rest first: it is an obstacle from then on
            t1 = min(arriving)
            self._rec_flight(path, t0, t1)
            return lambda: self._flight_after_lift_off(t1, k, path.at(t1), contact, planned)
        self._rec_flight(path, t0, t_c)
        x, y, vx, vy = path.at(t_c)
        state = {"x": x, "y": y, "vx": vx, "vy": vy, "theta": theta, "omega": w / self.ls[k]}
        del self.palm_events[planned:]  # palm k does not reach the stop planned at the lift-off
        if kind != "top":
            return self._fail(t_c, "blocked", k + 1, state,
                              f"hit the side of palm {k + 1} while it swings after the lift-off")
        return self._impact(t_c, k, theta, w, x, y, vx, vy, log_as="landing", stage=k + 1,
                            before=state, at_rest=False)
