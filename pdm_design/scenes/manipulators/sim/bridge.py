"""The object resting across two palms, each contact stuck or sliding. Mixed into run.Run
(docs/physics.md, section 2.2d).

After a plastic impact at both contacts (twocontact.py) the object bears on palm j (the new
contact) and palm k (the old). A stuck contact keeps the object's point b_i (its frame, from its
centre) on palm i's point e_i (along the top, from its centre); a sliding one keeps only the
normal gap closed (the object's corner on the palm's face, or the palm's edge along the
object's base), its force N (n - mu sgn(slip) t). Coordinates q = (X, Y, phi, th_j, th_k),
M = diag(m, m, I_c, F_j l_j^2, F_k l_k^2), forces lambda_i on the object entering as
J_i^T lambda_i (twocontact.contact_jacobian):

    M q'' = Q + J_j^T lambda_j + J_k^T lambda_k
    stuck:   J_i q'' = phi'^2 r_i - l_i th_i'^2 r_hat_i      (r_i = R(phi) b_i)
    sliding: n . J_i q'' = the same along n (a corner), or, a palm's edge on the base,
             -l th'^2 r_hat . n_b - 2 phi' (v_c - l th' t) . tau_b - phi'^2 r . n_b

each with a Baumgarte term -(2 g' + g / tau) / tau against drift, tau = 0.01 sqrt(h / g); a palm
held by a stop drops its coordinate. Guards: a normal force through zero (it opens: the object
rocks about the other contact, rocking.py, or rocks and slides on it, edgeslide.py), a stuck
force leaving its cone (`slip`), a slip stopping (`stick`), a sliding contact running off the
palm's or base's end (it opens), a held palm dragged off its stop; time stepped (stepped.py):
any other palm met, or either palm met away from the two contacts; not followed: a free palm
reaching a stop (`tip`). At rest across both: `stranded`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .edgeslide import ROUNDING
from .ode import SLIP_START_ATOLS
from .rocking import rotate
from .twocontact import contact_jacobian

REST_ATOLS = 1e4  # speeds below this many atol (times l for rates) at a segment's end: rest


@dataclass(frozen=True)
class Bridge:
    """The two stuck contacts: palms (j, k), the object's points b (its frame, from its centre),
    the palms' points e (along the top, from its centre), whether each is a palm's edge on the
    object's base (its normal turns with the object), and which palms their stops hold."""

    palms: tuple[int, int]
    b: tuple[tuple[float, float], tuple[float, float]]
    e: tuple[float, float]
    edge: tuple[bool, bool]
    held: tuple[bool, bool]
    modes: tuple = ("stick", "stick")


def contact_geometry(q, qd, contact, mode, h):
    """(r, jac, bias, gap, n): the object's point r (from its centre) at a contact, J_i there,
    and the constraint rows: stuck, J_i q'' = bias - .. with the gap the two points' offset;
    sliding, n.J_i q'' = bias with the normal gap. contact: (b, e, l, pivot, edge)."""
    b, e, l, pivot, edge = contact
    theta, omega, phi, w = q[3], qd[3], q[2], qd[2]
    palm = (pivot[0] + l * math.sin(theta) + e, pivot[1] + l * math.cos(theta))
    n = np.array([math.sin(phi), math.cos(phi)]) if edge else np.array([0.0, 1.0])
    radial = l * omega * omega * np.array([math.sin(theta), math.cos(theta)])
    if mode != "stick" and edge:  # the palm's edge e slides along the object's base
        r = np.array([palm[0] - q[0], palm[1] - q[1]])
        base = np.array(rotate(phi, (r @ np.array([n[1], -n[0]])), -0.5 * h))
        jac = contact_jacobian(r, l, theta, 3)
        slip = np.array([qd[0], qd[1]]) - l * omega * np.array([math.cos(theta), -math.sin(theta)])
        tb = np.array([n[1], -n[0]])
        bias = -radial @ n - 2.0 * w * (slip @ tb) - w * w * (r @ n)
        return r, jac, bias, float((base - r) @ n), n
    r = np.array(rotate(phi, *b))
    jac = contact_jacobian(r, l, theta, 3)
    if mode != "stick":  # the object's corner b slides along the palm's face
        return r, jac, float(n @ (w * w * r - radial)), float(q[1] + r[1] - palm[1]), n
    gap = np.array([q[0] + r[0] - palm[0], q[1] + r[1] - palm[1]])
    return r, jac, w * w * r - radial, gap, n


