"""The manipulators' rows over a box of link lengths, every palm its own (docs/optimizer.md
section 4a, `link_length`): palm K's link l_K = l + e_K, |e_K| <= t_l, on the paper's device
(allocation.check refuses links and pivot friction, and the back stops' tolerance with it).

The pivots stay where the design puts them (each within its own box). What a link moves:
* palm K's rest top, P_K + l_K (-sin a, cos a): palm 1's top is e_1 cos a higher (the fall onto
  it) and e_1 sin a further back (the first landing's place);
* the handover K -> K+1, where palm K's top comes down to palm K+1's:
      l_K cos th_K = l cos b + z_K,   z_K = e_{K+1} cos a + dy_{K+1} - dy_K,
  so cos th_K lies between (l cos b - Z) / (l +- t_l) and (l cos b + Z) / (l -+ t_l),
  Z = t_l cos a + 2 t_y (`handover_cosines`);
* the carry: its energy 2 g l_K (cos a - cos th) (increasing in l_K where th >= a, which
  palm_clearance keeps), the lift-off capacity g l_K cos th, the top 2 g l_K (1 - cos a):
  monotone in l_K at a fixed angle, so the rows take the worse end (`ends`);
* the landing place: o_{K+1} = o_K + G(e_K, z_K) + e_{K+1} sin a - (dx_{K+1} - dx_K), with
      G(e, z) = sqrt((l + e)^2 - (l cos b + z)^2) - l sin b
  jointly concave (sqrt(A^2 - B^2) is concave on A > |B|: its Hessian is negative
  semidefinite), G = e / sin b - cot b z + R(e, z), R <= 0 concave, R(0, 0) = 0. Summed along
  the row the first-order terms do not telescope (`first_order`) and R adds up stage by stage
  (`second_order`).
"""

from __future__ import annotations

import casadi as ca

from .common import fmin_all


def ends(m, box):
    """(l_lo, l_hi): the link lengths the box allows (the design's l twice, the same
    expression, when the link length is exact)."""
    t_l = box.get("link_length", 0.0)
    if isinstance(t_l, (int, float)) and t_l == 0.0:
        return m.l, m.l
    return m.l - t_l, m.l + t_l


def reach(m, tau, t_l):
    """Z = t_l cos a + 2 t_y: the largest |z_K| (the handover's rise, palm K+1's link and the
    two pivots' heights), and t_l cos a the most palm 1's top is raised or lowered by its link."""
    return t_l * ca.cos(m.a) + 2 * tau


def handover_cosines(m, tau, t_l):
    """(cm, cp): the smallest and the largest cos th_K = (l cos b + z_K) / l_K over the box
    (each numerator over both ends of the link: either sign of the numerator)."""
    l, Z = m.l, reach(m, tau, t_l)
    low, high = l * ca.cos(m.b) - Z, l * ca.cos(m.b) + Z
    return (ca.fmin(low / (l + t_l), low / (l - t_l)),
            ca.fmax(high / (l - t_l), high / (l + t_l)))


def first_order(m, stages, t_l):
    """The largest first-order move of the landing place on palms 2..N by the links: with
    o_1 = C0 + vx0 t(rho_1) - dx_1 + e_1 sin a (rho_1 = dy_1 + e_1 cos a, palm 1's top's rise),

        o_K = C0 + phi(rho_1) - dx_K - cot b dy_K + c_m sum_{j<K} e_j + c_K e_K
              + sum_{j<K} R(e_j, z_j),
        c_m = (1 - cos(a + b)) / sin b >= 0,   c_K = -cos(a + b) / sin b,

    (phi(rho) = vx0 t(rho) + cot b rho, section 4's): every link before palm K carries the
    object c_m e_j further, and the sum is largest on palm N: t_l ((N - 1) c_m + |c_N|)."""
    a, b = m.a, m.b
    c_m = (1 - ca.cos(a + b)) / ca.sin(b)
    return t_l * ((stages - 1) * c_m + ca.fabs(ca.cos(a + b)) / ca.sin(b))


def residual(m, e, z):
    """R(e, z) = G(e, z) - e / sin b + cot b z, G written without cancellation:
    G = (2 l e + e^2 - 2 l cos b z - z^2) / (sqrt((l + e)^2 - (l cos b + z)^2) + l sin b).
    The square root's argument is kept >= 0 (a number wherever IPOPT steps; the handover
    exists on the feasible set, palm_clearance)."""
    l, b = m.l, m.b
    inside = ca.fmax((l + e) ** 2 - (l * ca.cos(b) + z) ** 2, 0.0)
    G = (2 * l * e + e**2 - 2 * l * ca.cos(b) * z - z**2) / (ca.sqrt(inside) + l * ca.sin(b))
    return G - e / ca.sin(b) + ca.cos(b) / ca.sin(b) * z


def second_order(m, stages, tau, t_l):
    """A lower bound of sum_{K<N} R(e_K, z_K): each term at least the least R over the
    product box e in [-t_l, t_l], z in [-Z, Z] (R concave: least at one of its four corners),
    N - 1 of them (each R <= 0: palm N's sum is the smallest)."""
    Z = reach(m, tau, t_l)
    corners = [residual(m, e, z) for e in (t_l, -t_l) for z in (Z, -Z)]
    return (stages - 1) * fmin_all(corners)
