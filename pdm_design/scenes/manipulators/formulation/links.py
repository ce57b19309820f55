"""The manipulators' rows over a box of link lengths, every palm its own (docs/optimizer.md
section 4a, `link_length`): palm K's link l_K = l + e_K, |e_K| <= t_l, and with it, when
toleranced too, its back stop a_K in [a_lo, a_hi] (the stops only on the paper's device:
allocation.check; on real links the carry's terms are free of a build's link, and the rows
take both link ends where they are not monotone in it: rows._top_needs, _contact_rows).

The pivots stay where the design puts them (each within its own box). Palm j resting on its
back stop has its top at P_j + l_j (-sin a_j, cos a_j): q_j = l_j cos a_j - l cos a higher and
p_j = l_j sin a_j - l sin a further back than the design's (`Rest`). What they move:
* palm 1's top: the fall onto it and the first landing's place;
* the handover K -> K+1, where palm K's top comes down to palm K+1's:
      l_K cos th_K = l cos b + z_K,   z_K = q_{K+1} + dy_{K+1} - dy_K  in [z_lo, z_hi],
  so cos th_K lies between (l cos b + z_lo) / (l +- t_l) and (l cos b + z_hi) / (l -+ t_l)
  (`handover_cosines`);
* the carry: its energy 2 g l_K (cos a_K - cos th) (increasing in l_K where th >= a_K, which
  palm_clearance keeps), the lift-off capacity g l_K cos th, the top 2 g l_K (1 - cos a_K);
* the landing place: o_{K+1} = o_K + G(e_K, z_K) + p_{K+1} - (dx_{K+1} - dx_K), with
      G(e, z) = sqrt((l + e)^2 - (l cos b + z)^2) - l sin b
  jointly concave (sqrt(A^2 - B^2) is concave on A > |B|: its Hessian is negative
  semidefinite), G = e / sin b - cot b z + R(e, z), R <= 0 concave, R(0, 0) = 0. Summed along
  the row the first-order terms do not telescope (`Rest.first_order`) and R adds up stage by
  stage (`second_order`).
"""

from __future__ import annotations

import casadi as ca

from ....formulation.common import fmax_all, fmin_all
from ..physics import cos_difference


def ends(m, box):
    """(l_lo, l_hi): the link lengths the box allows (the design's l twice, the same
    expression, when the link length is exact)."""
    t_l = box.get("link_length", 0.0)
    if isinstance(t_l, (int, float)) and t_l == 0.0:
        return m.l, m.l
    return m.l - t_l, m.l + t_l


class Rest:
    """Where a palm rests over the box: q in [q_lo, q_hi] (its top's rise), p in [p_lo, p_hi]
    (its top's move back), with its link's error t_l and its stop in [a_lo, a_hi] (a_lo >= 0:
    back_stop_range), written without cancellation (exactly the links' terms without a stop
    tolerance)."""

    def __init__(self, m, t_l, stops):
        a, l = m.a, m.l
        self.m, self.t_l, (a_lo, a_hi) = m, t_l, stops
        self.a_lo, self.a_hi = a_lo, a_hi
        # l_j cos a_j - l cos a = l (cos a_j - cos a) + e_j cos a_j: least at (l - t_l, a_hi)
        self.q_lo = -l * cos_difference(a, a_hi) - t_l * ca.cos(a_hi)
        self.q_hi = -l * cos_difference(a, a_lo) + t_l * ca.cos(a_lo)
        # l_j sin a_j - l sin a: increasing in both on a_j in [0, pi/2)
        self.p_lo = l * (ca.sin(a_lo) - ca.sin(a)) - t_l * ca.sin(a_lo)
        self.p_hi = l * (ca.sin(a_hi) - ca.sin(a)) + t_l * ca.sin(a_hi)

    def z_range(self, tau):
        """(z_lo, z_hi): the handover's z_K = q_{K+1} + dy_{K+1} - dy_K over the box."""
        return self.q_lo - 2 * tau, self.q_hi + 2 * tau

    def handover_cosines(self, tau):
        """(cm, cp): the smallest and the largest cos th_K = (l cos b + z_K) / l_K over the box
        (each numerator over both ends of the link: either sign of the numerator)."""
        m, t_l = self.m, self.t_l
        low, high = (m.l * ca.cos(m.b) + z for z in self.z_range(tau))
        return (ca.fmin(low / (m.l + t_l), low / (m.l - t_l)),
                ca.fmax(high / (m.l - t_l), high / (m.l + t_l)))

    def first_order(self, stages):
        """(least, largest) first-order move of the landing place on palms 2..N by the links
        and stops. With o_1 = C0 + vx0 t(rho_1) - dx_1 + p_1 (rho_1 = dy_1 + q_1, palm 1's
        top's rise),

            o_K = C0 + phi(rho_1) - dx_K - cot b dy_K + sum_{j<K} c(l_j, a_j)
                  + d(l_K, a_K) + sum_{j<K} R(e_j, z_j),
            c(l', a') = (l' (1 - cos(a' + b)) - l (1 - cos(a + b))) / sin b,
            d(l', a') = -(l' cos(a' + b) - l cos(a + b)) / sin b

        (phi(rho) = vx0 t(rho) + cot b rho, section 4's): c = p - cot b q + e / sin b, each link
        before palm K carries the object c further; d = p - cot b q, palm K's own. Each is
        affine in l' and, with a' + b in (0, pi), monotone in a': extreme at the corners of
        [l - t_l, l + t_l] x [a_lo, a_hi]; c >= its value at (l - t_l, a_lo) and <= at
        (l + t_l, a_hi) (c increases in both), d over all four. Palm N's sum is the widest."""
        m, t_l, b = self.m, self.t_l, self.m.b

        def c(e, s):  # e (1 - cos(s + b)) + l (cos(a + b) - cos(s + b)), over sin b
            return (e * (1 - ca.cos(s + b)) + m.l * cos_difference(m.a + b, s + b)) / ca.sin(b)

        def d(e, s):
            return -(e * ca.cos(s + b) - m.l * cos_difference(m.a + b, s + b)) / ca.sin(b)

        corners = [d(e, s) for e in (-t_l, t_l) for s in (self.a_lo, self.a_hi)]
        return ((stages - 1) * c(-t_l, self.a_lo) + fmin_all(corners),
                (stages - 1) * c(t_l, self.a_hi) + fmax_all(corners))

    def second_order(self, stages, tau):
        """A lower bound of sum_{K<N} R(e_K, z_K): each term at least the least R over the
        product box e in [-t_l, t_l], z in [z_lo, z_hi] (R concave: least at one of its four
        corners), N - 1 of them (each R <= 0: palm N's sum is the smallest)."""
        corners = [residual(self.m, e, z) for e in (self.t_l, -self.t_l)
                   for z in self.z_range(tau)]
        return (stages - 1) * fmin_all(corners)


def residual(m, e, z):
    """R(e, z) = G(e, z) - e / sin b + cot b z, G written without cancellation:
    G = (2 l e + e^2 - 2 l cos b z - z^2) / (sqrt((l + e)^2 - (l cos b + z)^2) + l sin b).
    The square root's argument is kept >= 0 (a number wherever IPOPT steps; the handover
    exists on the feasible set, palm_clearance)."""
    l, b = m.l, m.b
    inside = ca.fmax((l + e) ** 2 - (l * ca.cos(b) + z) ** 2, 0.0)
    G = (2 * l * e + e**2 - 2 * l * ca.cos(b) * z - z**2) / (ca.sqrt(inside) + l * ca.sin(b))
    return G - e / ca.sin(b) + ca.cos(b) / ca.sin(b) * z