def bridge_accelerations(y, masses, forces, geometry, tau, mu=0.0):
    """(q'', forces on the object at the two contacts, 4 values) of the object across two
    palms at y = (q, q'). masses: diag(M); forces: Q(y); geometry: per contact (b, e, l,
    pivot, edge) with its mode ("stick" or the slip's sign), and the held flags."""
    q, qd = np.asarray(y[:5], float), np.asarray(y[5:], float)
    contacts, modes, held, h = geometry
    cols, rows, rhs, dirs = [], [], [], []
    for i, (contact, mode) in enumerate(zip(contacts, modes)):
        sub = np.array([q[0], q[1], q[2], q[3 + i], 0.0])
        subd = np.array([qd[0], qd[1], qd[2], qd[3 + i], 0.0])
        _, jac3, bias, gap, n = contact_geometry(sub, subd, contact, mode, h)
        jac = np.zeros((2, 5))
        jac[:, :3], jac[:, 3 + i] = jac3[:, :3], jac3[:, 3]
        if mode == "stick":
            d = np.eye(2)
            rows.append(jac)
            rhs.append(bias - (2.0 * (jac @ qd) + gap / tau) / tau)
        else:
            d = (n - mu * mode * np.array([n[1], -n[0]]))[:, None]
            rows.append(n @ jac)
            rhs.append([bias - (2.0 * (n @ jac @ qd) + gap / tau) / tau])
        cols.append(jac.T @ d)
        dirs.append(d)
    free = [i for i in range(5) if i < 3 or not held[i - 3]]
    g, e = np.hstack(cols)[free], np.vstack([np.atleast_2d(r) for r in rows])[:, free]
    k = g.shape[1]
    kkt = np.block([[np.diag(np.asarray(masses)[free]), -g], [e, np.zeros((k, k))]])
    sol = np.linalg.solve(kkt, np.concatenate([np.asarray(forces)[free], np.concatenate(rhs)]))
    qdd = np.zeros(5)
    qdd[free] = sol[:len(free)]
    lam, out = sol[len(free):], []
    for d in dirs:
        out += list(d @ lam[:d.shape[1]])
        lam = lam[d.shape[1]:]
    return qdd, np.array(out)


def contact_parts(lam, phi, edge):
    """(normal, tangential) of a contact force on the object: normal y on a palm's face, the
    base's normal R(phi) y where a palm's edge bears on the base."""
    n = (math.sin(phi), math.cos(phi)) if edge else (0.0, 1.0)
    return lam[0] * n[0] + lam[1] * n[1], lam[0] * n[1] - lam[1] * n[0]


