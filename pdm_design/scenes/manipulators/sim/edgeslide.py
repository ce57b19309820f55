"""The rocking object sliding on its pin: Coulomb friction at the one contact with its palm.
Mixed into run.Run (EdgeSlidingPhases); the pure functions are the physics (docs/physics.md,
section 2.2b).

When the rocking object's pin force leaves the friction cone (rocking.py's `slides`), the pin
slides. Two kinds of contact, as in rocking.py: the object's base corner on the palm's face
(`corner`: the corner d along the base is fixed, its place e along the palm slides), or the
palm's edge bearing on the object's base (the edge e along the palm is fixed, the base's point d
on it slides). The state is (th, th', phi, phi', u, u'), u = e (corner) or d (edge), and

    C = c(th) + (e, 0) + rho(phi, d),   rho = R(phi) (-d, h/2)

with c(th) the palm's top centre. The palm's force on the object is N (n + mu_s tau), n the
contact normal (y, or the base's normal R(phi) y), tau the tangent (x, or the base's direction
R(phi) x) and mu_s = -mu sgn(slip), slip the object's velocity along tau relative to the palm at
the contact (u' with a corner, -u' with an edge). Newton-Euler for the object and Lagrange's
equation of the translating palm, with C'' = l th'' t - l th'^2 r + a phi'' - rho phi'^2 +
(x e'' | -tau d'' + 2 n phi' d'), are four linear equations in (th'', phi'', u'', N).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .geometry import support_words
from .ode import SLIP_START_ATOLS
from .rocking import (
    Rocker,
    accelerations,
    impact_onto_pin,
    lever,
    lever_rate,
    pin_force,
    rotate,
)

ROUNDING = 1e-9  # an acceleration rounding may give for 0, relative to g


def slide_frame(phi, corner):
    """(n, tau) of the contact: the palm's face (corner) or the object's base (edge)."""
    if corner:
        return (0.0, 1.0), (1.0, 0.0)
    return (math.sin(phi), math.cos(phi)), (math.cos(phi), -math.sin(phi))


def slide_accelerations(z, d, r: Rocker, mu, slip, *, corner, held=False, direction=1.0):
    """(th'', phi'', u'', N) of the object sliding on its pin at state z = (th, th', phi, phi',
    u, u'), pinned at d along its base (u = e with a corner, u = d with an edge); slip: the sign
    of the object's slip along tau; held: the palm is held by a stop (th' = th'' = 0). N is the
    normal force (N > 0 while the contact pushes)."""
    theta, omega, phi, phid, _, rate = z
    m, l, g = r.m, r.link_length, r.gravity
    sn, cs = math.sin(theta), math.cos(theta)
    rx, ry = lever(phi, d, r.h)
    ax, ay = lever_rate(phi, d, r.h)
    (nx, ny), (tx, ty) = slide_frame(phi, corner)
    fx, fy = nx - mu * slip * tx, ny - mu * slip * ty
    if corner:
        ux, uy, cx, cy = 1.0, 0.0, 0.0, 0.0
    else:
        ux, uy = -tx, -ty
        cx, cy = 2.0 * nx * phid * rate, 2.0 * ny * phid * rate
    cx += -l * omega * omega * sn - rx * phid * phid
    cy += -l * omega * omega * cs - ry * phid * phid
    moment = -ry * fx + rx * fy  # the clockwise moment of (fx, fy) at the pin about the centre
    a = np.array([[m * l * cs, m * ax, m * ux, -fx],
                  [-m * l * sn, m * ay, m * uy, -fy],
                  [0.0, r.inertia, 0.0, -moment],
                  [r.felt * l * l, 0.0, 0.0, l * (cs * fx - sn * fy)]])
    q_th = r.weight * g * l * sn - r.torque * direction - r.damping * omega
    b = np.array([-m * cx, -m * cy - m * g, 0.0, q_th])
    if held:
        x = np.linalg.solve(a[:3, 1:], b[:3])
        return 0.0, float(x[0]), float(x[1]), float(x[2])
    x = np.linalg.solve(a, b)
    return float(x[0]), float(x[1]), float(x[2]), float(x[3])


def slide_impact(v, spin, theta, omega, phi, d, r: Rocker, mu, slip, *, corner, held=False):
    """Plastic impact that makes the pin of `r` the object's one contact while it slides there
    (its impulse outside the friction cone): the impulse P (n + mu_s tau) at the pin, the
    links' radial. The same four equations as slide_accelerations with the accelerations
    replaced by the velocities after and N by P, the velocities before on the right:
    m V+ - P f = m v, I_c phi'+ - P moment = I_c spin, M_f l^2 th'+ + l (t . f) P = M_f l^2 th'
    with V+ = l th'+ t + phi'+ a + u'+ (x | -tau). Returns (th'+, phi'+, u'+, P); held: the
    palm's stop takes the impulse (th'+ = 0)."""
    m, l = r.m, r.link_length
    sn, cs = math.sin(theta), math.cos(theta)
    ax, ay = lever_rate(phi, d, r.h)
    rx, ry = lever(phi, d, r.h)
    (nx, ny), (tx, ty) = slide_frame(phi, corner)
    fx, fy = nx - mu * slip * tx, ny - mu * slip * ty
    ux, uy = (1.0, 0.0) if corner else (-tx, -ty)
    a = np.array([[m * l * cs, m * ax, m * ux, -fx],
                  [-m * l * sn, m * ay, m * uy, -fy],
                  [0.0, r.inertia, 0.0, ry * fx - rx * fy],
                  [r.felt * l * l, 0.0, 0.0, l * (cs * fx - sn * fy)]])
    b = np.array([m * v[0], m * v[1], r.inertia * spin, r.felt * l * l * omega])
    if held:
        x = np.linalg.solve(a[:3, 1:], b[:3])
        return 0.0, float(x[0]), float(x[1]), float(x[2])
    x = np.linalg.solve(a, b)
    return float(x[0]), float(x[1]), float(x[2]), float(x[3])


def stop_pull(z, d, r: Rocker, mu, slip, normal, *, corner):
    """The generalized force along th on a held palm besides its stop's (+ pulls it forward):
    gravity's and the contact's, Q_th - l (t . f) N."""
    theta, phi = z[0], z[2]
    (nx, ny), (tx, ty) = slide_frame(phi, corner)
    fx, fy = nx - mu * slip * tx, ny - mu * slip * ty
    l = r.link_length
    q_th = r.weight * r.gravity * l * math.sin(theta) - r.damping * z[1]
    return q_th - l * (math.cos(theta) * fx - math.sin(theta) * fy) * normal


def slide_centre_velocity(z, d, r: Rocker, *, corner):
    """The object's centre velocity: l th' t + phi' a + (x e' | -tau d')."""
    theta, omega, phi, phid, _, rate = z
    ax, ay = lever_rate(phi, d, r.h)
    l = r.link_length
    vx, vy = l * omega * math.cos(theta) + phid * ax, -l * omega * math.sin(theta) + phid * ay
    if corner:
        return vx + rate, vy
    _, (tx, ty) = slide_frame(phi, corner)
    return vx - rate * tx, vy - rate * ty


