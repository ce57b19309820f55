"""The manipulators' yield by statistical linearisation (first-order reliability, RSS).

Every condition the closed-form yield map judges (tolerances/manipulators.py: lift-off, slip,
tip and stall at the back stop, over the top, the handover's lift-off, slip and tip, the next
palm met, the landing's stick and tip) is a row g_i(x, d) >= 0 of the design x and the build's
deviations d (every part's pivot, link length, back stop and palm mass, the lot's friction,
object mass and width, feed place and speed). Linearised at d = 0,
    g_i(x, d) ~ g_i(x, 0) + J_i(x) d,   d ~ N(0, Sigma)  (sigma = t / 3 normal, t / sqrt 3 uniform)
so the row fails with probability Phi(-beta_i), beta_i = g_i / sqrt(J_i Sigma J_i^T) (exact for
a row linear in normal deviations), and the yield is at least 1 - sum_i Phi(-beta_i) (the
union bound: exact for one row, conservative for several).

The row is a chain of stages: stage k reads the state s_k = (u_k, o_k) (landing speed and
place on palm k), the parts of palms k and k + 1 and the lot. Linearised,
    ds_{k+1} = A ds_k + B_k e_k + B_{k+1} e_{k+1} + B_L e_lot,
and each part's deviation e_k is independent of every other part's, so ds_k is carried as
rest (independent of e_k, the later parts and the lot: covariance R), a coefficient C on e_k
and one L on the lot; one stage is
    R' = A R A^T + (A C + B_k) S_e (A C + B_k)^T,   C' = B_{k+1},   L' = A L + B_L
and a row's variance Gs R Gs^T + |(Gs C + G_k) S_e^1/2|^2 + |G_{k+1} S_e^1/2|^2
+ |(Gs L + G_L) S_L^1/2|^2: exact first-order covariance in O(stages), each stage a small
CasADi Function (built once) of the design, iterated (chain_moments.ChainPieces), so the
yield is a smooth function of the design for IPOPT, one node of its NLP at any row length.
A quantity toleranced per lot that is a part's (every link alike, say) is a lot deviation
added to every part.

The landing place's drift along the row is partly second order (the concave handover map's
r(delta), docs/optimizer.md section 4, which the worst case accumulates linearly): it enters
as every stage's second-order mean tr(H Sz)/2 and the quadratic term's spread
tr((H Sz)^2)/2. Left out: the parked palms' clearance (held, not a drift: the NLP's nominal
row keeps it) and the correlation of neighbouring stages' quadratic terms. A slip is not counted
(SURVIVED: the map hands it to the event simulator, which carries the object on: on the long
row 99.66 % of builds complete where 78 % slip on the map); a lift-off, a tip, a stall, a
palm in the way and a miss are (docs/optimizer.md section 10).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ....formulation import chain_moments
from ....formulation.chain_moments import nines
from .. import physics as phys

PARTS = ("pivot_x", "pivot_y", "link_length", "back_stop", "palm_mass")
LOTS = ("friction", "object_mass", "object_width", "feed_x", "feed_speed") + tuple(
    f"{q}_lot" for q in PARTS)
DESIGN = ("alpha", "beta", "link_length", "mass_ratio", "first_pivot_x", "first_pivot_y")
# Failures the event simulator carries on from (the map leaves them to it): not counted.
SURVIVED = ("slip",)
# Angles inside a carry on real links or pivots where its rows are taken too (Chain._inside)
INSIDE = 3


def sigmas(tolerances, scale=1.0):
    """(sigma of each part quantity (5,), sigma of each lot quantity (10,)) as lists of
    floats or SX (scale: a common factor, a number or a symbol) from the tolerances."""
    return chain_moments.sigmas(tolerances, PARTS, LOTS, scale)


class Chain:
    """The linearised stage maps of one scene (design symbols DESIGN, as a vector). active:
    (part mask, lot mask) of the deviations the maps are linearised in (chain_moments.active:
    those of a sigma other than 0), every one by default."""

    def __init__(self, scene, active=None):
        self.scene = scene
        self.active = active if active is not None else ((True,) * len(PARTS),
                                                          (True,) * len(LOTS))
        self.x = ca.SX.sym("design", len(DESIGN))
        self.ek, self.ek1 = ca.SX.sym("e_k", len(PARTS)), ca.SX.sym("e_k1", len(PARTS))
        self.el = ca.SX.sym("e_lot", len(LOTS))
        self.s = ca.SX.sym("s", 2)
        self.first = self._linearised(*self._first())
        self.middle = self._linearised(*self._stage(last=False))
        self.last = self._linearised(*self._stage(last=True))

    # -- the physics: the map of tolerances/manipulators.py, one build, symbols ---------------
    def _design(self):
        a, b, l, q, fpx, fpy = (self.x[i] for i in range(len(DESIGN)))
        return a, b, l, q, fpx, fpy

    def _part(self, e, offset):
        """Palm values (pivot x, y, link, stop, mass) with deviations e (+ the lot's)."""
        a, _, l, q, _, _ = self._design()
        lot = self.el[5:10]
        d = [e[i] + lot[i] for i in range(len(PARTS))]
        return (offset[0] + d[0], offset[1] + d[1], l + d[2], a + d[3],
                self.scene.body.mass / q + d[4])

    def _lot(self):
        body, palm = self.scene.body, self.scene.palm
        e = self.el
        return palm.friction + e[0], body.mass + e[1], body.width + e[2]

    def _terms(self, m, mk, lk):
        """(q_e, g_e, f) of a palm of mass mk on links of length lk carrying the object of mass
        m (physics.carry_terms: a build's links as the simulator's, their inertia scaling with
        the link as a rod's); (m / mk, g, 0) on the paper's device."""
        scene = self.scene
        if scene.plain_mechanism:
            return m / mk, scene.gravity, 0.0
        l = self._design()[2]
        return phys.carry_terms(m / mk, object_mass=m, gravity=scene.gravity, link_length=lk,
                                **scene.mechanism(length_scale=lk / l))

    def _first(self):
        """Rows of the first landing and the state on palm 1."""
        scene, g = self.scene, self.scene.gravity
        a, b, l, q, fpx, fpy = self._design()
        px, py, lk, ak, mk = self._part(self.ek, (fpx, fpy))
        mu, m, w = self._lot()
        (x0, y0), (vx, vy) = scene.initial.position, scene.initial.velocity
        speed = math.hypot(vx, vy)
        ux, uy = (vx / speed, vy / speed) if speed > 0.0 else (1.0, 0.0)
        feed = speed + self.el[4]
        vx0, vy0 = feed * ux, feed * uy
        cx, cy = phys.palm_centre(px, py, -ak, lk)
        fall = y0 - cy
        rows = [("blocked", fall / l)]
        fall_speed = ca.sqrt(vy0**2 + 2.0 * g * fall)
        o = x0 + self.el[3] + vx0 * (vy0 + fall_speed) / g - cx
        rows += self._meets(o, w)
        u, landing = self._land(vx0, -fall_speed, o, ak, self._terms(m, mk, lk)[0], mu, w)
        return rows + landing, ca.vertcat(u, o), [self.x, self.ek, self.el]

    def _meets(self, o, w):
        reach = 0.5 * (w + self.scene.palm.width)
        return [("fell_clear", reach - o), ("fell_clear", reach + o)]

    def _tips(self, point, o, w):
        half_palm = 0.5 * self.scene.palm.width
        return [("tip", e) for e in (0.5 * w - point, half_palm - o - point, point + 0.5 * w,
                                     point + half_palm + o)]

    def _land(self, vx, vy, o, a, q, mu, w):
        u = phys.landing_speed(vx, vy, a, q)
        px, py = phys.landing_impulse(vx, vy, a, q)
        h = self.scene.body.height
        return u, [("stall", u / ca.sqrt(vx**2 + vy**2)), ("slip", mu * py - px),
                   ("slip", mu * py + px), *self._tips(-0.5 * h * px / py, o, w)]

    def _carry_rows(self, u2, theta, o, mu, w, l, terms):
        """Lift-off, tip and slip of the stuck object at theta moving at u2 (= v^2) on links of
        length l, the carry's terms (q_e, g_e, f) (physics: the palm's force with its
        tangential part A on real links or pivots, none on the paper's device)."""
        g, h = self.scene.gravity, self.scene.body.height
        if self.scene.plain_mechanism:
            return [("lift_off", phys.lift_off_capacity(theta, gravity=g, link_length=l) - u2),
                    *self._tips(phys.carry_force_point(theta, h), o, w),
                    ("slip", mu - ca.tan(theta)), ("slip", mu + ca.tan(theta))]
        along = phys.carry_along(theta, gravity=g, carry_gravity=terms[1], friction=terms[2],
                                 link_length=l)
        ratio = phys.carry_force_ratio(theta, u2, gravity=g, link_length=l, along=along)
        held = phys.lift_off_capacity(theta, gravity=g, link_length=l, along=along)
        return [("lift_off", held - u2), *self._tips(phys.carry_force_point(theta, h, ratio), o, w),
                ("slip", mu - ratio), ("slip", mu + ratio)]

    def _inside(self, u, ak, theta, o, mu, w, lk, terms):
        """The carry's rows at INSIDE angles evenly between its ends (real links or pivots,
        where they need not be least at the ends: docs/physics.md section 2.1)."""
        if self.scene.plain_mechanism:
            return []
        out = []
        for i in range(1, INSIDE + 1):
            th = -ak + i * (theta + ak) / (INSIDE + 1)
            v2 = phys.carry_speed_squared(u, ak, th, gravity=terms[1], link_length=lk,
                                          friction=terms[2])
            out += self._carry_rows(v2, th, o, mu, w, lk, terms)
        return out

    def _stage(self, last: bool):
        """Rows of the carry on palm k (and the handover to k + 1, the landing on it)."""
        a, b, l, q, _, _ = self._design()
        u, o = self.s[0], self.s[1]
        px, py, lk, ak, mk = self._part(self.ek, (0.0, 0.0))
        mu, m, w = self._lot()
        terms = self._terms(m, mk, lk)
        _, g_e, f = terms
        rows = self._carry_rows(u**2, -ak, o, mu, w, lk, terms)
        rows.append(("stall", u**2 - phys.top_speed_squared_needed(ak, gravity=g_e,
                                                                   link_length=lk, friction=f)))
        inputs = [self.x, self.s, self.ek, self.el]
        if last:
            theta = b
        else:
            pitch_x, pitch_y = phys.pitch(a, b, l)
            qx, qy, lk1, ak1, mk1 = self._part(self.ek1, (pitch_x, -pitch_y))
            nx, ny = phys.palm_centre(qx, qy, -ak1, lk1)
            rows.append(("blocked", (py + lk * ca.cos(ak) - ny) / l))
            theta = ca.acos((ny - py) / lk)
            inputs.insert(3, self.ek1)
        rows.append(("stranded", self.scene.palm.front_stop - theta))
        v2 = phys.carry_speed_squared(u, ak, theta, gravity=g_e, link_length=lk, friction=f)
        rows += self._inside(u, ak, theta, o, mu, w, lk, terms)
        rows += self._carry_rows(v2, theta, o, mu, w, lk, terms)
        if last:
            return rows, None, inputs
        o_next = px + o + lk * ca.sin(theta) - nx
        rows += self._meets(o_next, w)
        v = ca.sqrt(v2)
        u_next, landing = self._land(v * ca.cos(theta), -v * ca.sin(theta), o_next, ak1,
                                     self._terms(m, mk1, lk1)[0], mu, w)
        return rows + landing, ca.vertcat(u_next, o_next), inputs

    # -- linearised at zero deviation, with the second-order mean -------------------------
    def _linearised(self, rows, state, inputs):
        """Function (x, s, Sz) -> (g + tr(H Sz) / 2, dg/dz, tr((H Sz)^2) / 2 of each row[,
        s' + tr(H Sz) / 2, ds'/dz, tr(H_a Sz H_b Sz) / 2 of the state's two]) at e = 0,
        z = (s, e_k, e_k1, e_lot), Sz the covariance of z (chain_moments.linearise)."""
        return chain_moments.linearise(rows, state, self.x, self.s, self.ek, self.ek1, self.el,
                                       *self.active)


def counted(names) -> ca.DM:
    """1 for the rows whose failure ends a run (every one but SURVIVED), else 0."""
    return ca.DM([0.0 if n in SURVIVED else 1.0 for n in names])


def failure_bound(g, sd, names):
    """sum_i Phi(-beta_i) over the counted rows, beta_i = g_i / sd_i (a row of no spread: 0
    if it holds, else 1)."""
    return chain_moments.failure_bound(g, sd, counted(names))


def design_vector(values: dict):
    """The DESIGN vector from a design's values (by name; first pivot 0 when left out)."""
    return ca.vertcat(*[values.get(n, 0.0) for n in DESIGN])


_ROWS: dict = {}  # (scene, stages, active) -> (rows Function, names, ChainPieces, Chain)


def kept(each, lot):
    """((part mask, lot mask), the part sigmas kept, the lot sigmas kept): the deviations of
    a sigma other than 0 (chain_moments.active), which the chain's Functions take."""
    active = (chain_moments.active(each), chain_moments.active(lot))
    return active, [s for s, a in zip(each, active[0]) if a], \
        [s for s, a in zip(lot, active[1]) if a]


def rows_function(scene, stages: int, active):
    """(Function (design vector, kept part sigmas, kept lot sigmas) -> (g, sd) of every row of
    a row of `stages` palms, their names): the first landing, stages - 1 calls of the middle
    stage iterated (chain_moments.chain_function: one graph at any number of stages) and the
    last palm's; built once, cached. active: `kept`'s masks."""
    return _functions(scene, stages, active)[:2]


def _functions(scene, stages: int, active):
    key = (repr(scene), stages, active)
    if key not in _ROWS:
        chain = Chain(scene, active)
        pieces = chain_moments.ChainPieces(chain.first, chain.middle, stages, len(DESIGN),
                                           sum(active[0]), sum(active[1]), last=chain.last)
        if len(_ROWS) >= CACHED:
            _ROWS.clear()
        _ROWS[key] = (pieces.rows_function(), pieces.names, pieces, chain)
    return _ROWS[key]


CACHED = 4  # chains kept (a spec's NLP and its checks share one)


def union_bound(scene, values: dict, stages: int, each, lot, reduce=None):
    """The union bound of a row of `stages` palms at the design `values` (by name, numbers or
    SX) and the part and lot sigmas `each`, `lot` (lists of numbers or SX): one node of an SX
    graph with its value, gradient and Hessian in the free symbols (chain_moments.
    second_order_term), the same size at any number of stages. reduce: (g, sd, counted) -> the
    node's value, chain_moments.failure_bound unless given (union_nines: its nines)."""
    active, each, lot = kept(each, lot)
    _, names, pieces, _ = _functions(scene, stages, active)
    mask, reduce = counted(names), reduce or chain_moments.failure_bound
    return chain_moments.second_order_term(
        pieces, lambda g, sd: reduce(g, sd, mask),
        [design_vector(values), ca.vertcat(*each), ca.vertcat(*lot)])


def yield_term(scene, values: dict, tolerances, stages: int, scale=1.0):
    """The max_yield objective term: nines of the linearised yield's union bound."""
    each, lot = sigmas(tolerances, scale)
    return nines(union_bound(scene, values, stages, each, lot))


def row_reliability(scene, design, tolerances, stages: int):
    """(g, sd, names) of every row of a fixed design (scenes.ManipulatorsDesign) as numpy arrays:
    each row's mean (second order) and standard deviation (first order and its quadratic
    term's), the rows of the first landing and then stage by stage."""
    active, each, lot = kept(*sigmas(tolerances))
    x = [float(getattr(design, n)) for n in DESIGN]
    fn, names = rows_function(scene, stages, active)
    g, sd = fn(x, each, lot)
    return np.asarray(g).ravel(), np.asarray(sd).ravel(), names


def linearised_yield(scene, design, tolerances, stages: int) -> dict:
    """The linearised yield of a fixed design: the union bound's yield, the failure bound, the
    smallest reliability index and the row count, as numbers."""
    g, sd, names = row_reliability(scene, design, tolerances, stages)
    return chain_moments.summary(g, sd, np.asarray(counted(names)).ravel() > 0.0)


def placed_rows(scene, design, tolerances, stages: int):
    """The rows of the linearised yield placed along the row (plugin_tolerances.PlacedRows):
    place 0 is the first landing, k palm k (the carry on palm k, the handover to and the
    landing on k + 1); slips not counted in the union bound."""
    from ....plugin_tolerances import PlacedRows

    g, sd, names = row_reliability(scene, design, tolerances, stages)
    chain = _functions(scene, stages, kept(*sigmas(tolerances))[0])[3]
    sizes = [len(chain.first[1])] + [len(chain.middle[1])] * (stages - 1) + [len(chain.last[1])]
    return PlacedRows(g, sd, names, np.asarray(counted(names)).ravel(),
                      np.repeat(np.arange(len(sizes)), sizes),
                      ("palm", "palms", "the first landing"))
