"""The carried object sliding on its palm while it pushes the palm ahead. Mixed into run.Run.

The push of pushing.py keeps the object stuck on palm k; where palm k's force on it leaves the
friction cone, the object slides on palm k (Coulomb) with its face still on palm j's corner:
docs/physics.md section 2.2c. State (th_k, th_k', s, s', th_j, th_j'); five linear equations
(the object's two, the two swings', the constraint's second derivative) give the accelerations
and the two contact forces (slide_push_accelerations). It ends where palm j parts (the sliding
carry goes on), the slip stops (the stuck push goes on), or as the stuck push ends.
"""

from __future__ import annotations

import math

import numpy as np

from . import phases as ph
from .geometry import face_guards
from .pushing import push_end

SLIP_START_ATOLS = 100.0  # initial slip speed from relative rest, in units of atol (as ode.py)


def slide_push_accelerations(z, *, acc_k, acc_j, l_k, l_j, m, m_k, m_j, mu, sgn, sgn_s, g):
    """(th_k'', s'', th_j'', Nk, N) for z = (th_k, th_k', s, s', th_j, th_j'): the object (mass m)
    slides at s' on palm k (mass m_k along t_k alone; friction on the object -mu Nk sgn_s, Nk
    its normal force) and is pushed by palm j's corner with N (-1, -sgn mu) (palm j: m_j along
    t_j); acc_k, acc_j: each palm's own th'' alone (gravity, pivots):

        m (l_k (th_k'' c_k - w_k^2 s_k) + s'')  = -mu Nk sgn_s - N
        -m l_k (th_k'' s_k + w_k^2 c_k)         = -m g + Nk - sgn mu N
        m_k l_k th_k'' = m_k l_k acc_k + mu Nk sgn_s c_k + Nk s_k
        m_j l_j th_j'' = m_j l_j acc_j + N (c_j - sgn mu s_j)
        l_k (th_k'' c_k - w_k^2 s_k) + s'' = l_j (th_j'' c_j - w_j^2 s_j)"""
    th_k, w_k, _, _, th_j, w_j = z
    ck, sk, cj, sj = math.cos(th_k), math.sin(th_k), math.cos(th_j), math.sin(th_j)
    A = np.array([
        [m * l_k * ck, m, 0.0, mu * sgn_s, 1.0],
        [-m * l_k * sk, 0.0, 0.0, -1.0, sgn * mu],
        [m_k * l_k, 0.0, 0.0, -(mu * sgn_s * ck + sk), 0.0],
        [0.0, 0.0, m_j * l_j, 0.0, -(cj - sgn * mu * sj)],
        [l_k * ck, 1.0, -l_j * cj, 0.0, 0.0]])
    b = np.array([m * l_k * w_k * w_k * sk, m * l_k * w_k * w_k * ck - m * g,
                  m_k * l_k * acc_k, m_j * l_j * acc_j,
                  l_k * w_k * w_k * sk - l_j * w_j * w_j * sj])
    return np.linalg.solve(A, b)


