"""Contacts no event phase follows, followed by time stepping (stepping.py). Mixed into run.Run.

Where a phase meets a contact it has no model for (the object's corner on a palm's side or
underside, a palm's corner on the object's side, a third contact while it rests across two
palms, a palm met while it swings, an impact with no consistent mode), the run goes on in the
stepper from that instant with the object and every palm within reach, until one of:

- the object lies flat on one palm and no other touches it for SETTLE: the event phases take
  it on (a carry, stuck or sliding, or a palm held by a stop);
- it is clear of every palm: a tumbling flight (tumbling.py);
- it falls past the row (`fell_clear`), the last palm carries it past beta (completed), it rests
  across palms (`stranded`), or the stepped time runs out (`timeout`).

A palm that bears the object up (a contact normal within 45 degrees of the vertical) other than
the one it came onto last is the object coming onto it (Run._comes_onto).
"""

from __future__ import annotations

import math

import numpy as np

from . import phases as ph
from .rocking import rotate
from .stepping import Block, Slab, Stepper, block_corners, contacts, step

STEP = 4e-4  # s
SETTLE = 50  # steps a state must last to end the stepping
FLAT, SPIN = 1e-4, 1e-2  # rad, rad/s: lying flat on a palm
STOPPED = 1e-4  # rad from a stop, with |th'| below STOPPED / STEP: the palm rests there
REST_SPEED = 1e-5  # m/s: every part at rest
MAX_TIME = 3.0  # s stepped at most in one go
WHOLE_TIME = 60.0  # s: a whole run stepped (_step_whole)
RECORD_EVERY = 25
UP = 0.7  # a contact whose normal is this near the vertical bears the object up
OVERLAP = 1e-3  # m: a palm this deep in the object where the stepping would start: not followed


