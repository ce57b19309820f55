"""The rocking object coming down on a second palm while it still bears on its own: a plastic
impact at both contacts at once. Mixed into run.Run (docs/physics.md, section 2.2d).

Coordinates q = (X, Y, phi, th_j, th_k): the object's centre, its clockwise rotation, the angle
of palm j (the new contact, c = 0) and of palm k (the old contact, c = 1). Palms translate on
their links, so the generalized mass is diagonal, M = diag(m, m, I_c, F_j l_j^2, F_k l_k^2)
(F the palm's felt mass along its swing), and the relative velocity of the object's point at
r (from its centre) against palm i's top is g_i = J_i q' with

    J_i = [[1, 0,  r_y, -l_i cos th_i (col i)],
           [0, 1, -r_x,  l_i sin th_i (col i)]]     (object point minus palm point).

The impulse P_i on the object (-P_i on the palm) enters as J_i^T P_i (links, pivots, gravity:
no impulse). Plastic: the normal relative speeds after vanish at both contacts; a contact
sticks (g_i = 0) while its impulse lies in the friction cone, else it slides with
P_i = p_i (n_i - mu sgn(sigma_i) t_i), sigma_i its slip before (kept through the impact).
M (q'+ - q'-) = sum J_i^T P_i and the conditions are linear in the impulses: two_contact_impact.
Modes are tried stuck-stuck, stuck-sliding, sliding-stuck, sliding-sliding (solve_two_contacts).
A palm resting on a stop that its impulse drives into the stop is held (its column dropped).

After the impact the object rests across both palms (bridge.py) until one contact opens.
"""

from __future__ import annotations

import math

import numpy as np

from .rocking import rotate


def contact_jacobian(r, l, theta, column):
    """J_i (2 x 5) of the object's point r (from its centre) against the top of the palm whose
    angle is coordinate `column` (3: palm j, 4: palm k)."""
    jac = np.zeros((2, 5))
    jac[0, 0] = jac[1, 1] = 1.0
    jac[0, 2], jac[1, 2] = r[1], -r[0]
    jac[0, column], jac[1, column] = -l * math.cos(theta), l * math.sin(theta)
    return jac


def _directions(normal, mode, mu):
    """Impulse directions of a contact (columns): sticking (n, t), or sliding n - mu s t with
    s = mode (the slip's sign before, along t = (n_y, -n_x))."""
    n = np.asarray(normal, float)
    t = np.array([n[1], -n[0]])
    if mode == "stick":
        return np.column_stack([n, t]), np.vstack([n, t])
    return (n - mu * mode * t)[:, None], n[None, :]


def two_contact_impact(inv_mass, qd, jacobians, normals, modes, mu):
    """The plastic impact at two contacts: (q'+, impulses) with impulses[i] = (normal,
    tangential) on the object, or None where the linear system is singular. inv_mass: the
    diagonal of M^-1 (0 for a held palm); modes: per contact "stick" or the slip's sign."""
    columns, rows = [], []
    for jac, n, mode in zip(jacobians, normals, modes):
        d, e = _directions(n, mode, mu)
        columns.append(jac.T @ d)
        rows.append(e @ jac)
    g = np.hstack(columns)                      # generalized impulse per unknown
    e = np.vstack(rows)                         # the conditions on q'+
    a = e @ (inv_mass[:, None] * g)
    if abs(np.linalg.det(a)) < 1e-14 * max(1.0, np.abs(a).max() ** len(a)):
        return None
    lam = np.linalg.solve(a, -e @ qd)
    after = qd + inv_mass * (g @ lam)
    impulses, i = [], 0
    for n, mode in zip(normals, modes):
        n = np.asarray(n, float)
        t = np.array([n[1], -n[0]])
        if mode == "stick":
            p = lam[i] * n + lam[i + 1] * t
            i += 2
        else:
            p = lam[i] * (n - mu * mode * t)
            i += 1
        impulses.append((float(p @ n), float(p @ t)))
    return after, impulses


