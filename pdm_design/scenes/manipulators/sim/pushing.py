"""The carried object pushing a resting palm ahead off its back stop. Mixed into run.Run.

The object, stuck on palm k, meets the rear end of palm j (ahead, at rest on its back stop) with
its front face: docs/physics.md section 2.2c. Both palms are pendulums on their links: palm k
with the object (the carrying system) moves along t_k = (cos th_k, -sin th_k), palm j along t_j.
The contact at palm j's rear top corner has its normal along the row (the object's face is
vertical: palms translate) and Coulomb friction along the face.

  impact   plastic: the relative normal speed vanishes, the corner slides along the face
           (or sticks, then both palms stop): push_impact;
  push     the object keeps its face on the corner: the constraint l_k sin th_k - l_j sin th_j
           = const ties the two swings, the contact force N >= 0 follows from it
           (push_accelerations); the phase ends when N falls through zero: palm j parts and
           swings on alone, followed as a palm swinging from rest (swinging.py), and the carry
           goes on. The object slipping on palm k while it pushes: pushslide.py. Not followed
           (`blocked`, with the reason): the object lifting or tipping on palm k, the corner's
           slip stopping, a stop reached, another palm's side met while pushing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from . import phases as ph
from .geometry import face_guards

# a push's ends that are not followed, in words (push_end)
PUSH_ENDS = {
    "lift": "the object lifts off its palm", "tip": "the object tips on its palm",
    "slid_off": "the object slides off its palm",
    "corner_sticks": "the corner sticks on its face",
    "below": "the palm's top comes level with the object's base",
    "stall": "its palm stops", "front_stop": "a palm reaches its front stop",
    None: "no event",
}


def push_end(kind) -> str:
    """What ended a push the phases do not follow on (a guard's kind, or (kind, palm))."""
    if kind in PUSH_ENDS:
        return PUSH_ENDS[kind]
    return f"it meets palm {kind[1] + 1}" if isinstance(kind, tuple) else str(kind)


@dataclass(frozen=True)
class Push:
    """Result of the push impact: rates along the swings after it (u = l th'), the impulse on
    the object (-pn along the row, pt up its face), and whether the corner sticks."""

    u_k: float
    u_j: float
    pn: float
    pt: float
    stick: bool


def push_impact(u_k, u_j, th_k, th_j, *, m_k, m_j, mu) -> Push | None:
    """Plastic impact of the carrying system (mass m_k along t_k, speed u_k) against palm j's
    corner (mass m_j along t_j, speed u_j); None if the object does not approach or no
    consistent impulse exists. The impulse on the object is P = pn (-1, 0) + pt (0, 1), on
    palm j -P; the swings' speeds change by P . t_k / m_k and -P . t_j / m_j. Darboux-Keller
    in the normal impulse pn: the corner slides against its slip until the approach ends; a
    slip that would reverse first sticks there, or slides on the other way."""
    ck, sk, cj, sj = math.cos(th_k), math.sin(th_k), math.cos(th_j), math.sin(th_j)
    if u_k * ck - u_j * cj <= 0.0:
        return None
    pn_sum, pt_sum = 0.0, 0.0
    vt = -u_k * sk + u_j * sj  # object minus corner, up the face
    sgn = math.copysign(1.0, vt) if vt != 0.0 else 0.0
    for _ in range(3):
        vn = u_k * ck - u_j * cj
        if sgn == 0.0:  # at relative rest: it sticks, or slides the way friction allows
            if _sticks(u_k, u_j, ck, sk, cj, sj, m_k, m_j, mu):
                pn, pt = _stick_impulse(u_k, u_j, ck, sk, cj, sj, m_k, m_j)
                return Push(0.0, 0.0, pn_sum + pn, pt_sum + pt, True)
            sgn = _slip_way(u_k, u_j, ck, sk, cj, sj, m_k, m_j, mu)
            if sgn is None:
                return None
        ak, aj = ck - sgn * mu * sk, cj - sgn * mu * sj  # -(P . t) / pn on each swing
        rate_n = ak * ck / m_k + aj * cj / m_j  # approach speed lost per unit pn
        rate_t = ak * sk / m_k + aj * sj / m_j  # d vt / d pn
        if rate_n <= 0.0:
            return None
        pn = vn / rate_n
        vt = -u_k * sk + u_j * sj
        if sgn * (vt + rate_t * pn) < 0.0:  # the slip ends first, at vt = 0
            pn = -vt / rate_t
        u_k, u_j = u_k - pn * ak / m_k, u_j + pn * aj / m_j
        pn_sum, pt_sum = pn_sum + pn, pt_sum - sgn * mu * pn
        if u_k * ck - u_j * cj <= 1e-12 * (abs(u_k) + abs(u_j)):
            return Push(u_k, u_j, pn_sum, pt_sum, False)
        sgn = 0.0
    return None


def _sticks(u_k, u_j, ck, sk, cj, sj, m_k, m_j, mu):
    """The sticking impulse from this state (both swings stop) pushes, within the cone."""
    if abs(ck * sj - sk * cj) == 0.0:
        return False
    pn, pt = _stick_impulse(u_k, u_j, ck, sk, cj, sj, m_k, m_j)
    return pn >= 0.0 and abs(pt) <= mu * pn


def _slip_way(u_k, u_j, ck, sk, cj, sj, m_k, m_j, mu):
    """From relative rest up the face: the slip direction whose friction keeps it (None: no
    direction does)."""
    for sgn in (1.0, -1.0):
        ak, aj = ck - sgn * mu * sk, cj - sgn * mu * sj
        if sgn * (ak * sk / m_k + aj * sj / m_j) > 0.0:
            return sgn
    return None


def _stick_impulse(u_k, u_j, ck, sk, cj, sj, m_k, m_j):
    """(pn, pt) that stops both swings: P . t_k = -m_k u_k and P . t_j = m_j u_j."""
    # -pn ck - pt sk = -m_k u_k ;  -pn cj - pt sj = m_j u_j
    det = ck * sj - sk * cj
    ak, aj = m_k * u_k, -m_j * u_j
    return (ak * sj - aj * sk) / det, (ck * aj - cj * ak) / det


def push_accelerations(th_k, om_k, th_j, om_j, *, acc_k, acc_j, l_k, l_j, m_k, m_j, mu, sgn):
    """(th_k'', th_j'', N) while the object's face stays on palm j's corner. acc_k, acc_j: each
    swing's own th'' (gravity, pivots); the contact force on the object N (-1, -sgn mu) (sgn:
    the sign of the object's speed up the face relative to the corner) adds N c_i / l_i:

        l_k th_k'' = l_k acc_k + N c_k,  c_k = -(cos th_k - sgn mu sin th_k) / m_k
        l_j th_j'' = l_j acc_j + N c_j,  c_j =  (cos th_j - sgn mu sin th_j) / m_j

    and the constraint l_k sin th_k - l_j sin th_j = const, twice differentiated, fixes N."""
    ck, sk, cj, sj = math.cos(th_k), math.sin(th_k), math.cos(th_j), math.sin(th_j)
    c_k = -(ck - sgn * mu * sk) / m_k
    c_j = (cj - sgn * mu * sj) / m_j
    a_k, a_j = l_k * acc_k, l_j * acc_j
    # ck (a_k + N c_k) - l_k om_k^2 sk = cj (a_j + N c_j) - l_j om_j^2 sj
    rhs = cj * a_j - l_j * om_j * om_j * sj - ck * a_k + l_k * om_k * om_k * sk
    n = rhs / (ck * c_k - cj * c_j)
    return (a_k + n * c_k) / l_k, (a_j + n * c_j) / l_j, n


class PushingPhases:
    """The carried object pushing the next palm off its back stop (expects Run's helpers)."""

    def _push_contact(self, t, k, theta, s, j):
        """Height of palm j's rear top corner above the object's base when the object stuck on
        palm k at theta meets palm j's box through its rear face, palm j resting on its back
        stop; None when that is not the contact (another face, the palm elsewhere)."""
        if j <= k or self.rest_since[j] > t or self.rest_angle[j] != -self.alphas[j]:
            return None
        px, py = self.row.pivots[k]
        x = px + self.ls[k] * math.sin(theta) + s
        y = py + self.ls[k] * math.cos(theta)
        box = self._rest_box(j)
        tol, box_thickness = 1e-7 * self.l, self.row.palm_thickness
        hc = box.y_high - y
        if abs(x - (box.cx - box.half_width)) > tol or not 0.0 < hc < self.h + box_thickness:
            return None
        return hc

    def _push(self, t, k, theta, omega, s, j, hc):
        """The impact of the object stuck on palm k against palm j's corner, then the push."""
        m_k, m_j = self.swings_loaded[k].inertia, self.swings_alone[j].inertia
        th_j = self.rest_angle[j]
        before = self._on_palm(k, theta, omega, s)
        imp = push_impact(self.ls[k] * omega, 0.0, theta, th_j, m_k=m_k, m_j=m_j, mu=self.mu)
        if imp is None or imp.stick or imp.u_k <= 0.0 or imp.u_j <= 0.0:
            what = ("both palms stop" if imp is not None and imp.stick else
                    "no consistent impact" if imp is None else "a palm is driven back")
            why = f"the carried object pushes palm {j + 1} off its back stop: {what}"
            return (self._stepped_carry(t, k, (theta, omega, s, 0.0), (), 0, [], before, why)
                    or self._fail(t, "blocked", k + 1, before, why + " (not followed)"))
        omega, om_j = imp.u_k / self.ls[k], imp.u_j / self.ls[j]
        after = dict(self._on_palm(k, theta, omega, s), palm_theta=th_j, palm_omega=om_j)
        self._log(t, "push", k + 1, before, after,
                  f"the carried object pushes palm {j + 1} off its back stop "
                  f"(impulse {imp.pn:.4g} N s)")
        self.rest_since[j] = math.inf
        return lambda: self._pushing(t, k, theta, omega, s, j, th_j, om_j, hc)

    def _push_terms(self, k, j, sgn):
        sw_k, sw_j = self.swings_loaded[k], self.swings_alone[j]
        l_k, l_j = self.ls[k], self.ls[j]

        def accel(z):
            return push_accelerations(
                z[0], z[1], z[2], z[3], l_k=l_k, l_j=l_j, m_k=sw_k.inertia, m_j=sw_j.inertia,
                mu=self.mu, sgn=sgn,
                acc_k=ph.swing_acceleration(z[0], z[1], sw_k, direction=1.0),
                acc_j=ph.swing_acceleration(z[2], z[3], sw_j, direction=1.0))

        return accel

    def _push_forces(self, z, accel, k, sgn):
        """(friction, normal) of palm k's force on the object and where it crosses the base
        (from its centre) while the corner pushes at height hc: the object translates, so the
        moments about its centre balance."""
        thdd_k, _, n = accel(z)
        fx, fn = ph.stuck_contact_force(z[0], z[1], thdd_k, gravity=self.g, link_length=self.ls[k])
        fx, fn = self.m * fx + n, self.m * fn + sgn * self.mu * n
        return fx, fn, n

    def _pushing(self, t0, k, theta0, omega0, s, j, th_j0, om_j0, hc0):
        """State (th_k, th_k', th_j, th_j'): the push until palm j parts from the object."""
        l_k, l_j, h, w = self.ls[k], self.ls[j], self.h, self.row.body_width
        T = self.row.palm_thickness
        (px, py), qy = self.row.pivots[k], self.row.pivots[j][1]
        vt = -l_k * omega0 * math.sin(theta0) + l_j * om_j0 * math.sin(th_j0)
        sgn = math.copysign(1.0, vt) if vt != 0.0 else -1.0
        accel = self._push_terms(k, j, sgn)
        lo, hi = self.row.support(s)

        def corner(z):  # palm j's top rear corner above the object's base
            return qy + l_j * math.cos(z[2]) - py - l_k * math.cos(z[0])

        def moment(z, height):  # where palm k's force crosses the base, times its normal
            fx, fn, n = self._push_forces(z, accel, k, sgn)
            return -0.5 * h * fx + 0.5 * w * sgn * self.mu * n - (height - 0.5 * h) * n, fn

        def tips_forward(z):  # the push at the overlap's top: the base's front end at the most
            xb, fn = moment(z, min(h, corner(z)))
            return hi * fn - xb

        def tips_back(z):  # the push at the overlap's bottom
            xb, fn = moment(z, max(0.0, corner(z) - T))
            return xb - lo * fn

        physics = [
            (lambda t, z: accel(z)[2], "part"),
            (lambda t, z: self._push_forces(z, accel, k, sgn)[1], "lift"),
            (lambda t, z: self.mu * self._push_forces(z, accel, k, sgn)[1]
             - abs(self._push_forces(z, accel, k, sgn)[0]), "slip"),
            (lambda t, z: tips_forward(z), "tip"), (lambda t, z: tips_back(z), "tip"),
            (lambda t, z: sgn * (-l_k * z[1] * math.sin(z[0]) + l_j * z[3] * math.sin(z[2])),
             "corner_sticks"),
            (lambda t, z: corner(z), "below"),
            (lambda t, z: h + T - corner(z), "above"),
            (lambda t, z: z[1], "stall"),
            (lambda t, z: self.fs - z[0], "front_stop"),
            (lambda t, z: self.fs - z[2], "front_stop"),
        ]

        def point(z):
            return px + l_k * math.sin(z[0]) + s, py + l_k * math.cos(z[0])

        faces = []
        for box in self._obstacles(t0, k, near=px):
            if box.palm != j:
                faces += [(f, d, v, (kind, box.palm))
                          for f, d, v, kind in face_guards(lambda z, b=box: b, point)]

        def rhs(t, z):
            thdd_k, thdd_j, _ = accel(z)
            return [z[1], thdd_k, z[3], thdd_j]

        tracked = self._tracked(t0, k)  # palms swinging (from rest, or pushed earlier)
        z0, rhs, more = self._with_swinging(tracked, t0, [theta0, omega0, th_j0, om_j0], rhs,
                                            point)
        t_split = self._next_arrival(t0, k)
        te, z, kind, _ = self._integrate(rhs, t0, z0, physics, faces + more, t_end=t_split)
        self._swung_to(te, z, 4, tracked)
        if isinstance(kind, tuple) and len(kind) == 3:  # a swinging palm met: j parts there
            theta, omega, th_j, om_j = (float(v) for v in z[:4])
            state = dict(self._on_palm(k, theta, omega, s), palm_theta=th_j, palm_omega=om_j)
            self._part(te, k, theta, omega, s, j, th_j, om_j, state)
            return self._met_swinging(te, kind, z, 4, tracked, None, state, k + 1,
                                      carrier=(k, theta, omega, s, 0.0))
        if kind == "slip":  # the object slides on palm k, still pushing (pushslide.py)
            theta, omega, th_j, om_j = (float(v) for v in z[:4])
            state = dict(self._on_palm(k, theta, omega, s), palm_theta=th_j, palm_omega=om_j)
            fx = self._push_forces(z, accel, k, sgn)[0]
            return self._push_slip(te, k, theta, omega, s, j, th_j, om_j, fx, state)
        return self._push_ended(te, kind, k, s, j, [float(v) for v in z[:4]], t_split, hc0)

    def _push_ended(self, t, kind, k, s, j, z, t_split, hc0):
        """What follows the push phase's end: palm j parts (N falls to zero, or the palm rises
        clear over the object's top), the object comes onto palm j's or another palm's top, or
        the run ends `blocked` with the reason."""
        theta, omega, th_j, om_j = z
        state = dict(self._on_palm(k, theta, omega, s), palm_theta=th_j, palm_omega=om_j)
        if kind is None and t_split is not None and t >= t_split:
            return lambda: self._pushing(t, k, theta, omega, s, j, th_j, om_j, hc0)
        if kind in ("part", "above"):
            return self._part(t, k, theta, omega, s, j, th_j, om_j, state)
        obj_vy = state["vy"]
        if kind == "below" and obj_vy + self.ls[j] * om_j * math.sin(th_j) < 0.0:
            # the object comes onto palm j's top as palm j swings
            return self._handover(t, k, theta, omega, s, 0.0, j, palm=(th_j, self.ls[j] * om_j))
        if isinstance(kind, tuple) and kind[0] == "top":
            self._part(t, k, theta, omega, s, j, th_j, om_j, state)  # (it swings on, followed)
            return self._handover(t, k, theta, omega, s, 0.0, kind[1])
        why = f"while the carried object pushes palm {j + 1}: {push_end(kind)}"
        return (self._stepped_carry(t, k, (theta, omega, s, 0.0), (th_j, om_j), 0, [j], state,
                                    why)
                or self._fail(t, "blocked", k + 1, state, why + " (not followed)"))

    def _part(self, t, k, theta, omega, s, j, th_j, om_j, state, sd=0.0):
        """Palm j parts from the object: it swings on alone from (th_j, th_j'), followed as a
        palm swinging from rest is (swinging.py) until the object meets it; the carry goes on
        (stuck, or sliding at s' = sd)."""
        self._log(t, "part", k + 1, state, state,
                  f"palm {j + 1} parts from the object at th = {th_j:.6g} rad")
        events = len(self.palm_events)
        self._release(j, t, th_j, self.ls[j] * om_j)
        if len(self.palm_events) > events:
            self._planned[j] = self.palm_events[-1]
        self.unmet.add(j)
        self.pushed.add(j)
        self._free[j] = (t, th_j, om_j)
        if sd != 0.0:
            return lambda: self._sliding(t, k, theta, omega, s, sd)
        return lambda: self._stuck(t, k, theta, self.ls[k] * omega, s)

