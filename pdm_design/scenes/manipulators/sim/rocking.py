"""The object as a rotating rigid body: rocking about one edge on a swinging palm. Mixed into
run.Run (RockingPhases); the pure functions are the physics (docs/physics.md, section 2.2).

When the line of the palm's force (or impulse) on the translating object leaves the supported
part of its base, the object turns about the end of that part: the pin. The pin is a point of
the palm's top (its edge, or where the object's base corner stands on it) and a point of the
object's base (its corner, or where the palm's edge bears on it); with the pin's friction
holding, neither moves against the other. Two coordinates then: the palm's angle th (clockwise
from the vertical) and the object's rotation phi (clockwise: + tips it forward).

Notation: the pin is `e` along the palm from its top centre and `d` along the object's base from
its centre (at phi = 0); rho(phi) = R(phi) (-d, h/2) is the centre of mass from the pin, with
R(phi) the clockwise rotation; a(phi) = d rho / d phi = R(phi) (h/2, d). The palm's felt mass
along the swing is `felt` (M, or M + J on real links), the mass whose weight turns it `weight`
(M, or M + W), its pivots' Coulomb torque `torque` and damping `damping`.

    T = (felt l^2 th'^2 + m |l th' t + phi' a|^2 + I_c phi'^2) / 2,
    V = weight g l cos th + m g (l cos th + rho_y)
gives M(q) q'' = Q - C with
    M11 = (felt + m) l^2,  M12 = m l (a . t),  M22 = I_c + m |rho|^2 = I_P  (t = (cos th, -sin th))
    Q_th = (weight + m) g l sin th - torque sgn th' - damping th',   Q_phi = -m g a_y
    C_th = -m l (rho . t) phi'^2,   C_phi = -m l (a . r) th'^2        (r = (sin th, cos th))
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from . import phases as ph
from .geometry import support_words

START_ATOLS = 100.0  # rocking from rest on its edge starts at this many atol of edge speed


@dataclass(frozen=True)
class Rocker:
    """The object (mass m, inertia I_c about its centre, height h) pinned at `d` along its base
    and `e` along the top of a palm (pivot, link l) that is its `felt`/`weight` masses, pivot
    torque and damping; `edge`: the palm's edge bears on the object's base (the contact's
    normal turns with the object), else the object's corner stands on the palm's face."""

    m: float
    inertia: float
    d: float
    h: float
    e: float
    felt: float
    weight: float
    torque: float
    damping: float
    gravity: float
    link_length: float
    pivot: tuple[float, float]
    edge: bool

    @property
    def about_pin(self) -> float:
        """I_P = I_c + m |rho|^2, the inertia about the pin."""
        return self.inertia + self.m * (self.d * self.d + 0.25 * self.h * self.h)


def lever(phi, d, h):
    """rho = R(phi) (-d, h/2): the centre of mass from the pin."""
    c, s = math.cos(phi), math.sin(phi)
    return -d * c + 0.5 * h * s, d * s + 0.5 * h * c


def lever_rate(phi, d, h):
    """a = d rho / d phi = R(phi) (h/2, d)."""
    c, s = math.cos(phi), math.sin(phi)
    return d * s + 0.5 * h * c, d * c - 0.5 * h * s


def rotate(phi, x, y):
    """R(phi) (x, y): the clockwise rotation by phi."""
    c, s = math.cos(phi), math.sin(phi)
    return x * c + y * s, -x * s + y * c


def mass_matrix(theta, phi, r: Rocker):
    ax, ay = lever_rate(phi, r.d, r.h)
    l = r.link_length
    m12 = r.m * l * (ax * math.cos(theta) - ay * math.sin(theta))
    return (r.felt + r.m) * l * l, m12, r.about_pin


def accelerations(theta, omega, phi, phid, r: Rocker, *, direction=1.0, held=False):
    """(th'', phi'') of the pinned object on its palm (the module docstring's equations);
    held: the palm is held by a stop (th' = th'' = 0): the inverted pendulum about a fixed pin.
    direction: the sign of th' the Coulomb torque opposes."""
    m, l, g = r.m, r.link_length, r.gravity
    ax, ay = lever_rate(phi, r.d, r.h)
    q_phi = -m * g * ay
    if held:
        return 0.0, q_phi / r.about_pin
    sn, cs = math.sin(theta), math.cos(theta)
    rx, ry = lever(phi, r.d, r.h)
    m11, m12, m22 = mass_matrix(theta, phi, r)
    q_th = (r.weight + m) * g * l * sn - r.torque * direction - r.damping * omega
    b1 = q_th + m * l * (rx * cs - ry * sn) * phid * phid
    b2 = q_phi + m * l * (ax * sn + ay * cs) * omega * omega
    det = m11 * m22 - m12 * m12
    return (b1 * m22 - m12 * b2) / det, (m11 * b2 - m12 * b1) / det


def pin_force(theta, omega, phi, phid, thdd, phidd, r: Rocker):
    """(tangential, normal) force of the palm on the object at the pin, F = m (r'' + g y):
    along the palm's face (normal y) where the object's corner stands on it, along the object's
    base (normal R(phi) y) where the palm's edge bears on the base."""
    l, m = r.link_length, r.m
    sn, cs = math.sin(theta), math.cos(theta)
    rx, ry = lever(phi, r.d, r.h)
    ax, ay = lever_rate(phi, r.d, r.h)
    fx = m * (l * thdd * cs - l * omega * omega * sn + phidd * ax - phid * phid * rx)
    fy = m * (-l * thdd * sn - l * omega * omega * cs + phidd * ay - phid * phid * ry + r.gravity)
    nx, ny = (math.sin(phi), math.cos(phi)) if r.edge else (0.0, 1.0)
    return fx * ny - fy * nx, fx * nx + fy * ny


def centre_velocity(theta, omega, phi, phid, r: Rocker):
    """Velocity of the object's centre of mass: l th' t + phi' a."""
    ax, ay = lever_rate(phi, r.d, r.h)
    l = r.link_length
    return (l * omega * math.cos(theta) + phid * ax, -l * omega * math.sin(theta) + phid * ay)


def pin_point(theta, r: Rocker):
    px, py = r.pivot
    l = r.link_length
    return px + l * math.sin(theta) + r.e, py + l * math.cos(theta)


def body_point(theta, phi, bx, by, r: Rocker):
    """Where the object's point (bx, by) (from its base centre at phi = 0) is."""
    x, y = pin_point(theta, r)
    dx, dy = rotate(phi, bx - r.d, by)
    return x + dx, y + dy


def impact_onto_pin(vx, vy, spin, theta, omega, phi, r: Rocker, hold=None):
    """Plastic impact that makes the pin of `r` the object's one contact (a corner coming down,
    or the impulse of a landing leaving the supported base). The impulse acts at the pin only,
    the links take radial impulse, so the generalized momenta of (th, phi) about the new pin
    are kept: M(q) q'+ = (felt l^2 th' + m v . l t, m v . a + I_c spin) with v, spin the
    object's centre velocity and clockwise spin before, th' the palm's. On a fixed palm
    (felt -> inf) this is the angular momentum about the new contact. hold: "back" / "front"
    when the palm rests on that stop (it holds the palm when the impulse drives it into it:
    th'+ = 0). Returns (th'+, phi'+, held, (Px, Py)) with P the impulse on the object."""
    l, m = r.link_length, r.m
    sn, cs = math.sin(theta), math.cos(theta)
    ax, ay = lever_rate(phi, r.d, r.h)
    p_th = r.felt * l * l * omega + m * l * (vx * cs - vy * sn)
    p_phi = m * (vx * ax + vy * ay) + r.inertia * spin
    m11, m12, m22 = mass_matrix(theta, phi, r)
    det = m11 * m22 - m12 * m12
    th1, phi1 = (p_th * m22 - m12 * p_phi) / det, (m11 * p_phi - m12 * p_th) / det
    held = (hold == "back" and th1 < 0.0) or (hold == "front" and th1 > 0.0)
    if held:
        th1, phi1 = 0.0, p_phi / m22
    ux, uy = centre_velocity(theta, th1, phi, phi1, r)
    return th1, phi1, held, (m * (ux - vx), m * (uy - vy))


def settle_speed(vx, vy, theta, omega, r: Rocker):
    """Palm speed l th'+ after the object comes down flat on it (plastic, the whole base in
    contact: no rotation after): (felt + m) l^2 th'+ = felt l^2 th' + m v . l t."""
    l = r.link_length
    p = r.felt * l * omega + r.m * (vx * math.cos(theta) - vy * math.sin(theta))
    return p / (r.felt + r.m)


def fixed_edge_speed_squared(phi, phi0, phid0, r: Rocker):
    """phi'^2 about a fixed pin (palm held): the energy integral of the inverted pendulum,
    I_P phi'^2 / 2 + m g rho_y(phi) = const."""
    return phid0 * phid0 + 2.0 * r.m * r.gravity * (
        lever(phi0, r.d, r.h)[1] - lever(phi, r.d, r.h)[1]) / r.about_pin


def tips_over_on_fixed_edge(phi, phid, r: Rocker) -> bool:
    """Whether an object rocking at (phi, phi') about a fixed pin can no longer come back: its
    centre reaches the pin's vertical (rho_y = |rho|, the top of the potential) with phi' still
    turning it outward. Past the vertical gravity's moment about the pin turns it further at every
    angle up to pi/2, where it leaves its edge."""
    side = math.copysign(1.0, phid) if phid != 0.0 else (1.0 if r.d > 0.0 else -1.0)
    rx, ry = lever(phi, r.d, r.h)
    if side * rx >= 0.0:  # past the vertical, outward
        return True
    top = math.hypot(r.d, 0.5 * r.h)
    energy = 0.5 * r.about_pin * phid * phid + r.m * r.gravity * ry
    return side * phid > 0.0 and energy >= r.m * r.gravity * top


class RockingPhases:
    """The rocking object (expects the attributes and helpers of Run and OdePhases)."""

    def _rocker(self, k, s, d):
        """Rocker of the object at offset s on palm k, pinned at d along its base."""
        w, h, m = self.row.body_width, self.h, self.m
        if self.plain:
            felt = weight = self.Ms[k]
            torque = damping = 0.0
        else:
            sw = self.swings_alone[k]
            felt, weight, torque, damping = sw.inertia, sw.weight, sw.torque, sw.damping
        edge = abs(d) < 0.5 * w * (1.0 - 1e-12)  # the palm's end lies inside the base
        return Rocker(m, m * (w * w + h * h) / 12.0, d, h, s + d, felt, weight, torque,
                      damping, self.g, self.ls[k], self.row.pivots[k], edge)

    def _rock_state(self, k, z, r: Rocker):
        """The event state: the object's bottom centre and velocity, its rotation and spin."""
        theta, omega, phi, phid = (float(v) for v in z)
        x, y = body_point(theta, phi, 0.0, 0.0, r)
        cx, cy = centre_velocity(theta, omega, phi, phid, r)
        bx, by = rotate(phi, 0.0, -0.5 * r.h)  # bottom centre from the centre of mass
        return {"x": x, "y": y, "vx": cx + phid * by, "vy": cy - phid * bx, "theta": theta,
                "omega": omega, "offset": r.e - r.d, "phi": phi, "spin": phid}

    def _rock_landing(self, t, j, theta, w, vx, vy, offset, point, before, held_at, rec):
        """A landing (or handover) whose impulse line meets the base at `point`, outside the
        supported base: a plastic impact about the support's end beyond which it passes, the
        object turning about it from then on."""
        lo, hi = self.row.support(offset)
        d = hi if point > hi else lo
        r = self._rocker(j, offset, d)
        th1, phi1, held, (px, py) = impact_onto_pin(vx, vy, 0.0, theta, w / r.link_length, 0.0,
                                                    r, held_at)
        side = 1.0 if point > hi else -1.0
        if side * phi1 > 0.0 and py > 0.0 and abs(px) > self.mu * py:  # (edgeslide.py)
            return self._slide_landing(t, j, theta, w, (vx, vy), r, held_at, side, before, rec)
        if side * phi1 <= 0.0 or py <= 0.0:
            return None  # (no rocking landing: the impulse does not lift the base)
        state = self._rock_state(j, (theta, th1, 0.0, phi1), r)
        if rec is not None:
            rec["landing_speed"] = r.link_length * th1
        self._log(t, "rock", j + 1, before, state,
                  f"the impulse {support_words(point, (lo, hi))}: the object turns about the "
                  f"{'palm' if r.edge else 'base'}'s {'front' if side > 0 else 'rear'} edge at "
                  f"{phi1:+.4g} rad/s")
        if held:
            self.rest_angle[j], self.rest_since[j] = theta, t
        else:
            self.rest_since[j] = math.inf
        return lambda: self._rock(t, j, offset, d, (theta, th1, 0.0, phi1), held)

    def _rock_onset(self, t, k, theta, omega, s, point, support, state):
        """The carry's force line reaches the end of the supported base: the object starts to
        turn about that end, from rest on it."""
        lo, hi = support
        d = hi if point > hi or (point >= 0.5 * (lo + hi)) else lo
        side = 1.0 if d == hi else -1.0
        r = self._rocker(k, s, d)
        phid = side * START_ATOLS * self.acc.atol / self.h
        self._log(t, "rock", k + 1, state, state,
                  f"the contact force {support_words(point, support)}: the object turns about "
                  f"the {'palm' if r.edge else 'base'}'s {'front' if side > 0 else 'rear'} edge")
        return lambda: self._rock(t, k, s, d, (theta, omega, 0.0, phid), False)

    def _rock(self, t0, k, s, d, z0, held, way=None, side=None):
        """The object turning about its pin on palm k (offset s, pin d along its base), state
        z = (th, th', phi, phi'); held: palm k rests on a stop. Guards (positive while the phase
        holds): phi back to 0 (`settle`), phi at pi/2 (about a corner its side face comes
        down, `roll`; on a palm's edge `tipped_over`), the pin's normal force (it leaves the
        palm, tumbling.py) and friction cone (it slides on the pin, edgeslide.py), the palm's
        stops, a held palm dragged off its stop, beta on the last palm; contacts with the
        palms at rest (tumbling._pinned_guards, _meets). side: the way the base is lifted
        (+1: its part behind the pin, phi > 0), by default that of phi' (else phi)."""
        r = self._rocker(k, s, d)
        if side is None:
            side = 1.0 if z0[3] > 0.0 or (z0[3] == 0.0 and z0[2] > 0.0) else -1.0
        theta0, omega0 = z0[0], z0[1]
        if way is None:  # the sign of th' the pivots' Coulomb torque opposes
            way = 1.0 if omega0 >= 0.0 else -1.0
        at_back = held and theta0 <= -self.alphas[k]

        def acc(z):
            return accelerations(z[0], z[1], z[2], z[3], r, direction=way, held=held)

        def rhs(t, z):
            thdd, phidd = acc(z)
            return [z[1], thdd, z[3], phidd]

        def force(z):
            return pin_force(z[0], z[1], z[2], z[3], *acc(z), r)

        mu = self.mu
        physics = [(lambda t, z: side * z[2], "settle"),
                   (lambda t, z: 0.5 * math.pi - side * z[2], "tipped_over"),
                   (lambda t, z: force(z)[1], "lost"),
                   (lambda t, z: mu * force(z)[1] - abs(force(z)[0]), "slides")]
        if held:
            drag = 1.0 if at_back else -1.0  # the way the palm would leave its stop

            def pull(z):
                return accelerations(z[0], 0.0, z[2], z[3], r, direction=drag)[0]

            physics.append((lambda t, z: -drag * pull(z), "release"))
        else:
            physics += [(lambda t, z: z[0] + self.alphas[k], "back_stop"),
                        (lambda t, z: self.fs - z[0], "front_stop")]
            if not self.plain:
                physics.append((lambda t, z: way * z[1], "turn"))
            if k == self.n - 1 and theta0 < self.beta:
                physics.append((lambda t, z: self.beta - z[0], "complete"))
        faces = self._pinned_guards(
            t0, k, lambda z: (*body_point(z[0], z[2], 0.0, 0.5 * r.h, r), z[2]))
        t_split = self._next_arrival(t0, k)
        te, z, kind, sol = self._integrate(rhs, t0, list(z0), physics, faces,
                                           max_step=0.05 * math.sqrt(self.h / self.g),
                                           t_end=t_split)
        z = [float(v) for v in z]
        if self.record and sol is not None:
            for t in np.linspace(t0, te, 40):
                st = self._rock_state(k, sol.sol(t), r)
                self._rec(t, st["x"], st["y"], st["vx"], st["vy"], st["theta"], k + 1)
        state = self._rock_state(k, z, r)
        if kind is None and t_split is not None and te >= t_split:
            return lambda: self._rock(te, k, s, d, z, held, side=side)
        if kind == "turn":  # the palm stops: it moves on the way its acceleration takes it
            z[1] = 0.0
            ahead = accelerations(z[0], 0.0, z[2], z[3], r, direction=1.0)[0]
            back = accelerations(z[0], 0.0, z[2], z[3], r, direction=-1.0)[0]
            if ahead <= 0.0 <= back:
                return self._fail(te, "stall", k + 1, state,
                                  f"palm {k + 1} stops where its pivot friction holds it, the "
                                  "object rocking on it (not followed)")
            return lambda: self._rock(te, k, s, d, z, held, 1.0 if ahead > 0.0 else -1.0,
                                      side=side)
        if kind == "release":
            self.rest_since[k] = math.inf
            self._log(te, "release", k + 1, state, state,
                      f"the rocking object drags palm {k + 1} off its stop")
            return lambda: self._rock(te, k, s, d, z, False, side=side)
        if kind in ("back_stop", "front_stop"):
            return self._rock_stop(te, k, s, d, z, r, kind, state, side)
        if kind == "settle":
            return self._rock_settle(te, k, s, d, z, r, held, state)
        if isinstance(kind, tuple):
            return self._rock_catch(te, k, z, r, kind, state)
        if kind == "complete":
            return self._complete(te, k, z[0], z[1], s)
        if kind == "lost":  # the object flies off its pin, tumbling (tumbling.py)
            return self._leave_edge(te, k, z, r, state)
        if kind == "slides":  # the pin slides (edgeslide.py)
            return self._slide_onset(te, k, z, r, held, side, way, state)
        if kind == "tipped_over" and not r.edge:  # its side face comes down (edgeslide.py)
            body = (centre_velocity(*z, r), body_point(z[0], z[2], 0.0, 0.5 * r.h, r), z[3])
            return self._roll_over(te, k, z[0], z[1], body, r.e, side, held, state)
        return self._rock_fail(te, k, kind, z, r, state)

    def _rock_fail(self, t, k, kind, z, r, state):
        """The rocking ends where the model stops: at pi/2 on a palm's edge (its base stands
        against the edge, `tipped_over`), or no event in the phase's time."""
        if kind is None:
            return self._fail(t, "timeout", k + 1, state, f"rocking on palm {k + 1}: no event")
        return self._fail(t, "tipped_over", k + 1, state,
                          f"the object turned to pi/2 on palm {k + 1}'s edge: its base stands "
                          "against the edge (not followed)")

    def _rock_stop(self, t, k, s, d, z, r, kind, state, side=None):
        """Palm k reaches a stop while the object rocks on it: the stop takes a generalized
        impulse along th only, so p_phi = M12 th' + M22 phi' is kept and th'+ = 0."""
        _, m12, m22 = mass_matrix(z[0], z[2], r)
        stop = -self.alphas[k] if kind == "back_stop" else self.fs
        phid = (m12 * z[1] + m22 * z[3]) / m22
        after = [stop, 0.0, z[2], phid]
        self.rest_angle[k], self.rest_since[k] = stop, t
        self._log(t, kind, k + 1, state, self._rock_state(k, after, r),
                  f"palm {k + 1} stopped with the object rocking on it")
        return lambda: self._rock(t, k, s, d, after, True, side=side)

    def _rock_settle(self, t, k, s, d, z, r, held, state):
        """The base comes back down onto palm k: a plastic impact at the other end of the
        supported base. If turning about that end lifts the first one, the object rocks about
        it; else it lies flat and the carry goes on."""
        theta, omega, _, phid = z
        lo, hi = self.row.support(s)
        at_hi = abs(d - hi) <= abs(d - lo)
        other = lo if at_hi else hi
        vx, vy = centre_velocity(theta, omega, 0.0, phid, r)
        hold = None
        if held:
            hold = "back" if theta <= -self.alphas[k] else "front"
        r2 = self._rocker(k, s, other)
        th1, phi1, held2, _ = impact_onto_pin(vx, vy, phid, theta, omega, 0.0, r2, hold)
        side = -1.0 if at_hi else 1.0
        if side * phi1 * max(self.h, self.row.body_width) > self.zeno_speed:
            self._log(t, "rock", k + 1, state, self._rock_state(k, (theta, th1, 0.0, phi1), r2),
                      f"comes down on the other end of its base: rocks about it at "
                      f"{phi1:+.4g} rad/s")
            return lambda: self._rock(t, k, s, other, (theta, th1, 0.0, phi1), held2)
        speed = 0.0 if held else settle_speed(vx, vy, theta, omega, r)
        if hold == "back" and speed < 0.0 or hold == "front" and speed > 0.0:
            speed = 0.0
        after = self._on_palm(k, theta, speed / r.link_length, s)
        self._log(t, "settle", k + 1, state, after, "the object settles flat on its palm")
        if held or speed == 0.0:
            if speed == 0.0 and not held:
                self.rest_angle[k], self.rest_since[k] = theta, t
            return self._held_slide(t, k, theta, s, 0.0, after)
        if speed < 0.0:
            return self._fail(t, "stall", k + 1, after,
                              f"the object settles on palm {k + 1} swinging backwards")
        if self.plain:
            return lambda: self._stuck(t, k, theta, speed, s)
        return lambda: self._stuck_integrated(t, k, theta, speed / r.link_length, s)

    def _rock_catch(self, t, k, z, r, kind, state):
        """The rocking object meets palm j (kind: a base corner on a face of palm j's slab, or a
        corner of palm j on a face of the object): _meets."""
        theta, omega, phi, phid = z
        v = centre_velocity(theta, omega, phi, phid, r)
        ox, oy = body_point(theta, phi, r.d, 0.0, r)
        normal = (math.sin(phi), math.cos(phi)) if r.edge else (0.0, 1.0)
        centre = body_point(theta, phi, 0.0, 0.5 * r.h, r)
        return self._meets(t, k, kind, (phi, v, phid, centre),
                           ((ox, oy), normal, (theta, omega), r.edge), state)

    def _meets(self, t, k, kind, body, old, state):
        """The rocking (or edge-sliding) object on palm k meets palm j: its base corner bx on
        palm j's top, or palm j's top corner on its base, is a catch (_catch); any other contact
        is not followed (`blocked`). body: phi, the centre's velocity, the spin and the centre;
        old: its contact on palm k (point, normal, palm k's (th, th'), whether palm k's edge
        bears on the base)."""
        phi, v, phid, centre = body
        if kind[0] == "palm_corner":  # (palm j's corner at (x, y), on the object's `face`)
            _, j, face, x, y = kind
            top_x, top_y = self.row.palm_top(j, self.rest_angle[j])
            if face != "base" or y < top_y - 0.5 * self.row.palm_thickness:  # (its underside)
                why = f"the rocking object hits a corner of palm {j + 1}"
                return (self._stepped(t, (*centre, *v, phi, phid), {k: old[2]}, state, why)
                        or self._fail(t, "blocked", k + 1, state, why))
            from .tumbling import world_to_body  # (tumbling imports this module)

            d, _ = world_to_body(*centre, phi, x, top_y, self.h)
            return self._catch(t, k, j, d, (x, phi, v, phid, centre), old, state,
                               edge=x - top_x)
        face, j, bx = kind
        if face != "top":
            why = f"the rocking object hits the side of palm {j + 1}"
            return (self._stepped(t, (*centre, *v, phi, phid), {k: old[2]}, state, why)
                    or self._fail(t, "blocked", k + 1, state, why))
        corner_x = centre[0] + rotate(phi, bx, -0.5 * self.h)[0]
        return self._catch(t, k, j, bx, (corner_x, phi, v, phid, centre), old, state)

    def _catch(self, t, k, j, bx, body, old, state, edge=None):
        """The object's base point bx comes down on palm j's top (palm j at rest on its stop):
        its corner on palm j's face, or its base on palm j's edge `edge` along the palm (then
        its side is that edge's: the rest of the object must be above palm j, side phi > 0).
        A plastic impact about that point (sticking, or sliding where the sticking impulse
        leaves the friction cone: edgeslide.slide_impact), palm k released; the object rocks
        (or rocks and slides) about it on palm j. body: the point's x, phi, the centre's
        velocity, the spin and the centre; old: the contact on palm k (point, its normal, palm
        k's (th, th'), edge), which lets go if its normal speed relative to palm k is outward
        after the impact; else both contacts take an impulse (twocontact.py)."""
        corner_x, phi, v, phid, centre = body
        swinging = self._swinging_from_rest(t, j)
        if swinging is not None:  # (it may meet that palm in the stepper's time)
            stepped = self._stepped(t, (*centre, *v, phi, phid), {k: old[2]}, state,
                                    f"the object reaches palm {j + 1} while palm {swinging}, "
                                    f"{self._swing_origin(swinging - 1)}, still swings")
            if stepped is not None:
                return stepped
        theta_j = self.rest_angle[j]
        top_x, _ = self.row.palm_top(j, theta_j)
        s_j = corner_x - top_x - bx
        r2 = self._rocker(j, s_j, bx)
        side = math.copysign(1.0, bx if edge is None else edge)
        if edge is not None:
            r2 = replace(r2, edge=True)
            if side * phi <= 0.0:
                why = (f"the rocking object comes down on the edge of palm {j + 1} turned the "
                       "way that brings its base onto palm j's top (two contacts)")
                return (self._stepped(t, (*centre, *v, phi, phid), {k: old[2]}, state, why)
                        or self._fail(t, "tip", k + 1, state, why + " (not followed)"))
        hold = "back" if theta_j <= -self.alphas[j] else "front" if theta_j >= self.fs else None
        th1, phi1, held, (px, py) = impact_onto_pin(*v, phid, theta_j, 0.0, phi, r2, hold)
        if r2.edge:  # the impulse along the object's base and its normal
            px, py = (px * math.cos(phi) - py * math.sin(phi),
                      px * math.sin(phi) + py * math.cos(phi))
        z, slip = (theta_j, th1, phi, phi1), None
        if py <= 0.0 or abs(px) > self.mu * py:
            slid = self._tumble_slide_impact((*centre, *v, phi, phid), j, theta_j, 0.0, phi, r2,
                                             hold)
            if slid is None:
                why = (f"the rocking object comes down on palm {j + 1}: no consistent sliding "
                       "impact")
                return (self._stepped(t, (*centre, *v, phi, phid), {k: old[2]}, state, why)
                        or self._fail(t, "tip", k + 1, state, why + " (not followed)"))
            z, held, slip = slid
            from .edgeslide import slide_centre_velocity  # (edgeslide imports this module)

            u = slide_centre_velocity(z, r2.d, r2, corner=not r2.edge)
        else:
            u = centre_velocity(theta_j, th1, phi, phi1, r2)
        (ox, oy), (nx, ny), (theta, omega) = old[:3]
        l = self.ls[k]
        away = ((u[0] + z[3] * (oy - centre[1]) - l * omega * math.cos(theta)) * nx
                + (u[1] - z[3] * (ox - centre[0]) + l * omega * math.sin(theta)) * ny)
        if away < 0.0:  # the old contact takes an impulse too (twocontact.py)
            return self._two_contact_catch(t, k, j, r2, (centre, v, phi, phid, hold), old,
                                           state, side)
        return self._caught(t, k, j, r2, z, held, slip, state, side)

    def _caught(self, t, k, j, r2, z, held, slip, state, side, release=None, note=""):
        """Bookkeeping of the catch of _catch: palm k hands the object over to palm j;
        release: palm k's th' after the catch (default its th' before), note: added to the
        event's text."""
        swinging = self._swinging_from_rest(t, j)
        if swinging is not None:
            return self._fail(t, "swinging_palm", j + 1, state,
                              f"the object reaches palm {j + 1} while palm {swinging}, "
                              f"{self._swing_origin(swinging - 1)}, still swings")
        if self._comes_onto(j):
            return self._fail(t, "skipped_palm", self.at + 2, state,
                              f"the object flew over palm {self.at + 2} and came onto palm "
                              f"{j + 1}")
        theta, omega = state["theta"], state["omega"] if release is None else release
        l = self.ls[k]
        rec = self._stage(k)
        if rec is not None:
            rec.update(handover_time=t, handover_speed=math.hypot(state["vx"], state["vy"]),
                       handover_angle=theta, handover_vx=state["vx"], handover_vy=state["vy"],
                       release_speed=l * omega)
        self._release(k, t, theta, l * omega)
        after = (self._rock_state(j, z, r2) if slip is None
                 else self._slide_state(j, z, r2.d, r2, not r2.edge))
        imp = ph.Impact(after["vx"], after["vy"], r2.link_length * z[1], 0.0, 0.0, True)
        self._new_stage(j, t, r2.e - r2.d, state["vx"], state["vy"], imp)
        self._log(t, "catch", k + 1, state, dict(after, palm=j + 1),
                  f"palm {k + 1} -> palm {j + 1}: the rocking object's "
                  + (f"base comes down on palm {j + 1}'s {'front' if side > 0 else 'rear'} edge"
                     if r2.edge else
                     f"{'front' if side > 0 else 'rear'} corner comes down on palm {j + 1}")
                  + ("" if slip is None else ", sliding") + note)
        self.rest_since[j] = t if held else math.inf
        if slip is not None:
            way = 1.0 if z[1] >= 0.0 else -1.0
            return lambda: self._edge_slide(t, j, r2, list(z), held, side, slip, way)
        return lambda: self._rock(t, j, r2.e - r2.d, r2.d, z, held, side=side)

    @staticmethod
    def _point_speed(after, phid, r, theta, phi, px, py):
        """Velocity of the object's point at (px, py) after an impact about r's pin."""
        ux, uy = centre_velocity(theta, after["omega"], phi, phid, r)
        x, y = body_point(theta, phi, 0.0, 0.5 * r.h, r)  # the centre of mass
        return ux + phid * (py - y), uy - phid * (px - x)