def slip_speed(z, corner):
    """The object's slip along tau at the contact relative to the palm."""
    return z[5] if corner else -z[5]


class EdgeSlidingPhases:
    """The rocking object sliding on its pin (expects the attributes and helpers of Run,
    RockingPhases and TumblingPhases)."""

    def _slide_onset(self, t, k, z, r, held, side, way, state):
        """The rocking object's pin force leaves the friction cone: the pin slides, the way the
        friction the pinned motion asks for cannot hold it (slip = -sgn of that force)."""
        thdd, phidd = accelerations(z[0], z[1], z[2], z[3], r, direction=way, held=held)
        tangential, _ = pin_force(z[0], z[1], z[2], z[3], thdd, phidd, r)
        slip = -math.copysign(1.0, tangential)
        corner = not r.edge
        u = r.e if corner else r.d
        start = slip * SLIP_START_ATOLS * self.acc.atol  # the slip speed from rest (ode.py's)
        zs = list(z) + [u, start if corner else -start]
        self._log(t, "slip", k + 1, state, state,
                  f"the rocking object's {'corner' if corner else 'base'} slides on palm {k + 1}"
                  f"{'' if corner else chr(39) + 's edge'}")
        return lambda: self._edge_slide(t, k, r, zs, held, side, slip, way)

    def _slide_point(self, k, z, d, r, bx, by, corner):
        """Where the object's point (bx, by) (from its base centre) is at the slide's state z."""
        e = z[4] if corner else r.e
        dd = d if corner else z[4]
        px, py = self.row.palm_top(k, z[0])
        dx, dy = rotate(z[2], bx - dd, by)
        return px + e + dx, py + dy

    def _slide_guards(self, k, z0, d, r, held, side, slip, corner, acc, way):
        """Physics guards of the slide (positive while it holds)."""
        half = 0.5 * (self.row.palm_width if corner else self.row.body_width)
        physics = [(lambda t, z: slip * slip_speed(z, corner), "slip_stop"),
                   (lambda t, z: acc(z)[3], "lost"),
                   (lambda t, z: side * z[2], "settle"),
                   (lambda t, z: 0.5 * math.pi - side * z[2], "tipped_over"),
                   (lambda t, z: half - z[4], "off_end"),
                   (lambda t, z: z[4] + half, "off_end")]
        if held:
            drag = 1.0 if z0[0] <= -self.alphas[k] else -1.0  # the way it would leave its stop

            def pull(z):
                return stop_pull(z, z[4] if not corner else d, r, self.mu, slip, acc(z)[3],
                                 corner=corner)
            physics.append((lambda t, z: -drag * pull(z), "release"))
        else:
            physics += [(lambda t, z: z[0] + self.alphas[k], "stop"),
                        (lambda t, z: self.fs - z[0], "stop")]
            if not self.plain:  # (the palm turning, where pivot friction may hold it)
                physics.append((lambda t, z: way * z[1], "turn"))
            if k == self.n - 1 and z0[0] < self.beta:
                physics.append((lambda t, z: self.beta - z[0], "complete"))
        return physics

    def _edge_slide(self, t0, k, r, z0, held, side, slip, way):
        """The object turning and sliding on its one contact with palm k, state z0 = (th, th',
        phi, phi', u, u'). Guards: the slip stops (it sticks, or reverses), the normal force
        vanishes or the contact runs off the end of the base or the palm (the object tumbles
        off: tumbling.py), phi back to 0 or at pi/2 about the contact, the palm's stops, a held
        palm dragged off its stop, beta on the last palm, a base corner meeting another palm."""
        corner = not r.edge
        d0 = r.d

        def dof(z):
            return d0 if corner else z[4]

        def acc(z):
            return slide_accelerations(z, dof(z), r, self.mu, slip, corner=corner, held=held,
                                       direction=way)

        def rhs(t, z):
            thdd, phidd, udd, _ = acc(z)
            return [z[1], thdd, z[3], phidd, z[5], udd]

        # a slip from rest starts where the pinned force reaches the cone's side, with no slip
        # acceleration yet: one that is against the slip beyond rounding is not consistent
        from_rest = abs(slip_speed(z0, corner)) <= 2.0 * SLIP_START_ATOLS * self.acc.atol
        if from_rest and slip * slip_speed(rhs(t0, z0), corner) < -ROUNDING * self.g:
            state = self._slide_state(k, z0, dof(z0), r, corner)
            why = f"the rocking object on palm {k + 1}: no consistent slide"
            return (self._stepped_state(t0, k, state, why)
                    or self._fail(t0, "tip", k + 1, state, why + " (not followed)"))
        physics = self._slide_guards(k, z0, d0, r, held, side, slip, corner, acc, way)
        faces = self._pinned_guards(
            t0, k, lambda z: (*self._slide_point(k, z, dof(z), r, 0.0, 0.5 * r.h, corner), z[2]))
        t_split = self._next_arrival(t0, k)
        te, z, kind, sol = self._integrate(rhs, t0, list(z0), physics, faces,
                                           max_step=0.05 * math.sqrt(self.h / self.g),
                                           t_end=t_split)
        z = [float(v) for v in z]
        if self.record and sol is not None:
            for t in np.linspace(t0, te, 40):
                zz = sol.sol(t)
                st = self._slide_state(k, zz, dof(zz), r, corner)
                self._rec(t, st["x"], st["y"], st["vx"], st["vy"], st["theta"], k + 1)
        if kind is None and t_split is not None and te >= t_split:
            return lambda: self._edge_slide(te, k, r, z, held, side, slip, way)
        return self._slide_end(te, k, z, dof(z), r, held, side, slip, way, kind)

    def _slide_state(self, k, z, d, r, corner):
        """The event state: the object's bottom centre and velocity, rotation and spin."""
        z = [float(v) for v in z]
        x, y = self._slide_point(k, z, d, r, 0.0, 0.0, corner)
        cx, cy = slide_centre_velocity(z, d, r, corner=corner)
        bx, by = rotate(z[2], 0.0, -0.5 * r.h)
        e = z[4] if corner else r.e
        return {"x": x, "y": y, "vx": cx + z[3] * by, "vy": cy - z[3] * bx, "theta": z[0],
                "omega": z[1], "offset": e - d, "phi": z[2], "spin": z[3]}

    def _slide_end(self, t, k, z, d, r, held, side, slip, way, kind):
        """What follows the slide's end `kind` at state z (contact d along the base)."""
        corner = not r.edge
        state = self._slide_state(k, z, d, r, corner)
        if kind in ("lost", "off_end"):  # the object flies off, tumbling (tumbling.py)
            cx, cy = self._slide_point(k, z, d, r, 0.0, 0.5 * r.h, corner)
            body = (cx, cy, *slide_centre_velocity(z, d, r, corner=corner), z[2], z[3])
            why = "the contact force vanishes" if kind == "lost" else (
                f"the contact slides off the end of the {'palm' if corner else 'base'}")
            return self._leave(t, k, z[0], z[1], body, r.link_length, state, why)
        if kind == "slip_stop":
            pinned = replace(r, e=z[4]) if corner else replace(r, d=z[4])
            thdd, phidd = accelerations(*z[:4], pinned, direction=way, held=held)
            tangential, normal = pin_force(*z[:4], thdd, phidd, pinned)
            if normal > 0.0 and abs(tangential) <= self.mu * normal:
                self._log(t, "stick", k + 1, state, state, "the sliding pin sticks again")
                return lambda: self._rock(t, k, pinned.e - pinned.d, pinned.d, z[:4], held,
                                          way, side=side)
            slip = -math.copysign(1.0, tangential)
            start = slip * SLIP_START_ATOLS * self.acc.atol
            z = z[:5] + [start if corner else -start]
            self._log(t, "slip", k + 1, state, state, "the slip of the rocking object reverses")
            return lambda: self._edge_slide(t, k, r, z, held, side, slip, way)
        if kind == "release":
            self.rest_since[k] = math.inf
            self._log(t, "release", k + 1, state, state,
                      f"the sliding object drags palm {k + 1} off its stop")
            return lambda: self._edge_slide(t, k, r, z, False, side, slip, way)
        if kind == "complete":
            return self._complete(t, k, z[0], z[1], state["offset"])
        if kind == "settle":
            return self._slide_settle(t, k, z, d, r, held, side, state)
        if kind is None:
            return self._fail(t, "timeout", k + 1, state, f"sliding on palm {k + 1}: no event")
        if kind == "tipped_over" and corner:  # its side face comes down
            body = (slide_centre_velocity(z, d, r, corner=corner),
                    self._slide_point(k, z, d, r, 0.0, 0.5 * r.h, corner), z[3])
            return self._roll_over(t, k, z[0], z[1], body, z[4], side, held, state)
        if kind == "tipped_over":
            return self._fail(t, "tipped_over", k + 1, state,
                              f"the object turned to pi/2 sliding on palm {k + 1}: it tipped over")
        if isinstance(kind, tuple):  # it meets palm j (rocking._meets)
            centre = self._slide_point(k, z, d, r, 0.0, 0.5 * r.h, corner)
            v = slide_centre_velocity(z, d, r, corner=corner)
            contact = self._slide_point(k, z, d, r, d, 0.0, corner)
            normal, _ = slide_frame(z[2], corner)
            return self._meets(t, k, kind, (z[2], v, z[3], centre),
                               (contact, normal, (z[0], z[1]), not corner), state)
        what = {"stop": "rides its palm onto a stop",
                "turn": "turns with its palm where pivot friction acts"}[kind]
        return self._fail(t, "tip", k + 1, state,
                          f"the object sliding on its edge on palm {k + 1} {what} (not followed)")

    def _slide_landing(self, t, j, theta, w, v, r, hold, side, before, rec):
        """A landing whose impulse about the support's end (the pin of r) lies outside the
        friction cone: the sliding impact (slide_impact, the slip's sign that of the object's
        velocity along the palm relative to it before), then the object turns and slides on
        that pin. None where that is not consistent (the impulse does not push, the slip
        reverses, or the base is not lifted)."""
        corner = not r.edge
        rel = v[0] - w * math.cos(theta)
        if rel == 0.0:
            return None
        slip = math.copysign(1.0, rel)
        omega = w / r.link_length
        out = slide_impact(v, 0.0, theta, omega, 0.0, r.d, r, self.mu, slip, corner=corner)
        held = (hold == "back" and out[0] < 0.0) or (hold == "front" and out[0] > 0.0)
        if held:
            out = slide_impact(v, 0.0, theta, 0.0, 0.0, r.d, r, self.mu, slip, corner=corner,
                               held=True)
        th1, phi1, u1, impulse = out
        z = [theta, th1, 0.0, phi1, r.e if corner else r.d, u1]
        if impulse <= 0.0 or side * phi1 <= 0.0 or slip * slip_speed(z, corner) < 0.0:
            return None
        state = self._slide_state(j, z, r.d, r, corner)
        if rec is not None:
            rec["landing_speed"] = r.link_length * th1
            rec["slipped"] = True
        self._log(t, "rock", j + 1, before, state,
                  f"the impulse outside the friction cone: the object turns about the "
                  f"{'palm' if r.edge else 'base'}'s {'front' if side > 0 else 'rear'} edge at "
                  f"{phi1:+.4g} rad/s, sliding on it at {slip_speed(z, corner):+.4g} m/s")
        if held:
            self.rest_angle[j], self.rest_since[j] = theta, t
        else:
            self.rest_since[j] = math.inf
        way = 1.0 if th1 >= 0.0 else -1.0
        return lambda: self._edge_slide(t, j, r, z, held, side, slip, way)

    def _slide_settle(self, t, k, z, d, r, held, side, state):
        """The sliding object's base comes back down on palm k (phi = 0): _come_down."""
        corner = not r.edge
        v = slide_centre_velocity(z, d, r, corner=corner)
        centre = self._slide_point(k, z, d, r, 0.0, 0.5 * r.h, corner)
        return self._come_down(t, k, z[0], z[1], (v, centre, z[3]), state["offset"], side,
                               held, state)

    def _come_down(self, t, k, theta, omega, body, s, side, held, state):
        """The object's base (at offset s) comes down on palm k at phi = 0, turning about its
        `side` end (+1 the front) with body = (centre velocity, centre, phi'). As in
        rocking._rock_settle, a plastic impact about the support's other end first: if turning
        about it lifts the first one the object rocks (sliding, if the impulse leaves the
        friction cone) about it. Else it lies flat: the whole base stops turning and the
        object's translation meets the palm as a landing does (phases.impact: sticking, or
        sliding, plastic), the impulse's moment taking the spin, I_c phi' = (h/2) P_x + x_b P_y,
        which puts its point x_b on the base: it must lie on the supported part."""
        v, centre, phid = body
        lo, hi = self.row.support(s)
        other = lo if side > 0.0 else hi
        hold = ("back" if theta <= -self.alphas[k] else "front") if held else None
        r2 = self._rocker(k, s, other)
        th1, phi1, held2, (px, py) = impact_onto_pin(*v, phid, theta, omega, 0.0, r2, hold)
        if -side * phi1 * max(self.h, self.row.body_width) <= self.zeno_speed:
            return self._slide_flat(t, k, theta, omega, v, phid, s, held, state)
        if py > 0.0 and abs(px) <= self.mu * py:
            self._log(t, "rock", k + 1, state, self._rock_state(k, (theta, th1, 0.0, phi1), r2),
                      f"comes down on the other end of its base: rocks about it at "
                      f"{phi1:+.4g} rad/s")
            return lambda: self._rock(t, k, s, other, (theta, th1, 0.0, phi1), held2)
        slid = self._tumble_slide_impact((*centre, *v, 0.0, phid), k, theta, omega, 0.0, r2,
                                         hold)
        if slid is None:
            why = (f"the object comes down on the other end of its base on palm {k + 1}: no "
                   "consistent sliding impact")
            return (self._stepped(t, (*centre, *v, 0.0, phid), {k: (theta, omega)}, state, why)
                    or self._fail(t, "tip", k + 1, state, why + " (not followed)"))
        z2, held2, slip2 = slid
        self._log(t, "rock", k + 1, state, self._slide_state(k, z2, other, r2, not r2.edge),
                  "comes down on the other end of its base: rocks about it, sliding")
        way = 1.0 if z2[1] >= 0.0 else -1.0
        return lambda: self._edge_slide(t, k, r2, z2, held2, -side, slip2, way)

    def _roll_over(self, t, k, theta, omega, body, e, side, held, state):
        """The object turned to pi/2 about its base corner at e along palm k (side +1: the
        front one): its side face comes down on the palm and is its base from then on
        (tumbling._turn_body); the corner is that face's rear (front) end: _come_down."""
        state = dict(state, face=self.face)  # (phi as it was: in the frame of this face)
        self._turn_body(1 if side > 0.0 else 3)
        d = -side * 0.5 * self.row.body_width
        self._log(t, "roll", k + 1, state, state,
                  f"the object turned onto its {'front' if side > 0 else 'rear'} face on palm "
                  f"{k + 1}")
        return self._come_down(t, k, theta, omega, body, e - d, -side, held, state)

    def _slide_flat(self, t, k, theta, omega, v, phid, s, held, state):
        """The object lies flat on palm k after it came down: _slide_settle's flat impact."""
        l = self.ls[k]
        imp, held_f = self._resolve(k, v[0], v[1], l * omega, theta, 0.0, held)
        lo, hi = self.row.support(s)
        spin_moment = self.m * (self.row.body_width ** 2 + self.h ** 2) / 12.0 * phid
        xb = (spin_moment - 0.5 * self.h * imp.pt) / imp.pn if imp.pn > 0.0 else math.nan
        if imp.jam or not lo <= xb <= hi:
            why = (f"the object comes down flat on palm {k + 1}: the impulse "
                   f"{'is not consistent' if imp.jam else support_words(xb, (lo, hi))}")
            top_x, top_y = self.row.palm_top(k, theta)
            body = (top_x + s, top_y + 0.5 * self.h, v[0], v[1], 0.0, phid)
            return (self._stepped(t, body, {k: (theta, omega)}, state, why)
                    or self._fail(t, "tip", k + 1, state, why + " (not followed)"))
        after = {"x": state["x"], "y": state["y"], "vx": imp.vx, "vy": imp.vy, "theta": theta,
                 "omega": imp.w / l, "offset": s}
        self._log(t, "settle", k + 1, state, after,
                  f"the object settles flat on its palm, {'sticking' if imp.stick else 'sliding'}")
        if held_f:
            self.rest_angle[k], self.rest_since[k] = theta, t
            return self._held_slide(t, k, theta, s, 0.0 if imp.stick else imp.vx, after)
        if imp.w < 0.0:
            return self._fail(t, "stall", k + 1, after,
                              f"the object settles on palm {k + 1} driving it backwards")
        self.rest_since[k] = math.inf
        if imp.stick:
            return lambda: self._stuck(t, k, theta, imp.w, s)
        sd = imp.vx - imp.w * math.cos(theta)
        return lambda: self._sliding(t, k, theta, imp.w / l, s, sd)