def admissible(after, impulses, jacobians, normals, modes, mu, tol=1e-12):
    """Coulomb and plasticity: every normal impulse pushes, a sticking one lies in the cone, a
    sliding contact's slip after has not reversed."""
    for (pn, pt), jac, n, mode in zip(impulses, jacobians, normals, modes):
        if pn <= 0.0:
            return False
        if mode == "stick":
            if abs(pt) > mu * pn * (1.0 + 1e-12):
                return False
        else:
            slip = float(np.array([n[1], -n[0]]) @ (jac @ after))
            if mode * slip < -tol:
                return False
    return True


def _slip_way(jac, normal, qd, stuck, i):
    """The way contact i slides through the impact: its slip before, or from relative rest
    the way its sticking impulse leaves the cone (against its tangential part)."""
    n = np.asarray(normal, float)
    slip = float(np.array([n[1], -n[0]]) @ (jac @ qd))
    if slip != 0.0:
        return math.copysign(1.0, slip)
    return None if stuck is None else -math.copysign(1.0, stuck[1][i][1])


def solve_two_contacts(inv_mass, qd, jacobians, normals, mu):
    """The consistent plastic impact at both contacts, each sticking or sliding the way it
    slipped before (or, from relative rest, the way its sticking impulse leaves the cone);
    sticking tried first. Returns (q'+, impulses, modes) or None."""
    stuck = two_contact_impact(inv_mass, qd, jacobians, normals, ("stick", "stick"), mu)
    ways = [_slip_way(jacobians[i], normals[i], qd, stuck, i) for i in range(2)]
    for modes in (("stick", "stick"), ("stick", ways[1]), (ways[0], "stick"), tuple(ways)):
        if None in modes:
            continue
        solved = two_contact_impact(inv_mass, qd, jacobians, normals, modes, mu)
        if solved is not None and admissible(*solved, jacobians, normals, modes, mu):
            return (*solved, modes)
    return None


def _impulse(normal, impulse):
    """The impulse vector from its (normal, tangential) parts, t = (n_y, -n_x)."""
    n = np.asarray(normal, float)
    return impulse[0] * n + impulse[1] * np.array([n[1], -n[0]])


