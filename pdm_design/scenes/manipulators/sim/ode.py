"""The numerically integrated phases of a manipulators run: the sliding carry and, with
restitution > 0, the object bouncing above its moving palm. Mixed into run.Run.

Guards are of two sorts. Physics guards (normal force, slip velocity, support, stops, ...) are
written positive while the phase holds and end it when they fall through zero (terminal
events, located by solve_ivp to the integration tolerance). Contact with another palm uses the
four face lines of its contact box (geometry.face_guards): crossing a face line is a
contact only within the face's extent, so these events do not stop the integration; the
earliest valid one, if it precedes the terminal event, ends the phase.
"""

from __future__ import annotations

import math

import numpy as np

from ....sim.core import Event
from . import phases as ph
from .geometry import Arc, face_guards, first_contact, support_words

SLIP_START_ATOLS = 100.0  # initial slip speed of a slip from relative rest, in units of atol
LIFT_GAP = 1e-9  # link lengths the object rises above its palm after a lift-off before it counts


class OdePhases:
    """Sliding carry and bouncing phases (expects the attributes and helpers of Run)."""

    def _integrate(self, rhs, t0, z0, physics, faces, max_step=math.inf, t_end=None):
        """Integrate from (t0, z0) until the first physics guard or valid face contact.

        physics: [(g(t, z), kind)] positive while the phase holds; a guard already negative at
        t0 fires at t0. faces: [(g, direction, valid, kind)] from face_guards.
        Returns (t, z, kind, sol) with kind None if nothing happened by t_end (default: within
        the phase time)."""
        for fun, kind in physics:
            if fun(t0, z0) < 0.0:
                return t0, np.asarray(z0, dtype=float), kind, None
        from ....sim.rk import solve  # solve_ivp's RK45 / DOP853 in plain floats

        events = [(fun, -1, True) for fun, _ in physics]
        events += [(fun, direction, False) for fun, direction, _, _ in faces]
        # Free steps (the sliding carry): DOP853 from rtol 1e-6 down - at 1e-8 RK45 took twice
        # its steps and more time than DOP853 at 1e-9. Steps capped by max_step (bouncing):
        # RK45 down to 1e-8, its cheaper steps win there (results/bench_accuracy.py).
        loosest = 1e-6 if max_step == math.inf else 1e-9
        method = "DOP853" if self.acc.rtol <= loosest else "RK45"
        t_end = t0 + self.phase_time if t_end is None else min(t_end, t0 + self.phase_time)
        sol = solve(rhs, t0, t_end, z0, method=method, rtol=self.acc.rtol, atol=self.acc.atol,
                    events=events, dense_output=self.record, max_step=max_step)
        best = (sol.t_last, np.asarray(sol.y_last), None)
        if sol.status == 1:
            i = next(i for i in range(len(physics)) if len(sol.t_events[i]))
            best = (sol.t_events[i][0], np.asarray(sol.y_events[i][0]), physics[i][1])
        for n, (_, _, valid, kind) in enumerate(faces):
            i = len(physics) + n
            for t, z in zip(sol.t_events[i], sol.y_events[i]):
                if t < best[0] and valid(z):
                    best = (t, np.asarray(z), kind)
        return best[0], best[1], best[2], sol

    # ------------------------------------------------------------ sliding carry
    def _sliding(self, t0, k, theta0, omega0, s0, sd0):
        """Object sliding on palm k, state (th, th', s, s'): phases.slide_accelerations."""
        l = self.ls[k]
        base = self._slide_params(1.0, k)
        sgn = math.copysign(1.0, sd0) if sd0 != 0.0 else ph.slide_direction(theta0, omega0, base)
        p = self._slide_params(sgn, k)
        if sd0 == 0.0:
            # A slip from relative rest starts with zero relative acceleration (tan th = mu), so
            # integration noise would cross s' = 0 at once. Start strictly inside the slip-stop
            # guard, at a slip speed 100 atol, far below the integration error of any speed.
            sd0 = sgn * SLIP_START_ATOLS * self.acc.atol
        rec = self._stage(k)
        if rec is not None:
            rec["slipped"] = True
        if ph.slide_accelerations(theta0, omega0, p)[3] <= 0.0:
            return self._jam(t0, k, theta0, omega0, s0, sd0)
        px, py = self.row.pivots[k]
        w, W = self.row.body_width, self.row.palm_width
        xb = ph.slide_force_point(sgn, self.mu, self.h)

        def point(z):
            return px + l * math.sin(z[0]) + z[2], py + l * math.cos(z[0])

        physics = [
            (lambda t, z: sgn * z[3], "slip_stop"),
            (lambda t, z: ph.slide_accelerations(z[0], z[1], p)[1], "lift_off"),
            (lambda t, z: ph.slide_accelerations(z[0], z[1], p)[3], "jam"),
            (lambda t, z: min(0.5 * w, 0.5 * W - z[2]) - xb, "tip"),
            (lambda t, z: xb - max(-0.5 * w, -0.5 * W - z[2]), "tip"),
            (lambda t, z: 0.5 * W - abs(z[2]), "slid_off"),
            (lambda t, z: z[1], "stall"),
            (lambda t, z: self.fs - z[0], "stranded"),
        ]
        if k == self.n - 1 and theta0 < self.beta:
            physics.append((lambda t, z: self.beta - z[0], "complete"))
        tracked = self._tracked(t0, k)  # palms swinging from rest (swinging.py)
        z0, rhs, faces = self._with_swinging(tracked, t0, [theta0, omega0, s0, sd0],
                                             ph.slide_rhs(p), point)
        for box in self._obstacles(t0, k, near=px):
            faces += [(f, d, v, (kind, box.palm))
                      for f, d, v, kind in face_guards(lambda z, b=box: b, point)]
        t_split = self._next_arrival(t0, k)  # a palm at rest from then on is an obstacle
        te, z, kind, sol = self._integrate(rhs, t0, z0, physics, faces, t_end=t_split)
        self._swung_to(te, z, 4, tracked)
        if self.record and sol is not None:
            for t in np.linspace(t0, te, 60):
                zz = sol.sol(t)
                st = self._on_palm(k, zz[0], zz[1], zz[2], zz[3])
                self._rec(t, st["x"], st["y"], st["vx"], st["vy"], zz[0], k + 1)
        theta, omega, s, sd = (float(v) for v in z[:4])
        state = self._on_palm(k, theta, omega, s, sd)
        if kind is None and t_split is not None and te >= t_split:
            return lambda: self._sliding(te, k, theta, omega, s, sd)
        if kind is None:
            msg = sol.message if sol is not None and sol.status < 0 else "no event"
            return self._fail(te, "timeout", k + 1, state, f"sliding on palm {k + 1}: {msg}")
        if isinstance(kind, tuple) and len(kind) == 3:
            return self._met_swinging(te, kind, z, 4, tracked, None, state, k + 1,
                                      carrier=(k, theta, omega, s, sd))
        if isinstance(kind, tuple):
            face, j = kind
            if face == "top":
                return self._handover(te, k, theta, omega, s, sd, j)
            why = f"the sliding object hits the side of palm {j + 1}"
            return (self._stepped_carry(te, k, (theta, omega, s, sd), z, 4, tracked, state, why)
                    or self._fail(te, "blocked", k + 1, state, why))
        if kind == "slip_stop":
            if self._sticks(theta, omega, k):
                self._log(te, "stick", k + 1, state, state, f"sticks again at th = {theta:.6g}")
                return lambda: self._stuck(te, k, theta, l * omega, s)
            self._log(te, "slip", k + 1, state, state, "the slip reverses")
            return lambda: self._sliding(te, k, theta, omega, s, 0.0)
        if kind == "jam":
            return self._jam(te, k, theta, omega, s, sd)
        if kind == "complete":
            return self._complete(te, k, theta, omega, s, sd)
        if kind == "stranded":
            return self._stop_with_object(te, k, omega, s, sd)
        if kind == "lift_off":  # the object flies on (liftoff.py)
            return self._lift_off(te, k, theta, omega, s, sd,
                                  f"the normal force vanishes while sliding, th = {theta:.6g} rad")
        details = {
            "tip": f"with sliding friction the contact force "
                   f"{support_words(xb, self.row.support(s))}, the object {s:+.4g} m from the "
                   "palm's centre",
            "slid_off": f"the object's centre passed the end of palm {k + 1}",
            "stall": f"the palm stops at th = {theta:.6g} rad and swings back",
        }
        if kind in ("tip", "slid_off"):  # the object turns off its palm: time stepped
            stepped = self._stepped_carry(te, k, (theta, omega, s, sd), z, 4, tracked, state,
                                          details[kind])
            if stepped is not None:
                return stepped
        return self._fail(te, kind, k + 1, state, details[kind])

    def _sticks(self, theta, omega, k):
        """The object at rest on palm k at (th, th') stays stuck: the contact force the stuck
        carry needs is a push within the friction cone."""
        if self.plain:
            return (abs(math.tan(theta)) <= self.mu
                    and self.g * math.cos(theta) > self.ls[k] * omega ** 2)
        thdd = ph.swing_acceleration(theta, omega, self.swings_loaded[k], direction=1.0)
        fx, fn = ph.stuck_contact_force(theta, omega, thdd, gravity=self.g,
                                        link_length=self.ls[k])
        return fn > 0.0 and abs(fx) <= self.mu * fn

    def _jam(self, t, k, theta, omega, s, sd):
        """The sliding contact cannot continue (M + m c sin th <= 0): a tangential impact."""
        st = self._on_palm(k, theta, omega, s, sd)
        imp = ph.impact(st["vx"], st["vy"], self.ls[k] * omega, theta, m=self.m,
                        mass_ratio=self.qs[k], mu=self.mu, eps=0.0)
        if imp.jam or not imp.stick or imp.w <= 0.0:
            return self._fail(t, "impact_jam", k + 1, st,
                              "the sliding contact jams and no sticking impulse resolves it")
        self._log(t, "jam", k + 1, st, self._on_palm(k, theta, imp.w / self.ls[k], s),
                  "tangential impact: the contact sticks")
        return lambda: self._stuck(t, k, theta, imp.w, s)

    # ------------------------------------------------------------ stuck carry on real links
    def _stuck_integrated(self, t0, k, theta0, omega0, s):
        """Object stuck on palm k whose links have mass or whose pivots have friction or
        damping: state (th, th'), phases.swing_acceleration with the object's mass added.
        Guards: the contact force m (A t + B r) (phases.stuck_contact_force) keeps a positive
        normal (lift_off), stays within the friction cone (slip) and crosses the base within
        the support (tip); th' -> 0 (stall: the palm stops short and swings back, or pivot
        friction holds it); front stop, beta on the last manipulator, and the first contact
        of the object's arc with a resting palm (closed form in th, geometry.first_contact)."""
        sw, g, l, mu = self.swings_loaded[k], self.g, self.ls[k], self.mu
        lo, hi = self.row.support(s)
        half_h = 0.5 * self.h

        def force(z):
            thdd = ph.swing_acceleration(z[0], z[1], sw, direction=1.0)
            return ph.stuck_contact_force(z[0], z[1], thdd, gravity=g, link_length=l)

        physics = [
            (lambda t, z: force(z)[1], "lift_off"),
            (lambda t, z: hi * force(z)[1] + half_h * force(z)[0], "tip"),
            (lambda t, z: -lo * force(z)[1] - half_h * force(z)[0], "tip"),
            (lambda t, z: mu * force(z)[1] - force(z)[0], "slip"),
            (lambda t, z: mu * force(z)[1] + force(z)[0], "slip"),
            (lambda t, z: z[1], "stall"),
            (lambda t, z: self.fs - z[0], "stranded"),
        ]
        theta_end = self.fs
        if k == self.n - 1 and theta0 < self.beta:
            physics.append((lambda t, z: self.beta - z[0], "complete"))
            theta_end = self.beta
        px, py = self.row.pivots[k]
        entry = first_contact(Arc(px + s, py, l), self._obstacles(t0, k, near=px), theta0,
                              theta_end)
        if entry is not None:
            kind = ("handover", entry.palm) if entry.kind == "top" else ("blocked", entry.palm)
            physics.append((lambda t, z: entry.tau - z[0], kind))
        tracked = self._tracked(t0, k)  # palms swinging from rest (swinging.py)
        px, py = self.row.pivots[k]
        z0, rhs, faces = self._with_swinging(
            tracked, t0, [theta0, omega0],
            lambda t, y: [y[1], ph.swing_acceleration(y[0], y[1], sw, direction=1.0)],
            lambda z: (px + l * math.sin(z[0]) + s, py + l * math.cos(z[0])))
        t_split = self._next_arrival(t0, k)  # a palm at rest from then on is an obstacle
        te, z, kind, sol = self._integrate(rhs, t0, z0, physics, faces, t_end=t_split)
        self._swung_to(te, z, 2, tracked)
        if self.record and sol is not None:
            for t in np.linspace(t0, te, 40):
                zz = sol.sol(t)
                st = self._on_palm(k, zz[0], zz[1], s)
                self._rec(t, st["x"], st["y"], st["vx"], st["vy"], zz[0], k + 1)
        theta, omega = float(z[0]), float(z[1])
        if isinstance(kind, tuple) and len(kind) == 3:
            state = self._on_palm(k, theta, omega, s)
            return self._met_swinging(te, kind, z, 2, tracked, None, state, k + 1,
                                      carrier=(k, theta, omega, s, 0.0))
        if isinstance(kind, tuple):
            theta = entry.tau  # the contact angle is closed form: the event only finds its time
        state = self._on_palm(k, theta, omega, s)
        if kind is None and t_split is not None and te >= t_split:
            return lambda: self._stuck_integrated(te, k, theta, omega, s)
        if kind is None:
            return self._fail(te, "timeout", k + 1, state, f"carry on palm {k + 1}: no event")
        if isinstance(kind, tuple):
            if kind[0] == "handover":
                return self._handover(te, k, theta, omega, s, 0.0, kind[1])
            hc = self._push_contact(te, k, theta, s, kind[1])  # pushed off its stop (pushing.py)
            if hc is not None:
                return self._push(te, k, theta, omega, s, kind[1], hc)
            return self._fail(te, "blocked", k + 1, state,
                              f"the carried object hits the side of palm {kind[1] + 1}")
        if kind == "complete":
            return self._complete(te, k, theta, omega, s)
        if kind == "stranded":
            return self._stop_with_object(te, k, omega, s, 0.0)
        if kind == "slip":
            fx, fn = force(z)
            self._log(te, "slip", k + 1, state, state,
                      f"friction / normal = {abs(fx / fn):.6g} reaches mu = {mu:g}")
            return lambda: self._sliding(te, k, theta, omega, s, 0.0)
        if kind == "lift_off":  # the object flies on (liftoff.py)
            return self._lift_off(te, k, theta, omega, s, 0.0,
                                  f"the normal force vanishes at th = {theta:.6g} rad")
        fx, fn = force(z)
        if kind == "tip" and fn <= 0.0:  # (the force line's guard met with the force gone)
            return self._lift_off(te, k, theta, omega, s, 0.0,
                                  f"the contact force vanishes at th = {theta:.6g} rad")
        if kind == "tip" and self.eps == 0.0:  # the object turns about its edge (rocking.py)
            return self._rock_onset(te, k, theta, omega, s, -half_h * fx / fn, (lo, hi),
                                    state)
        held = ph.held_by_friction(theta, sw)
        details = {
            "tip": f"the contact force crosses the base at {-half_h * fx / fn:+.4g} m, outside "
                   f"the support [{lo:+.4g}, {hi:+.4g}] m, th = {theta:.6g} rad",
            "stall": (f"the palm stops at th = {theta:.6g} rad "
                      + ("and pivot friction holds it there" if held else
                         "before the top and swings back" if theta < 0.0 else
                         "and swings back")),
        }
        return self._fail(te, kind, k + 1, state, details[kind])

    def _free_swing_arrival(self, k, theta0, w0):
        """(dt, stop angle, speed there) of an empty palm on real links and pivots swinging from
        (th0, tangential speed w0): integrated to its front or back stop, or to where pivot
        friction holds it (a turning point where its weight's torque is within the friction):
        palm k's own swing and back stop."""
        sw, l, t, theta, omega = self.swings_alone[k], self.ls[k], 0.0, theta0, w0 / self.ls[k]
        back = self.alphas[k]
        for _ in range(50):  # turning points of a swing that friction and damping slow down
            if omega == 0.0:  # at rest: held, or it starts down the way gravity pulls
                if ph.held_by_friction(theta, sw):
                    return t, theta, 0.0
                direction = 1.0 if theta > 0.0 else -1.0
            else:
                direction = math.copysign(1.0, omega)
            physics = [(lambda t_, z: z[0] + back, "back_stop"),
                       (lambda t_, z: self.fs - z[0], "front_stop"),
                       (lambda t_, z, way=direction: way * z[1], "turn")]
            te, z, kind, _ = self._integrate(
                lambda t_, y, way=direction: [y[1], ph.swing_acceleration(y[0], y[1], sw, way)],
                t, [theta, omega], physics, [])
            theta, omega, t = float(z[0]), float(z[1]), te
            if kind in ("back_stop", "front_stop"):
                stop = -back if kind == "back_stop" else self.fs
                return t, stop, abs(omega) * l
            if kind != "turn":
                return math.inf, theta, 0.0
            omega = 0.0
        return t, theta, 0.0

    # ------------------------------------------------------------ bouncing (restitution > 0)
    def _bouncing(self, t0, k, x, y, vx, vy, theta, omega, leaving=True, lifted=False):
        """Object in flight above its palm k, which swings freely (l th'' = g sin th; on real
        links and pivots phases.swing_acceleration, split where the palm turns: the Coulomb
        torque changes sign there, or holds it); leaving: the object leaves the palm's top face
        at t0 (False: the phase goes on after a split); lifted: the flight after a lift-off
        off palm k (liftoff.py), whose fall past the row is `missed` and whose contact with
        palm k is a landing."""
        g, l = self.g, self.ls[k]
        physics = [(lambda t, z: z[4] + self.alphas[k], "back_stop"),
                   (lambda t, z: self.fs - z[4], "front_stop"),
                   (lambda t, z: z[1] - self.y_floor, "fell_clear")]
        if self.plain:
            def rhs(t, z):
                return [z[2], z[3], 0.0, -g, z[5], g * math.sin(z[4]) / l]
        else:  # the palm on real links and pivots, moving one way (turn: it stops)
            sw = self.swings_alone[k]
            way = math.copysign(1.0, omega) if omega != 0.0 else (1.0 if theta > 0.0 else -1.0)
            if omega == 0.0 and ph.held_by_friction(theta, sw):
                return self._palm_held(t0, k, theta, (x, y, vx, vy))

            def rhs(t, z):
                return [z[2], z[3], 0.0, -g, z[5], ph.swing_acceleration(z[4], z[5], sw, way)]

            physics.append((lambda t, z: way * z[5], "turn"))

        def point(z):
            return z[0], z[1]

        faces = [(f, d, v, (kind, k))
                 for f, d, v, kind in face_guards(lambda z: self.row.box(k, z[4]), point)]
        # The object leaves the carrier's top face at t0: its gap to that face starts at zero.
        # gap / (t - t0) starts at the separation speed instead and has the same later root.
        # After a lift-off that speed is zero too (the gap grows like (t - t0)^3 at first,
        # below the rounding of the heights): the face is left out until the gap has exceeded
        # LIFT_GAP link lengths (`separated` splits the phase there).
        gap, gn0 = faces[0][0], vy + l * omega * math.sin(theta)
        if lifted and leaving:
            physics.append((lambda t, z: LIFT_GAP * l - gap(t, z), "separated"))
            del faces[0]
        elif leaving:
            faces[0] = ((lambda t, z: gap(t, z) / (t - t0) if t > t0 else gn0),) + faces[0][1:]
        for box in self._obstacles(t0, k):
            faces += [(f, d, v, (kind, box.palm))
                      for f, d, v, kind in face_guards(lambda z, b=box: b, point)]
        tracked = self._tracked(t0, k)  # palms swinging from rest (swinging.py)
        z0, rhs, more = self._with_swinging(tracked, t0, [x, y, vx, vy, theta, omega], rhs,
                                            point)
        faces += more
        t_split = self._next_arrival(t0, k)  # a palm at rest from then on is an obstacle
        te, z, kind, sol = self._integrate(rhs, t0, z0, physics, faces,
                                           max_step=0.05 * math.sqrt(l / g), t_end=t_split)
        self._swung_to(te, z, 6, tracked)
        if self.record and sol is not None:
            ts = np.linspace(t0, te, 40)
            zz = sol.sol(ts)
            self._rec(ts, zz[0], zz[1], zz[2], zz[3], zz[4], k + 1)
        zs = [float(v) for v in z]
        z = zs[:6]
        state = {"x": z[0], "y": z[1], "vx": z[2], "vy": z[3], "theta": z[4], "omega": z[5]}
        if kind is None and t_split is not None and te >= t_split:
            return lambda: self._bouncing(te, k, *z, leaving=False, lifted=lifted)
        if kind == "separated":
            return lambda: self._bouncing(te, k, *z, leaving=False, lifted=lifted)
        if kind == "turn":  # the palm stops: held by pivot friction, or it swings back
            z[5] = 0.0
            return lambda: self._bouncing(te, k, *z, leaving=False, lifted=lifted)
        if kind is None:
            return self._fail(te, "timeout", k + 1, state, "no event while bouncing")
        if kind in ("back_stop", "front_stop"):
            stop = -self.alphas[k] if kind == "back_stop" else self.fs
            self.rest_angle[k], self.rest_since[k] = stop, te
            after = dict(state, theta=stop, omega=0.0)
            if lifted:  # a palm event, as an empty palm's stop after a lift-off (liftoff.py)
                self.palm_events.append(Event(float(te), kind, k + 1, state, after,
                                              f"empty palm {k + 1} stopped"))
            else:
                self._log(te, kind, k + 1, state, after,
                          f"palm {k + 1} stopped while the object is in the air")
            return lambda: self._flight(te, z[0], z[1], z[2], z[3], stage=k + 1)
        if kind == "fell_clear" and lifted:
            return self._fail(te, "missed", k + 1, state,
                              "fell past the row after the lift-off, landing on no palm")
        if kind == "fell_clear":
            return self._fail(te, "fell_clear", k + 1, state, "fell past the row")
        if len(kind) == 3:  # a palm swinging from rest: the object lands on it (or not)
            if kind[0] == "top":
                self._release(k, te, z[4], l * z[5])
            return self._met_swinging(te, kind, zs, 6, tracked, tuple(z[:4]), state, k + 1,
                                      palm=(k, z[4], z[5]))
        face, j = kind
        if face != "top":
            why = f"hits the side of palm {j + 1}"
            moving = {k: (z[4], z[5])}
            moving.update((p, (zs[6 + 2 * i], zs[7 + 2 * i])) for i, p in enumerate(tracked))
            return (self._stepped(te, (z[0], z[1] + 0.5 * self.h, z[2], z[3], 0.0, 0.0), moving,
                                  state, why)
                    or self._fail(te, "blocked", k + 1, state, why))
        if j == k:
            return self._impact(te, k, z[4], l * z[5], z[0], z[1], z[2], z[3],
                                log_as="landing" if lifted else "rebound", stage=k + 1,
                                before=state, at_rest=False)
        self._release(k, te, z[4], l * z[5])
        return self._impact(te, j, self.rest_angle[j], 0.0, z[0], z[1], z[2], z[3],
                            log_as="landing", stage=k + 1, before=state, at_rest=True)

    def _palm_held(self, t, k, theta, obj):
        """Palm k, empty, has stopped at theta where pivot friction holds it: it rests there
        (an obstacle) and the object flies on among the resting palms."""
        self.rest_angle[k], self.rest_since[k] = theta, t
        self.palm_events.append(Event(float(t), "pivot_friction_stop", k + 1,
                                      {"theta": float(theta), "omega": 0.0},
                                      {"theta": float(theta), "omega": 0.0},
                                      f"empty palm {k + 1} stopped"))
        return lambda: self._flight(t, *obj, stage=k + 1)

