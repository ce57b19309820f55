"""The carry's effective terms over a box of masses and pivot frictions (docs/optimizer.md,
section 4a): the ends of q_e, g_e and f that the robust rows take, and the model's view at a
corner of them.

Palm K as built has mass M_K, links of mass mu_K each (J_K, W_K: physics.carry_terms' effective
inertia mass and half the links' weight, both increasing in mu_K) and a Coulomb torque tau_K
(drawn below 0, it is 0); the lot's object has mass m. With A = m + M_K:

    q_e = m / (M + J)                increasing in m, decreasing in M and mu
    g_e = g (A + W) / (A + J)        d/dA = g (J - W) / (A + J)^2,  d/dmu = g A (W' - J') / (.)^2
                                     with W' - J' = (W - J) / mu: one sign for the whole box
    f   = tau / (A + J)              increasing in tau, decreasing in m, M and mu

Each is monotone in each raw quantity with one sign over the box, so its extremes over the box
are the values at two of its corners: exact ends, whatever the palm (each) or the lot. g_e's
two candidates are (A low, mu high) and (A high, mu low); which is the larger is the sign of
W - J (uniform rods: W = 3J/2 > J), decided here when it is a number and by min / max when
it is a symbol (a given inertia on a free link length).

The rows then use that every stage map, over-the-top need, lift-off capacity and force ratio is
monotone, convex or quasilinear in (g_e, f) (docs/optimizer.md section 4a): `low` is the
slowest carry (g_e low, f high), `high` the fastest, `corners` every vertex of the (g_e, f) box.
"""

from __future__ import annotations

import copy
import itertools
from dataclasses import dataclass

import casadi as ca

from ....formulation.common import VALIDITY
from .. import physics as phys
from . import rows

QUANTITIES = ("object_mass", "palm_mass", "link_mass", "pivot_friction")


@dataclass(frozen=True)
class CarryEnds:
    """[value] (exact) or [low, high] of the effective mass ratio q_e, gravity g_e and friction
    f over the box."""

    q: list
    g: list
    f: list
    # (the lightest palm's weight plus half its links', in kg; the largest torque) when f varies
    empty: tuple | None = None

    @property
    def carry_varies(self) -> bool:
        """Whether the carry itself (g_e or f) varies over the box, not only the landings."""
        return len(self.g) > 1 or len(self.f) > 1

    def low(self, m):
        """The model at the slowest carry: g_e low, f high."""
        return at(m, self.g[0], self.f[-1])

    def high(self, m):
        """The model at the fastest carry: g_e high, f low."""
        return at(m, self.g[-1], self.f[0])

    def corners(self, m) -> list:
        """(label, model) at every vertex of the (g_e, f) box ([("", m)] when exact)."""
        g_ends = rows.ends(self.g, "gravity")
        f_ends = rows.ends(self.f, "pivot friction")
        return [(", ".join(w for w in (gw, fw) if w), at(m, g, f))
                for (gw, g), (fw, f) in itertools.product(g_ends, f_ends)]


def terms(m, box) -> CarryEnds:
    """The ends of (q_e, g_e, f) over the box {quantity: half-width} (module docstring). On the
    paper's device with the masses alone toleranced, today's mass ratios (m.mass_ratios)."""
    t_m, t_M, t_l, t_t = (box.get(q, 0.0) for q in QUANTITIES)
    masses = rows.nonzero(t_m) or rows.nonzero(t_M) or rows.nonzero(t_l)
    if not (masses or rows.nonzero(t_t)):
        return CarryEnds([m.q], [m.gc], [m.f])
    scene = m.scene
    if scene.plain_mechanism:  # link_mass, pivot_friction need a nominal: allocation.check
        return CarryEnds(m.mass_ratios(box), [m.gc], [m.f])
    obj = scene.body.mass
    palm = obj / m.mass_ratio
    m_lo, m_hi = obj - t_m, obj + t_m
    M_lo, M_hi = palm - t_M, palm + t_M
    nominal = _links(scene, m.l, None)
    links = [nominal] if not rows.nonzero(t_l) else [
        _links(scene, m.l, scene.links.mass + s * t_l) for s in (-1.0, 1.0)]
    (J_lo, W_lo), (J_hi, W_hi) = links[0], links[-1]
    q = [m.q] if not masses else [m_lo / (M_hi + J_hi), m_hi / (M_lo + J_lo)]
    g = [m.gc]
    if masses and not (phys.is_exact_zero(J_hi) and phys.is_exact_zero(W_hi)):
        g = _ordered(m.g * (m_lo + M_lo + W_hi) / (m_lo + M_lo + J_hi),
                     m.g * (m_hi + M_hi + W_lo) / (m_hi + M_hi + J_lo),
                     nominal[1] - nominal[0])
    torque = scene.pivots.friction_torque
    if not (rows.nonzero(t_t) or (masses and torque != 0.0)):
        return CarryEnds(q, g, [m.f])
    tau_lo = ca.fmax(torque - t_t, 0.0) if rows.nonzero(t_t) else torque
    f = [tau_lo / (m_hi + M_hi + J_hi), (torque + t_t) / (m_lo + M_lo + J_lo)]
    return CarryEnds(q, g, f, (M_lo + W_lo, torque + t_t))