class TwoContactPhases:
    """The catch that meets the old contact still closing (expects Run and RockingPhases)."""

    def _two_contact_catch(self, t, k, j, r2, pre, old, state, side):
        """The rocking object's point on palm j (r2: the rocking about it) comes down while its
        contact on palm k still closes. pre: (centre, its velocity, phi, phi', hold of palm j);
        old: (point, normal, (th_k, th_k'), edge). The impact at both contacts; stuck on both,
        the object rests across them (bridge.py); sliding on palm k, it rocks on palm j if
        that contact opens, else `tip`."""
        centre, v, phi, phid, hold_j = pre
        (ox, oy), normal_k, (theta_k, omega_k), edge_k = old
        theta_j = self.rest_angle[j]
        p1 = (r2.pivot[0] + r2.link_length * math.sin(theta_j) + r2.e,
              r2.pivot[1] + r2.link_length * math.cos(theta_j))
        normal_j = (math.sin(phi), math.cos(phi)) if r2.edge else (0.0, 1.0)
        l_k = self.ls[k]
        jacs = [contact_jacobian((p1[0] - centre[0], p1[1] - centre[1]), r2.link_length,
                                 theta_j, 3),
                contact_jacobian((ox - centre[0], oy - centre[1]), l_k, theta_k, 4)]
        qd = np.array([v[0], v[1], phid, 0.0, omega_k])
        hold_k = self._stop_hold(k, theta_k, omega_k)
        solved = self._solve_held(qd, jacs, (normal_j, normal_k), r2, k, (hold_j, hold_k))
        if solved is None:
            why = (f"the rocking object comes down on palm {j + 1} still bearing on palm "
                   f"{k + 1}: no consistent impact at both contacts")
            return (self._stepped(t, (*centre, *v, phi, phid), {k: (theta_k, omega_k)}, state,
                                  why)
                    or self._fail(t, "tip", k + 1, state, why + " (not followed)"))
        after, held_j, held_k, modes = solved
        return self._bridge_start(t, (k, j, r2, side), (centre, phi, theta_k), old, after,
                                  (held_j, held_k, modes), state)

    def _bridge_start(self, t, catch, pose, old, after, how, state):
        """After the impact at both contacts the object rests across palms k and j, followed
        (bridge.py) until one contact opens. catch: (k, j, the Rocker about the new contact,
        its side); pose: the centre, phi and palm k's angle; how: palm j held, palm k held,
        the contacts' modes."""
        from .bridge import Bridge  # (bridge imports this module)

        k, j, r2, side = catch
        centre, phi, theta_k = pose
        (ox, oy), _, _, edge_k = old
        e_k = ox - (self.row.pivots[k][0] + self.ls[k] * math.sin(theta_k))
        p1 = (r2.pivot[0] + r2.link_length * math.sin(self.rest_angle[j]) + r2.e,
              r2.pivot[1] + r2.link_length * math.cos(self.rest_angle[j]))
        b = tuple(rotate(-phi, x - centre[0], y - centre[1]) for x, y in (p1, (ox, oy)))
        side_k = math.copysign(1.0, e_k if edge_k else b[1][0])
        br = Bridge((j, k), b, (r2.e, e_k), (r2.edge, edge_k), how[:2], how[2])
        y0 = [centre[0], centre[1], phi, self.rest_angle[j], theta_k, *map(float, after)]
        self._log(t, "bridge", k + 1, state, self._bridge_state(y0, 1, br),
                  f"the rocking object comes down on palm {j + 1} still bearing on palm "
                  f"{k + 1}: it rests across both")
        return lambda: self._bridge(t, br, y0, (side, side_k))

    def _stop_hold(self, k, theta, omega):
        """"back" / "front" when palm k rests on that stop, else None."""
        if omega != 0.0:
            return None
        if theta <= -self.alphas[k]:
            return "back"
        return "front" if theta >= self.fs else None

    def _solve_held(self, qd, jacs, normals, r2, k, holds):
        """solve_two_contacts with the palms free, else held by the stops their contact
        impulses drive them into (a held palm's column dropped; its stop pushes back only if
        the contact drives it into the stop, a free palm must not be driven through its stop).
        Returns (q'+, held_j, held_k, modes) or None."""
        base = np.array([1.0 / r2.m, 1.0 / r2.m, 1.0 / r2.inertia,
                         1.0 / (r2.felt * r2.link_length ** 2),
                         1.0 / (self._felt(k) * self.ls[k] ** 2)])
        into = {"back": -1.0, "front": 1.0, None: 0.0}
        for held in ((False, False), (True, False), (False, True), (True, True)):
            if any(h and holds[i] is None for i, h in enumerate(held)):
                continue
            inv = base.copy()
            for i, h in enumerate(held):
                inv[3 + i] = 0.0 if h else inv[3 + i]
            solved = solve_two_contacts(inv, qd, jacs, normals, self.mu)
            if solved is None:
                continue
            after, impulses, modes = solved
            pushes = [float((jacs[i].T @ _impulse(normals[i], impulses[i]))[3 + i])
                      for i in range(2)]
            # a held palm's contact pushes it into its stop; a free one is not driven through
            if all(into[holds[i]] * pushes[i] > 0.0 if held[i] else
                   into[holds[i]] * after[3 + i] <= 0.0 for i in range(2)):
                return after, held[0], held[1], modes
        return None

    def _felt(self, k):
        return self.Ms[k] if self.plain else self.swings_alone[k].inertia