class SteppedPhases:
    """The time-stepped phase (expects the attributes and helpers of Run and the phases)."""

    def _stepped(self, t, body, moving, state, why):
        """Go on by time stepping from t: body = (centre x, y, its velocity, phi, phi') in the
        frame of the face the object lies on, moving = {palm: (th, th')} of the palms the
        phase moves. None when the state of a palm within reach is unknown here, or a palm is
        already inside the object (a released palm swings unseen by the phases until it
        stops): the caller then ends the run as before, not followed."""
        if self.eps != 0.0:
            return None
        palms = sorted(self._near(body[0]))
        states = [moving.get(k) or self._palm_now(k, t) for k in palms]
        if any(s is None for s in states):
            return None
        stepper = self._stepper(palms)
        q = np.array([body[0], body[1], body[4]] + [s[0] for s in states], dtype=float)
        v = np.array([body[2], body[3], body[5]] + [s[1] for s in states], dtype=float)
        if min((c.gap for c in contacts(stepper, q, 0.0)), default=0.0) < -OVERLAP:
            return None  # (a palm the phases let swing unseen has passed into the object)
        for k in palms:  # their planned stops are the stepper's to find now
            self.palm_events = [e for e in self.palm_events
                                if not (e.stage == k + 1 and e.time > t)]
            self._planned.pop(k, None)
        self._log(t, "stepped", self.passed + 1, state, state,
                  f"{why}: followed by time stepping")
        return lambda: self._step_on(t, stepper, palms, q, v)

    def _stepped_carry(self, t, k, carry, z, base, tracked, state, why):
        """_stepped from a carry on palm k (th, th', s, s'), with the tracked palms' swings in
        z from index base."""
        theta, omega, s, sd = carry
        x, y, vx, vy = ph.object_state_on_palm(self.row.pivots[k], theta, omega, s, sd,
                                               self.ls[k])
        moving = {p: (float(z[base + 2 * i]), float(z[base + 2 * i + 1]))
                  for i, p in enumerate(tracked)}
        moving[k] = (theta, omega)
        return self._stepped(t, (x, y + 0.5 * self.h, vx, vy, 0.0, 0.0), moving, state, why)

    def _stepped_state(self, t, k, state, why):
        """_stepped from an event state of the object on palm k (its bottom centre and that
        point's velocity, phi, spin; the palm's theta, omega)."""
        phi, spin = state["phi"], state["spin"]
        bx, by = rotate(phi, 0.0, -0.5 * self.h)  # the bottom centre from the centre
        body = (state["x"] - bx, state["y"] - by, state["vx"] - spin * by,
                state["vy"] + spin * bx, phi, spin)
        return self._stepped(t, body, {k: (state["theta"], state["omega"])}, state, why)

    def _palm_now(self, k, t):
        """(th, th') of palm k at t from the run's bookkeeping: at rest, swinging from rest
        (swinging.py) or swinging alone since its release; None if unknown."""
        if self.rest_since[k] <= t:
            return self.rest_angle[k], 0.0
        if k in self.unmet:
            return self._free_state(k, t)
        launched = self._launched.get(k)
        if launched is None or launched[0] > t:
            return None
        t0, theta, omega = launched
        return self._swung_alone(k, t0, theta, omega, t) if t > t0 else (theta, omega)

    def _stepper(self, palms):
        w, h = self.row.body_width, self.h
        slabs = []
        for k in palms:
            sw = self.swings_alone[k]
            felt, weight, torque, damping = ((self.Ms[k], self.Ms[k], 0.0, 0.0) if self.plain
                                             else (sw.inertia, sw.weight, sw.torque, sw.damping))
            slabs.append(Slab(self.row.pivots[k], self.ls[k], felt, weight, torque, damping,
                              -self.alphas[k], self.fs, self.row.palm_width,
                              self.row.palm_thickness))
        block = Block(self.m, self.m * (w * w + h * h) / 12.0, w, h)
        return Stepper(block, tuple(slabs), self.g, self.mu, STEP)

    def _step_whole(self, t, x, y, vx, vy):
        """The whole run time stepped from the object's state (bottom centre) at t, every palm
        in the stepper and none handed back to the phases: a second method for the phases
        (results/bench_stepped_row.py)."""
        palms = list(range(self.n))
        states = [self._palm_now(k, t) for k in palms]
        q = np.array([x, y + 0.5 * self.h, 0.0] + [s[0] for s in states], dtype=float)
        v = np.array([vx, vy, 0.0] + [s[1] for s in states], dtype=float)
        return self._step_on(t, self._stepper(palms), palms, q, v, whole=True)

    def _step_on(self, t0, stepper, palms, q, v, whole=False):
        """Step until the stepping ends (the module docstring); whole: end only the run."""
        t, flat, clear, rest, last, found = t0, 0, 0, 0, None, ()
        last_palm = self.n - 1 if self.n - 1 in palms else None
        before = q[3 + palms.index(last_palm)] if last_palm is not None else None
        limit = WHOLE_TIME if whole else MAX_TIME
        while t - t0 < limit:
            q, v, found = step(stepper, q, v, found)
            t += stepper.dt
            touching = sorted({palms[c.slab] for c, n, _ in found if n > 0.0})
            bearing = sorted({palms[c.slab] for c, n, _ in found if n > 0.0 and c.normal[1] > UP})
            for j in bearing:
                if j != self.at:
                    if self._comes_onto(j):
                        return self._fail(t, "skipped_palm", self.at + 2, self._body_state(q, v),
                                          f"the object flew over palm {self.at + 2} and came "
                                          f"onto palm {j + 1}")
            last = touching[-1] if touching else last
            if self.record and round((t - t0) / stepper.dt) % RECORD_EVERY == 0:
                st = self._body_state(q, v)
                self._rec(t, st["x"], st["y"], st["vx"], st["vy"], np.nan, 0)
            if q[1] < self.y_floor:
                return self._fail(t, "fell_clear", self.passed + 1, self._body_state(q, v),
                                  "the object fell past the row")
            if last_palm is not None:  # the last palm carries it past beta
                theta = q[3 + palms.index(self.n - 1)]
                if bearing == [self.n - 1] and before < self.beta <= theta:
                    return self._stepped_complete(t, palms, q, v)
                before = theta
            lying = self._lying_on(stepper, palms, q, v, touching)
            flat = flat + 1 if lying is not None else 0
            clear = clear + 1 if not found else 0
            rest = rest + 1 if touching and float(np.max(np.abs(v))) * self.l < REST_SPEED else 0
            if whole and rest and lying is not None:  # at rest on a palm at a stop
                return self._stepped_flat(t, palms, q, v, *lying)
            if flat >= SETTLE and not whole:
                return self._stepped_flat(t, palms, q, v, *lying)
            if clear >= SETTLE and not whole:
                return self._stepped_flight(t, palms, q, v, last)
            if rest >= SETTLE:
                self._stepped_palms(t, palms, q, v)
                return self._fail(t, "stranded", self.passed + 1, self._body_state(q, v),
                                  "the object rests across palms "
                                  + " and ".join(str(j + 1) for j in touching))
        self._stepped_palms(t, palms, q, v)
        return self._fail(t, "timeout", self.passed + 1, self._body_state(q, v),
                          f"time stepping for {limit:g} s reached no state the phases follow")

    def _lying_on(self, stepper, palms, q, v, touching):
        """(palm, quarter turns) when the object lies flat on one palm and touches no other."""
        if len(touching) != 1 or abs(v[2]) > SPIN:
            return None
        turn = round(q[2] / (0.5 * math.pi))
        if abs(q[2] - turn * 0.5 * math.pi) > FLAT:
            return None
        j = touching[0]
        i = palms.index(j)
        corners = block_corners(q, stepper.block)
        low = min(c[1] for c in corners)
        if abs(low - stepper.slabs[i].top(q[3 + i])[1]) > 10.0 * FLAT * self.l:
            return None
        return j, turn % 4

    def _stepped_palms(self, t, palms, q, v, keep=None):
        """Hand the palms back to the run's bookkeeping at t: at rest on a stop, or swinging
        on alone (Run._release), but palm `keep`."""
        for i, k in enumerate(palms):
            if k == keep:
                continue
            theta, omega = float(q[3 + i]), float(v[3 + i])
            stop = self._stop_of(k, theta, omega)
            if stop is not None:
                self.rest_angle[k], self.rest_since[k] = stop, t
            else:
                events = len(self.palm_events)
                self._release(k, t, theta, self.ls[k] * omega)
                if k in self.unmet:
                    self._free[k] = (t, theta, omega)
                    if len(self.palm_events) > events:
                        self._planned[k] = self.palm_events[-1]

    def _stop_of(self, k, theta, omega):
        """The stop palm k rests on at (th, th'): within STOPPED of it, still or moving into
        it slower than STOPPED / STEP (the next step's stop row holds it); else None."""
        for stop, into in ((-self.alphas[k], -1.0), (self.fs, 1.0)):
            if abs(theta - stop) < STOPPED and (abs(omega) < STOPPED
                                                or 0.0 <= into * omega < STOPPED / STEP):
                return stop
        return None

    def _stepped_flat(self, t, palms, q, v, j, turn):
        """The object lies flat on palm j: a carry (stuck or sliding) or a held palm."""
        if turn:
            self._turn_body(turn)
        i = palms.index(j)
        theta, omega = float(q[3 + i]), float(v[3 + i])
        self._stepped_palms(t, palms, q, v, keep=j)
        top_x, _ = self.row.palm_top(j, theta)
        s = float(q[0]) - top_x
        sd = float(v[0]) - self.ls[j] * omega * math.cos(theta)
        if abs(sd) < REST_SPEED:
            sd = 0.0
        state = self._on_palm(j, theta, omega, s, sd)
        self._log(t, "stepped", j + 1, state, state,
                  f"the object lies on palm {j + 1}: the phases take it on")
        stop = self._stop_of(j, theta, omega)
        if stop is not None:
            self.rest_angle[j], self.rest_since[j] = stop, t
            return self._held_slide(t, j, stop, s, sd, state)
        self.rest_since[j] = math.inf
        if sd != 0.0:
            return lambda: self._sliding(t, j, theta, omega, s, sd)
        if self.plain:
            return lambda: self._stuck(t, j, theta, self.ls[j] * omega, s)
        return lambda: self._stuck_integrated(t, j, theta, omega, s)

    def _stepped_flight(self, t, palms, q, v, last):
        """The object is clear of every palm: a tumbling flight."""
        self._stepped_palms(t, palms, q, v)
        k = last if last is not None else max(self.at, 0)
        swing = ()
        if self.rest_since[k] > t:
            swing = self._palm_now(k, t) or ()
        body = [float(x) for x in (q[0], q[1], v[0], v[1], q[2], v[2])]
        planned = next((e for e in reversed(self.palm_events) if e.stage == k + 1
                        and e.time > t), None)
        return lambda: self._tumble(t, k, body, swing, planned)

    def _stepped_complete(self, t, palms, q, v):
        n = self.n - 1
        i = palms.index(n)
        self._stepped_palms(t, palms, q, v, keep=n)
        theta, omega = float(q[3 + i]), float(v[3 + i])
        return self._complete(t, n, theta, omega, float(q[0]) - self.row.palm_top(n, theta)[0])

    def _body_state(self, q, v):
        body = [float(x) for x in (q[0], q[1], v[0], v[1], q[2], v[2])]
        return self._tumble_state(body)