class SlidingPushPhases:
    """The object sliding on palm k while it pushes palm j (expects Run's helpers)."""

    def _push_slip(self, t, k, theta, omega, s, j, th_j, om_j, fx, state):
        """The stuck push's palm-k force left its cone (friction fx): the object slides the way
        that force could no longer hold it."""
        sgn_s = -math.copysign(1.0, fx)
        self._log(t, "slip", k + 1, state, state,
                  f"the object slips on palm {k + 1} while it pushes palm {j + 1}")
        sd = sgn_s * SLIP_START_ATOLS * self.acc.atol
        return lambda: self._pushing_slide(t, k, [theta, omega, s, sd, th_j, om_j], j)

    def _slide_push_terms(self, k, j, sgn, sgn_s):
        sw_k, sw_j = self.swings_alone[k], self.swings_alone[j]
        kw = dict(l_k=self.ls[k], l_j=self.ls[j], m=self.m, m_k=sw_k.inertia, m_j=sw_j.inertia,
                  mu=self.mu, sgn=sgn, sgn_s=sgn_s, g=self.g)

        def solve(z):
            return slide_push_accelerations(
                z[:6], acc_k=ph.swing_acceleration(z[0], z[1], sw_k, direction=1.0),
                acc_j=ph.swing_acceleration(z[4], z[5], sw_j, direction=1.0), **kw)

        return solve

    def _pushing_slide(self, t0, k, z0, j):
        """State (th_k, th_k', s, s', th_j, th_j') until palm j parts or the slip stops."""
        l_k, l_j, h, w, T = self.ls[k], self.ls[j], self.h, self.row.body_width, \
            self.row.palm_thickness
        (px, py), qy = self.row.pivots[k], self.row.pivots[j][1]
        vt = -l_k * z0[1] * math.sin(z0[0]) + l_j * z0[5] * math.sin(z0[4])
        sgn = math.copysign(1.0, vt) if vt != 0.0 else -1.0
        sgn_s = math.copysign(1.0, z0[3])
        solve = self._slide_push_terms(k, j, sgn, sgn_s)

        def corner(z):
            return qy + l_j * math.cos(z[4]) - py - l_k * math.cos(z[0])

        def base_point(z, height):  # where palm k's force crosses the base, times its normal
            _, _, _, nk, n = solve(z)
            ff = -self.mu * nk * sgn_s
            return -0.5 * h * ff + 0.5 * w * sgn * self.mu * n - (height - 0.5 * h) * n, nk

        def support(z):
            return self.row.support(z[2])

        physics = [
            (lambda t, z: solve(z)[4], "part"), (lambda t, z: solve(z)[3], "lift"),
            (lambda t, z: sgn_s * z[3], "slip_stop"),
            (lambda t, z: support(z)[1] * base_point(z, min(h, corner(z)))[1]
             - base_point(z, min(h, corner(z)))[0], "tip"),
            (lambda t, z: base_point(z, max(0.0, corner(z) - T))[0]
             - support(z)[0] * base_point(z, max(0.0, corner(z) - T))[1], "tip"),
            (lambda t, z: 0.5 * self.row.palm_width - abs(z[2]), "slid_off"),
            (lambda t, z: sgn * (-l_k * z[1] * math.sin(z[0]) + l_j * z[5] * math.sin(z[4])),
             "corner_sticks"),
            (lambda t, z: corner(z), "below"), (lambda t, z: h + T - corner(z), "above"),
            (lambda t, z: z[1], "stall"),
            (lambda t, z: self.fs - z[0], "front_stop"),
            (lambda t, z: self.fs - z[4], "front_stop"),
        ]

        def point(z):
            return px + l_k * math.sin(z[0]) + z[2], py + l_k * math.cos(z[0])

        faces = []
        for box in self._obstacles(t0, k, near=px):
            if box.palm != j:
                faces += [(f, d, v, (kind, box.palm))
                          for f, d, v, kind in face_guards(lambda z, b=box: b, point)]

        def rhs(t, z):
            thdd_k, sdd, thdd_j, _, _ = solve(z)
            return [z[1], thdd_k, z[3], sdd, z[5], thdd_j]

        tracked = self._tracked(t0, k)
        y0, rhs, more = self._with_swinging(tracked, t0, list(z0), rhs, point)
        t_split = self._next_arrival(t0, k)
        te, z, kind, _ = self._integrate(rhs, t0, y0, physics, faces + more, t_end=t_split)
        self._swung_to(te, z, 6, tracked)
        return self._slide_push_ended(te, kind, k, j, z, tracked, t_split)

    def _slide_push_ended(self, t, kind, k, j, z, tracked, t_split):
        theta, omega, s, sd, th_j, om_j = (float(v) for v in z[:6])
        state = dict(self._on_palm(k, theta, omega, s, sd), palm_theta=th_j, palm_omega=om_j)
        if kind is None and t_split is not None and t >= t_split:
            return lambda: self._pushing_slide(t, k, [theta, omega, s, sd, th_j, om_j], j)
        if kind in ("part", "above"):
            return self._part(t, k, theta, omega, s, j, th_j, om_j, state, sd=sd)
        if kind == "slip_stop":
            self._log(t, "stick", k + 1, state, state,
                      f"the object sticks on palm {k + 1} again while it pushes palm {j + 1}")
            return lambda: self._pushing(t, k, theta, omega, s, j, th_j, om_j, None)
        if isinstance(kind, tuple) and len(kind) == 3:  # a swinging palm met: j parts there
            self._part(t, k, theta, omega, s, j, th_j, om_j, state, sd=sd)
            return self._met_swinging(t, kind, z, 6, tracked, None, state, k + 1,
                                      carrier=(k, theta, omega, s, sd))
        if isinstance(kind, tuple) and kind[0] == "top":
            self._part(t, k, theta, omega, s, j, th_j, om_j, state, sd=sd)
            return self._handover(t, k, theta, omega, s, sd, kind[1])
        why = f"while the object sliding on its palm pushes palm {j + 1}: {push_end(kind)}"
        return (self._stepped_carry(t, k, (theta, omega, s, sd), (th_j, om_j), 0, [j], state,
                                    why)
                or self._fail(t, "blocked", k + 1, state, why + " (not followed)"))