class BridgePhases:
    """The object stuck across two palms (expects Run, RockingPhases, TwoContactPhases)."""

    def _bridge_model(self, br: Bridge):
        """masses, forces(y) and geometry for bridge_accelerations."""
        sws = [self.swings_alone[p] for p in br.palms]
        masses = [self.m, self.m, self.m * (self.row.body_width ** 2 + self.h ** 2) / 12.0]
        masses += [sw.inertia * sw.link_length ** 2 for sw in sws]

        def forces(y):
            out = [0.0, -self.m * self.g, 0.0]
            for i, sw in enumerate(sws):
                theta, omega = y[3 + i], y[8 + i]
                out.append(sw.weight * sw.gravity * sw.link_length * math.sin(theta)
                           - sw.torque * math.copysign(1.0, omega) - sw.damping * omega)
            return out

        contacts = [(br.b[i], br.e[i], self.ls[p], self.row.pivots[p], br.edge[i])
                    for i, p in enumerate(br.palms)]
        return masses, forces, (contacts, br.modes, br.held, self.h)

    def _bridge(self, t0, br: Bridge, y0, sides):
        """The object across palms j and k from (t0, y0); sides: the way its base lifts in the
        rocking about each contact once the other opens."""
        masses, forces, geometry = self._bridge_model(br)
        tau = 0.01 * math.sqrt(self.h / self.g)
        j, k = br.palms
        rows = sum(2 if m == "stick" else 1 for m in br.modes)
        if rows > 3 + br.held.count(False):  # held palms: the forces are not determined
            return self._fail(t0, "tip", k + 1, self._bridge_state(y0, 1, br),
                              f"the object rests across palms {k + 1} and {j + 1}, both held "
                              "by their stops, stuck on both (not followed)")
        memo = {}

        def solved(y):
            key = tuple(y)
            if key not in memo:
                memo.clear()
                memo[key] = bridge_accelerations(y, masses, forces(y), geometry, tau, self.mu)
            return memo[key]

        def rhs(t, y):
            return list(y[5:]) + list(solved(y)[0])

        bad = self._slip_inconsistent(br, geometry, solved(y0), y0)
        if bad is not None:
            why = (f"the object across palms {k + 1} and {j + 1}: no consistent slide on palm "
                   f"{br.palms[bad] + 1}")
            state = self._bridge_state(y0, 1, br)
            return (self._bridge_stepped(t0, br, y0, state, why)
                    or self._fail(t0, "tip", k + 1, state, why + " (not followed)"))
        physics = self._bridge_guards(br, geometry, solved, forces, y0)
        for p in br.palms:  # neither is an obstacle while it bears the object
            self.rest_since[p] = math.inf
        faces = (self._pinned_guards(t0, k, lambda y: (y[0], y[1], y[2]))
                 + self._bridge_beyond_guards(br))
        te, y, kind, _ = self._integrate(rhs, t0, list(y0), physics, faces,
                                         max_step=0.05 * math.sqrt(self.h / self.g),
                                         t_end=t0 + math.sqrt(self.l / self.g))
        y = [float(v) for v in y]
        if kind is None:  # a segment with no event: at rest across both, or on
            if max(abs(v) for v in y[5:]) * self.l > REST_ATOLS * self.acc.atol:
                return lambda: self._bridge(te, br, y, sides)
            return self._fail(te, "stranded", k + 1, self._bridge_state(y, 1, br),
                              f"the object rests across palms {k + 1} and {j + 1}")
        return self._bridge_end(te, br, y, kind, sides)

    def _slip_inconsistent(self, br, geometry, solution, y):
        """A sliding contact starting from relative rest whose slip acceleration is against
        the slip assumed (beyond rounding): its index, else None."""
        qdd = solution[0]
        for i, mode in enumerate(br.modes):
            if mode == "stick":
                continue
            q = np.array([y[0], y[1], y[2], y[3 + i], 0.0])
            qd = np.array([y[5], y[6], y[7], y[8 + i], 0.0])
            acc = np.array([qdd[0], qdd[1], qdd[2], qdd[3 + i], 0.0])
            r, jac, _, _, n = contact_geometry(q, qd, geometry[0][i], "stick", self.h)
            t = np.array([n[1], -n[0]])
            if abs(t @ (jac @ qd)) > 2.0 * SLIP_START_ATOLS * self.acc.atol:
                continue
            l, theta = geometry[0][i][2], q[3]
            rel = jac @ acc - qd[2] ** 2 * r + l * qd[3] ** 2 * np.array([math.sin(theta),
                                                                           math.cos(theta)])
            if mode * (t @ rel) < -ROUNDING * self.g:
                return i
        return None

    def _bridge_contact_guards(self, br, geometry, solved, i):
        """A contact's guards: its normal force (it opens); stuck, its cone (it slips); sliding,
        its slip (it sticks) and its point on the palm's top and on the object's base."""
        mu, mode, contact = self.mu, br.modes[i], geometry[0][i]

        def parts(y):
            return contact_parts(solved(y)[1][2 * i:2 * i + 2], y[2], br.edge[i])

        out = [(lambda t, y: parts(y)[0], ("open", i))]
        if mode == "stick":
            return out + [(lambda t, y: mu * parts(y)[0] - abs(parts(y)[1]), ("slip", i))]

        def local(y):
            q = np.array([y[0], y[1], y[2], y[3 + i], 0.0])
            qd = np.array([y[5], y[6], y[7], y[8 + i], 0.0])
            r, jac, _, _, n = contact_geometry(q, qd, contact, mode, self.h)
            slip = float(np.array([n[1], -n[0]]) @ (jac @ qd))
            if br.edge[i]:  # the contact's place along the base
                along = float(r @ np.array([n[1], -n[0]]))
                return slip, 0.5 * self.row.body_width - abs(along)
            top = y[0] + r[0] - (contact[3][0] + contact[2] * math.sin(y[3 + i]))
            return slip, 0.5 * self.row.palm_width - abs(top)

        start = SLIP_START_ATOLS * self.acc.atol  # (a slip from rest starts at zero)
        return out + [(lambda t, y: mode * local(y)[0] + start, ("stick", i)),
                      (lambda t, y: local(y)[1], ("open", i))]

    def _bridge_beyond_guards(self, br):
        """Guards of the two palms' slabs meeting the object anywhere but at its contacts (an
        object's corner entering a slab, a slab's corner entering the object: the object's
        base coming down on palm j, its side on palm k's edge); kind ("beyond", palm)."""
        from .tumbling import CORNERS  # (tumbling imports the modules this one does)

        w, h = self.row.body_width, self.h
        faces = []
        for i, p in enumerate(br.palms):
            def slab(y, i=i, p=p):
                return self.row.slab(p, y[3 + i])
            if br.edge[i]:  # palm p's edge on the base
                skip = {("edge", math.copysign(1.0, br.e[i]), True)}
            else:  # the object's corner b on palm p's top
                skip = {("corner", n) for n, (fx, fy) in enumerate(CORNERS)
                        if math.dist((fx * w, (fy - 0.5) * h), br.b[i]) < 1e-6 * w}
            faces += [(f, d, v, ("beyond", p)) for f, d, v, _ in
                      self._contact_guards(p, slab, lambda y: (y[0], y[1], y[2]), skip)]
        return faces

    def _bridge_guards(self, br, geometry, solved, forces, y0):
        """Physics guards (positive while the object rests across both): the contacts', each
        free palm's stops (and its turning, on real links), each held palm pressed into its
        stop."""
        out = []
        for i, p in enumerate(br.palms):
            out += self._bridge_contact_guards(br, geometry, solved, i)
            if br.held[i]:
                into = -1.0 if self.rest_angle[p] <= -self.alphas[p] else 1.0

                def pressed(y, i=i, into=into):
                    q = np.array([y[0], y[1], y[2], y[3 + i], 0.0])
                    jac = contact_geometry(q, np.zeros(5), geometry[0][i], br.modes[i],
                                           self.h)[1]
                    push = (jac.T @ solved(y)[1][2 * i:2 * i + 2])[3]
                    return into * (forces(y)[3 + i] + push)

                out.append((lambda t, y, f=pressed: f(y), ("release", i)))
                continue
            out += [(lambda t, y, i=i, p=p: y[3 + i] + self.alphas[p], "stop"),
                    (lambda t, y, i=i: self.fs - y[3 + i], "stop")]
            if not self.plain:
                way = -1.0 if y0[8 + i] < 0.0 else 1.0
                out.append((lambda t, y, i=i, way=way: way * y[8 + i], "stop"))
        return out

    def _bridge_state(self, y, i, br):
        """The event state with palm i's (0: j, 1: k) angle and rate, the object as pinned at
        its contact there."""
        return self._rock_state(None, (y[3 + i], y[8 + i], y[2], y[7]), self._bridge_rocker(br, i))

    def _bridge_rocker(self, br, i):
        """rocking.Rocker of the object pinned at contact i as it is now."""
        from dataclasses import replace

        d = br.b[i][0]
        return replace(self._rocker(br.palms[i], br.e[i] - d, d), edge=br.edge[i])

    def _restick(self, br, y, i):
        """br with contact i stuck where it is now (a slide's point taken as the pin)."""
        p = br.palms[i]
        l, (px, py) = self.ls[p], self.row.pivots[p]
        top = (px + l * math.sin(y[3 + i]), py + l * math.cos(y[3 + i]))
        b, e = list(br.b), list(br.e)
        if br.edge[i]:  # the base's point now on the palm's edge
            bx, _ = rotate(-y[2], top[0] + e[i] - y[0], top[1] - y[1])
            b[i] = (bx, -0.5 * self.h)
        else:  # the palm's point now under the object's corner
            e[i] = y[0] + rotate(y[2], *b[i])[0] - top[0]
        modes = tuple("stick" if n == i else m for n, m in enumerate(br.modes))
        return Bridge(br.palms, tuple(b), tuple(e), br.edge, br.held, modes)

    def _bridge_end(self, t, br, y, kind, sides):
        """Where the linkage ends: a contact opens (the object rocks about the other), slips or
        sticks, a held palm leaves its stop (the phase goes on), or not followed."""
        j, k = br.palms
        state = self._bridge_state(y, 1, br)
        if isinstance(kind, tuple) and kind[0] in ("release", "slip", "stick"):
            i = kind[1]
            if kind[0] == "stick":
                nxt = self._restick(br, y, i)
            elif kind[0] == "slip":
                lam = self._bridge_forces(br, y)[2 * i:2 * i + 2]
                way = -math.copysign(1.0, contact_parts(lam, y[2], br.edge[i])[1])
                modes = tuple(way if n == i else m for n, m in enumerate(br.modes))
                nxt = Bridge(br.palms, br.b, br.e, br.edge, br.held, modes)
            else:
                held = tuple(h and n != i for n, h in enumerate(br.held))
                nxt = Bridge(br.palms, br.b, br.e, br.edge, held, br.modes)
            self._log(t, "release" if kind[0] == "release" else kind[0], br.palms[i] + 1,
                      state, state, f"the object across palms {k + 1} and {j + 1}: "
                      + {"release": f"drags palm {br.palms[i] + 1} off its stop",
                         "slip": f"starts to slide on palm {br.palms[i] + 1}",
                         "stick": f"sticks on palm {br.palms[i] + 1}"}[kind[0]])
            return lambda: self._bridge(t, nxt, y, sides)
        if isinstance(kind, tuple) and kind[0] == "open":
            return self._bridge_open(t, br, y, kind[1], sides, state)
        words = {"stop": "a palm reaches a stop or stops", None: "no event"}
        if kind in words:
            return self._fail(t, "tip" if kind else "timeout", k + 1, state,
                              f"the object resting across palms {k + 1} and {j + 1}: "
                              f"{words[kind]} (not followed)")
        why = (f"the object resting across palms {k + 1} and {j + 1} meets palm {kind[1] + 1}"
               + (" away from its contact" if kind[0] == "beyond" else ""))
        return self._bridge_stepped(t, br, y, state, why) or self._fail(t, "blocked", k + 1,
                                                                         state, why)

    def _bridge_stepped(self, t, br, y, state, why):
        """Time stepping (stepped.py) from the bridge's state y."""
        body = (y[0], y[1], y[5], y[6], y[2], y[7])
        moving = {p: (y[3 + i], y[8 + i]) for i, p in enumerate(br.palms)}
        return self._stepped(t, body, moving, state, why)

    def _bridge_forces(self, br, y):
        masses, forces, geometry = self._bridge_model(br)
        tau = 0.01 * math.sqrt(self.h / self.g)
        return bridge_accelerations(y, masses, forces(y), geometry, tau, self.mu)[1]

    def _bridge_open(self, t, br, y, i, sides, state):
        """Contact i opens: the object rocks on (or rocks and slides, edgeslide.py) about the
        other one. Palm k letting go is the handover onto palm j (rocking._caught); palm j
        letting go leaves it on palm k, palm j swinging on alone (or at rest on its stop)."""
        j, k = br.palms
        n = 1 - i  # the contact that stays
        r, z, slip = self._staying(br, y, n)
        if i == 1:
            return self._caught(t, k, j, r, z, br.held[0], slip, state, sides[0], release=y[9],
                                note=f" (after resting across palms {k + 1} and {j + 1})")
        if br.held[0]:
            self.rest_since[j] = t
        else:
            self._release(j, t, y[3], self.ls[j] * y[8])
        if br.held[1]:
            self.rest_since[k] = t
        self._log(t, "rock", k + 1, state, state,
                  f"the object lets go of palm {j + 1}: it rocks on palm {k + 1}")
        if slip is not None:
            way = 1.0 if z[1] >= 0.0 else -1.0
            return lambda: self._edge_slide(t, k, r, list(z), br.held[1], sides[1], slip, way)
        return lambda: self._rock(t, k, r.e - r.d, r.d, z, br.held[1], side=sides[1])

    def _staying(self, br, y, n):
        """The Rocker, state and slip of the contact n that stays: stuck, the rocking state
        (th, th', phi, phi') and None; sliding, edgeslide's (th, th', phi, phi', u, u') with u
        the corner's place along the palm (e) or the palm's edge's along the base (d), and
        the slip's sign."""
        zr = (y[3 + n], y[8 + n], y[2], y[7])
        if br.modes[n] == "stick":
            return self._bridge_rocker(br, n), zr, None
        contact = self._bridge_model(br)[2][0][n]
        q = np.array([y[0], y[1], y[2], y[3 + n], 0.0])
        qd = np.array([y[5], y[6], y[7], y[8 + n], 0.0])
        r, jac, _, _, nv = contact_geometry(q, qd, contact, br.modes[n], self.h)
        slip = float(np.array([nv[1], -nv[0]]) @ (jac @ qd))
        if br.edge[n]:  # u = d along the base, d' = -slip
            d = float(r @ np.array([nv[1], -nv[0]]))
            rocker = self._bridge_rocker(Bridge(br.palms, tuple(
                (d, -0.5 * self.h) if m == n else b for m, b in enumerate(br.b)), br.e,
                br.edge, br.held, br.modes), n)
            return rocker, (*zr, d, -slip), br.modes[n]
        nxt = self._restick(br, y, n)  # the corner's place e on the palm now
        return self._bridge_rocker(nxt, n), (*zr, nxt.e[n], slip), br.modes[n]
