"""Palms released past the vertical, followed while they swing: the object may meet one in
flight, while carried or while it bounces. Mixed into run.Run.

A palm whose back stop is past the vertical swings forward from rest as the row is built
(run.Run._release_past_vertical). Until the object first meets it, every integrated phase
carries that palm's swing (th, th') as two more state variables (phases.swing_acceleration,
its own links and pivot friction; forward all the way: gravity pulls it on past the vertical)
and the four face lines of its moving contact box as contact guards. Its top face met by the
object is an impact with the palm at its angle and speed (phases.impact, docs/physics.md
section 2.2a), after which the carry starts from the palm's actual state; any other face met
is not followed (`swinging_palm`). A flight or a carry on the paper's device is closed form
among resting palms; while such a palm swings it is integrated here instead.
"""

from __future__ import annotations

import math

import numpy as np

from . import phases as ph
from .geometry import face_guards


class SwingingPhases:
    """Following the palms that swing from rest (expects the attributes and helpers of Run)."""

    def _tracked(self, t, carrier=None):
        """Palms released past the vertical that the object has not met and that still swing at
        t (not the carrier), in order."""
        return [k for k in sorted(self.unmet) if k != carrier and self.rest_since[k] > t]

    def _free_state(self, k, t):
        """(th, th') at time t of palm k, swinging alone from rest since the row was built."""
        t0, theta, omega = self._free[k]
        if t < t0:  # (an earlier time than the last asked for: from the release again)
            t0, theta, omega = 0.0, -self.alphas[k], 0.0
        if t > t0:
            theta, omega = self._swung_alone(k, t0, theta, omega, t, 1.0)
            self._free[k] = (t, theta, omega)
        return theta, omega

    def _swung_alone(self, k, t0, theta, omega, t, direction=None):
        """(th, th') at t of palm k swinging alone from (th, th') at t0 (direction: the sign
        the Coulomb torque opposes, default th''s)."""
        sw = self.swings_alone[k]
        _, z, _, _ = self._integrate(
            lambda t_, y: [y[1], ph.swing_acceleration(y[0], y[1], sw, direction)],
            t0, [theta, omega], [], [], t_end=t)
        return float(z[0]), float(z[1])

    def _with_swinging(self, tracked, t0, z0, rhs, point):
        """Extend an integrated phase (state z0, vector field rhs, object's reference point
        point(z)) by the swings of the tracked palms: (z0, rhs, faces) of the extended phase,
        face kinds (face, palm, "swinging")."""
        if not tracked:
            return z0, rhs, []
        base = len(z0)
        z0 = list(z0) + [v for k in tracked for v in self._free_state(k, t0)]
        swings = [self.swings_alone[k] for k in tracked]

        def extended(t, z):
            out = list(rhs(t, z[:base]))
            for i, sw in enumerate(swings):
                theta, omega = z[base + 2 * i], z[base + 2 * i + 1]
                out += [omega, ph.swing_acceleration(theta, omega, sw, 1.0)]
            return out

        faces = []
        for i, k in enumerate(tracked):
            def box_of(z, k=k, at=base + 2 * i):
                return self.row.box(k, z[at])
            faces += [(f, d, v, (kind, k, "swinging"))
                      for f, d, v, kind in face_guards(box_of, point)]
        return z0, extended, faces

    def _swung_to(self, te, z, base, tracked):
        """Remember the tracked palms' states at the end of a phase."""
        for i, k in enumerate(tracked):
            self._free[k] = (te, float(z[base + 2 * i]), float(z[base + 2 * i + 1]))

    def _met_swinging(self, t, kind, z, base, tracked, obj, state, stage, carrier=None,
                      palm=None):
        """The object (x, y, vx, vy = obj) meets tracked palm j's face at t: on its top, an
        impact with the palm at its angle and speed (a handover when the object was carried on
        palm `carrier`, else a landing); any other face: time stepping (stepped.py), with palm
        = (k, th, th') of a palm the phase moves."""
        face, j, _ = kind
        i = tracked.index(j)
        theta, omega = float(z[base + 2 * i]), float(z[base + 2 * i + 1])
        if face != "top":
            why = (f"the object meets the side of palm {j + 1}, {self._swing_origin(j)}, while "
                   f"it swings at th = {theta:.6g} rad")
            if carrier is not None:
                stepped = self._stepped_carry(t, carrier[0], carrier[1:], z, base, tracked,
                                              state, why)
            else:
                moving = {p: (float(z[base + 2 * i]), float(z[base + 2 * i + 1]))
                          for i, p in enumerate(tracked)}
                if palm is not None:
                    moving[palm[0]] = tuple(palm[1:])
                stepped = self._stepped(t, (obj[0], obj[1] + 0.5 * self.h, obj[2], obj[3], 0.0,
                                            0.0), moving, state, why)
            return stepped or self._fail(t, "swinging_palm", j + 1, state, why
                                         + " (not followed)")
        self._unplan(j)
        w = self.ls[j] * omega
        if carrier is not None:  # (palm k, th, th', s, s') of the carry
            return self._handover(t, *carrier, j, palm=(theta, w))
        return self._impact(t, j, theta, w, *obj, log_as="landing", stage=stage,
                            before=dict(state, palm_theta=theta, palm_omega=omega),
                            at_rest=False)

    def _swing_origin(self, j):
        """How palm j came to swing: pushed off its back stop by the carried object
        (pushing.py), or released past the vertical at the build."""
        return ("pushed off its back stop" if j in self.pushed
                else "released past the vertical")

    def _unplan(self, j):
        """Palm j is met while it swings from rest: its planned stop does not happen."""
        self.unmet.discard(j)
        planned = self._planned.pop(j, None)
        if planned is not None and planned in self.palm_events:
            self.palm_events.remove(planned)

    # ------------------------------------------------------------ a flight among them
    def _flight_swinging(self, t0, x, y, vx, vy, stage, tracked):
        """Free flight while the tracked palms swing: object and palms integrated together,
        the resting palms' and the swinging palms' faces as contact guards."""
        g = self.g

        def point(z):
            return z[0], z[1]

        z0, rhs, faces = self._with_swinging(
            tracked, t0, [x, y, vx, vy], lambda t, z: [z[2], z[3], 0.0, -g], point)
        for box in self._obstacles(t0):
            faces += [(f, d, v, (kind, box.palm))
                      for f, d, v, kind in face_guards(lambda z, b=box: b, point)]
        physics = [(lambda t, z: z[1] - self.y_floor, "fell_clear")]
        t_split = self._next_arrival(t0, None)
        te, z, kind, sol = self._integrate(rhs, t0, z0, physics, faces,
                                           max_step=0.05 * math.sqrt(self.l / g), t_end=t_split)
        self._swung_to(te, z, 4, tracked)
        if self.record and sol is not None:
            ts = np.linspace(t0, te, 40)
            zz = sol.sol(ts)
            self._rec(ts, zz[0], zz[1], zz[2], zz[3], np.nan, 0)
        obj = tuple(float(v) for v in z[:4])
        state = dict(zip(("x", "y", "vx", "vy"), obj))
        if kind is None and t_split is not None and te >= t_split:
            return lambda: self._flight(te, *obj, stage=stage)
        if kind is None:
            return self._fail(te, "timeout", self.passed + 1, state, "no event in flight")
        if kind == "fell_clear":
            lifted = self.events and self.events[-1].kind == "lift_off"
            return self._fail(te, "missed" if lifted else "fell_clear", self.passed + 1, state,
                              "fell past the row")
        if len(kind) == 3:
            return self._met_swinging(te, kind, z, 4, tracked, obj, state, stage)
        face, j = kind
        if face != "top":
            why = f"hit the side of palm {j + 1} in flight"
            moving = {k: (float(z[4 + 2 * i]), float(z[5 + 2 * i]))
                      for i, k in enumerate(tracked)}
            return (self._stepped(te, (obj[0], obj[1] + 0.5 * self.h, obj[2], obj[3], 0.0, 0.0),
                                  moving, state, why)
                    or self._fail(te, "blocked", self.passed + 1, state, why))
        return self._impact(te, j, self.rest_angle[j], 0.0, *obj, log_as="landing",
                            stage=stage, before=state, at_rest=True)