def _links(scene, l, mass):
    """(J, W) of a manipulator whose links weigh `mass` each (None: the scene's)."""
    mech = scene.mechanism(link_mass=mass)
    j = phys.links_inertia_mass(link_mass=mech["link_mass"], link_length=l,
                                link_inertia=mech["link_inertia"])
    return j, 0.5 * mech["link_mass"]


def _ordered(first, second, sign):
    """[low, high] of g_e's two corner values: `first` (light carry, heavy links) is the
    larger when W >= J (sign = W - J at the nominal link mass: both are proportional to it, so
    one sign for the box); min / max when the sign is a symbol (a given inertia on a free link
    length)."""
    if isinstance(sign, (int, float)):
        return [second, first] if sign >= 0.0 else [first, second]
    return [ca.fmin(first, second), ca.fmax(first, second)]


def at(m, gravity, friction):
    """The model m with its carry's effective gravity and friction replaced (m itself when they
    are its own): its stage map, carry speed and contact force at that corner."""
    if gravity is m.gc and friction is m.f:
        return m
    view = copy.copy(m)
    view.gc, view.f = gravity, friction
    del view.top_needed  # the nominal need: the rows take each corner's (carry_rows)
    return view


def back_contact(m, f, v, slow2, fast2):
    """The back stops toleranced on real links: (l N_lo at the fastest landing, [r_lo, r_hi] at
    each landing speed) over every stop angle a in [a_lo, a_hi] of the model view v (one
    vertex of the (g_e, f) box). At the back stop -a, per object mass,
        N = g - g_e sin^2 a - (u^2 / l) cos a - (f / l) sin a,
        F = -g_e sin a cos a - (f / l) cos a + (u^2 / l) sin a,
    both with |d2/da2| <= S = 2 g_e + u^2 / l + f / l, so each lies within its ends' range
    widened by S (a_hi - a_lo)^2 / 8 (a function is within that of its chord), and F / N within
    the quotients of those ranges (N_lo > 0: the lift-off row)."""
    l, g = m.l, m.g

    def forces(stop, u2):  # (friction, normal) at the back stop -stop
        along = phys.carry_along(-stop, gravity=g, carry_gravity=v.gc, friction=v.f,
                                 link_length=l)
        return phys.carry_contact_force(-stop, u2, gravity=g, link_length=l, along=along)

    out = []
    for u2 in (slow2, fast2):
        (f1, n1), (f2, n2) = forces(f.a_lo, u2), forces(f.a_hi, u2)
        sag = (2.0 * v.gc + u2 / l + v.f / l) * (f.a_hi - f.a_lo) ** 2 / 8.0
        n_lo, n_hi = ca.fmin(n1, n2) - sag, ca.fmax(n1, n2) + sag
        f_lo, f_hi = ca.fmin(f1, f2) - sag, ca.fmax(f1, f2) + sag
        out.append((n_lo, [ca.fmin(f_lo / n_lo, f_lo / n_hi), ca.fmax(f_hi / n_lo, f_hi / n_hi)]))
    return l * out[1][0], out[0][1] + out[1][1]


def validity_rows(m, f):
    """Links keep a mass within their tolerance (link mass 0 is a build, below it none; the
    ends of q_e, g_e and f are the extremes only over masses >= 0); with the carry varying, it
    descends over every handover angle (F increases with g_e only where cos a >= cos th); with
    the friction varying, every empty palm swings on to its front stop (the parked palms' rows
    take it there): gravity's torque on the lightest palm at the smallest handover angle beats
    the largest friction torque, and grows on to pi/2."""
    t_l = f.box.get("link_mass", 0.0)
    if rows.nonzero(t_l):
        mass = m.scene.links.mass
        f.add(("positive_mass",), "every link keeps a mass within its tolerance",
              (1.0 - rows.MASS_KEPT) * mass - t_l, mass, kind=VALIDITY)
    if f.robust and len(f.terms.g) > 1:
        f.add(("palm_clearance",), "the carry descends to every handover angle",
              phys.cos_difference(f.a_hi, f.th_lo), 1.0, kind=VALIDITY)
    if f.robust and f.terms.empty is not None:
        weight, torque = f.terms.empty
        push = weight * m.g * f.l_lo  # the shortest link's torque (m.l when it is exact)
        f.add(("parked_palms",), "every empty palm swings on to its front stop",
              push * ca.sin(f.th_lo) - torque, push, kind=VALIDITY)


