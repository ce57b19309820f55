"""The manipulators NLP's rows, one function per group (formulation/manipulators/__init__.py's
module docstring and docs/optimizer.md sections 4 and 4a derive each bound).

`Frame` holds what every group shares over the box {quantity: half-width}: the handover
angles' and the fall speed's ends, the back stops' ends, the sizes and the rows written so far.
The groups run in a fixed order (`conditions`): the periodic orbit and the speed interval, the
validity of the closed forms, the carry, the landing place (with the parked palms and the tip
during the carry), and the impacts.
"""

from __future__ import annotations

import itertools
import math

import casadi as ca

from ....formulation.common import MARGIN, MODEL, VALIDITY, Condition, fmax_all, fmin_all
from .. import physics as phys
from . import carry_box, links

START_CLEARANCE = 1e-3  # (x link length): the object starts at least this far above palm 1
# Margins whose periodic and first_ versions are one row (the speed interval covers both): the
# larger of their two requirements holds both.
OVER_THE_TOP = ("over_the_top", "first_over_the_top")
LIFT_OFF = ("lift_off", "first_lift_off")
ACOS_EDGE = 1e-15  # acos is taken of at most 1 - this: a finite slope
MASS_KEPT = 1e-3  # a mass tolerance leaves at least this fraction of the mass
CARRY_CELLS = phys.CARRY_CELLS  # cells of the carry's angle range (`_inside_rows`)


def conditions(m, S, u_lo, u_hi, box, robust) -> list[Condition]:
    """Every condition of model m (manipulators._Model) over the box {quantity: half-width}
    (pivot_x, pivot_y, feed_x, friction, object_width; a quantity left out is exact)."""
    f = Frame(m, S, u_lo, u_hi, box, robust)
    model_rows(m, f)
    validity_rows(m, f)
    carry_rows(m, f)
    placement_rows(m, f)
    impact_conditions(m, f)
    return f.out


class Frame:
    """What the groups of rows share: the box's ends of each quantity they bound, and `add`."""

    def __init__(self, m, S, u_lo, u_hi, box, robust):
        a, b, l = m.a, m.b, m.l
        body, palm = m.scene.body, m.scene.palm
        self.S, self.u_lo, self.u_hi, self.box, self.robust = S, u_lo, u_hi, box, robust
        tau = box.get("pivot_y", 0.0)  # the pivot heights: handover angles, fall, clearance
        t_w = box.get("object_width", 0.0)
        # every row is increasing in the friction (the stick rows: py > 0) and monotone in the
        # width (wider: lands less fully on the palm, tips less over its own edges)
        self.mu, self.W, self.h = palm.friction - box.get("friction", 0.0), palm.width, body.height
        self.w, self.w_lo = body.width + t_w, body.width - t_w
        self.tau, self.out, self.inside, self.g = tau, [], [], m.g
        a_lo, a_hi = m.stops(box)
        stopped = a_lo is not a_hi
        # palm K + 1's rest raises the handover by cos a_K+1 - cos a (its stop), the pivots by
        # their heights' difference; palm 1's top by its pivot's and its stop's error
        d_lo, d_hi = ((0.0, 0.0) if not stopped else
                      (ca.cos(a_hi) - ca.cos(a), ca.cos(a_lo) - ca.cos(a)))
        raise_lo, raise_hi = (-tau, tau) if not stopped else (-tau + l * d_lo, tau + l * d_hi)
        # the links' lengths (links.py): palm 1's top, the handover and the carry
        # move with them (and the stops, with both: a links.Rest)
        self.l_lo, self.l_hi = links.ends(m, box)
        self.linked, self.t_l = self.l_lo is not self.l_hi, box.get("link_length", 0.0)
        if self.linked:
            self.rest = links.Rest(m, self.t_l, (a_lo, a_hi))
            raise_lo, raise_hi = -tau + self.rest.q_lo, tau + self.rest.q_hi
        if robust:
            cm, cp = ca.cos(b) - 2 * tau / l, ca.cos(b) + 2 * tau / l
            if stopped:
                cm, cp = cm + d_lo, cp + d_hi
            if self.linked:
                cm, cp = self.rest.handover_cosines(tau)
            # a number wherever IPOPT may step: its push of tau off 0 (1 cm, say) can take
            # cos b + 2 tau / l past 1 where the handover drop l (1 - cos b) / 2 is smaller
            # (every start Invalid_Number_Detected); the palm_clearance row keeps the feasible
            # set inside, so the clip changes no answer
            edge = 1.0 - ACOS_EDGE
            th_hi, th_lo = ca.acos(ca.fmax(cm, -edge)), ca.acos(ca.fmin(cp, edge))
            thetas = [("smallest handover angle", th_lo), ("largest handover angle", th_hi)]
            Qs = [("palm 1 high", m.fall_speed(raise_hi)),
                  ("palm 1 low", m.fall_speed(raise_lo))]
        else:
            th_hi = th_lo = b
            thetas = [("at beta", b)]
            Qs = [("", m.fall_speed(0.0))]
        self.a_lo, self.a_hi, self.stopped, self.d_lo, self.d_hi = a_lo, a_hi, stopped, d_lo, d_hi
        self.raise_hi, self.th_lo, self.th_hi, self.thetas, self.Qs = (
            raise_hi, th_lo, th_hi, thetas, Qs)
        self.Q_hi = Qs[-1][1]

    def add(self, keys, where, slack, scale=1.0, kind=MARGIN, **kw):
        self.out.append(Condition(tuple(keys) if isinstance(keys, (tuple, list)) else (keys,),
                                  where, slack, scale, kind, **kw))


def model_rows(m, f):
    """The periodic fixed point and the invariant interval of landing speeds (sets f.speeds,
    f.qs: the feed speeds and mass ratios the box allows, and f.u1_lo, the slowest first
    landing)."""
    a, b, l, g, S, add = m.a, m.b, m.l, m.g, f.S, f.add
    if m.steps:  # integrated: S is v(b)^2 after landing at k sqrt(S) cos(a + b)
        u_star = m.k * ca.sqrt(ca.fmax(S, 0.0)) * ca.cos(a + b)
        add((), "periodic handover speed: S = v(beta)^2 (integrated)",
            m.carry_v2(u_star, b) - S, kind=MODEL, equality=True)
    else:
        add((), "periodic handover speed: S (1 - c) = D", S * (1 - m.c) - m.D,
            kind=MODEL, equality=True)
    speeds = f.speeds = m.feed_speeds(box := f.box)  # u_1 increases with them and the mass ratio
    f.terms = carry_box.terms(m, box)  # the ends of q_e, g_e and f over the box
    qs = f.qs = f.terms.q
    # u_1 = k (vx cos a_1 - Q sin a_1): decreasing in a_1 in [0, pi/2) for vx >= 0
    f.u1_lo = m.first_speed(f.Q_hi, speeds[0], qs[0], f.a_hi)
    u1_hi = m.first_speed(f.Qs[0][1], speeds[-1], qs[-1], f.a_lo)
    # The interval rows keep the backoff in speed units (sqrt(g l)): without it, an
    # interval met only to IPOPT's tolerance let the first landing stall 1e-4 rad short of
    # the top in 3 of 900 random specs; in m/s it would be a size-dependent 1e-6 m/s.
    model = {"kind": MODEL, "backoff_unit": ca.sqrt(g * l)}
    add((), "interval holds the first landing speed (low)", f.u1_lo - f.u_lo, **model)
    add((), "interval holds the first landing speed (high)", f.u_hi - u1_hi, **model)
    if f.robust:
        _robust_interval_rows(m, f, model)
    else:
        add((), "interval invariant (low)", m.next_speed(f.u_lo, b) - f.u_lo, **model)
        add((), "interval invariant (high)", f.u_hi - m.next_speed(f.u_hi, b), **model)


def _robust_interval_rows(m, f, model):
    """The interval [u_lo, u_hi] mapped into itself over the handover angles' range."""
    b, add, qs, u_lo, u_hi = m.b, f.add, f.qs, f.u_lo, f.u_hi
    th_lo, th_hi, a_lo, a_hi, thetas = f.th_lo, f.th_hi, f.a_lo, f.a_hi, f.thetas
    # Curvature bound of ln F(u, th) on the whole interval, for every u (docs/optimizer.md):
    # d2 ln F / d th2 = -sec^2(a + th) + (y cos th - y^2 sin^2 th) / 2 with y = 2 g l / v^2
    # <= cot^2(th_lo) / 8 - sec^2(a + th_lo) =: M; M+ = smooth max(M, 0) >= max(M, 0).
    # (with pivot friction f: cot th_lo becomes cos th_lo / (sin th_lo - f / (g l)),
    # the same maximum over 1 / v^2 of g l cos th / v^2 - 2 (g l sin th - f)^2 / v^4)
    # F increases with g_e and decreases with f (masses, links, pivot friction toleranced:
    # docs/optimizer.md 4a): the low rows take the slowest carry, the high rows the fastest,
    # each with its own curvature bound (m itself for both when they are exact)
    low, high = f.terms.low(m), f.terms.high(m)
    # (the shortest link's: f / (g_e l) is largest there, the bound with it; l-free otherwise)
    leans = {id(v): ca.sin(th_lo) if phys.is_exact_zero(v.f) else (
        ca.sin(th_lo) - v.f / (v.gc * f.l_lo)) for v in (low, high)}

    def curvature(stop, v=low):  # the landing palm's stop angle enters the sec^2 term only
        bound = (ca.cos(th_lo) / leans[id(v)]) ** 2 / 8 - 1 / ca.cos(stop + th_lo) ** 2
        return (bound + ca.sqrt(bound**2 + 1e-12)) / 2

    # F is decreasing in both palms' stop angles (the carry's start, the landing's
    # angle) and increasing in the carrying palm's link (th >= a): the low rows take a_hi
    # and l_lo, the high rows a_lo and l_hi (docs/optimizer.md 4a)
    curv = curvature(a_hi)
    # Low end: ln F >= chord - M+ (th - th_lo)(th_hi - th) / 2 >= min over the ends
    # - M+ (th_hi - th_lo)^2 / 8.
    sag = ca.exp(-curv * (th_hi - th_lo) ** 2 / 8)
    for where, th in thetas:
        add((), f"interval invariant (low, {where})",
            low.next_speed(u_lo, th, qs[0], a_hi, f.l_lo) * sag - u_lo, **model)
    # High end: ln F <= ln F(b) + lambda (th - b) + M+ (th - b)^2 / 2 (Taylor), convex in
    # th so largest at an end; lambda = d ln F / d th at b by CasADi AD.
    th_s = ca.SX.sym("th")
    dlog = ca.substitute(ca.jacobian(ca.log(high.next_speed(u_hi, th_s, a=a_lo, l=f.l_hi)),
                                     th_s), th_s, b)
    u_b = high.next_speed(u_hi, b, qs[-1], a_lo, f.l_hi)  # ln F's th-derivatives are free of q
    curv = curvature(a_lo, high) if f.stopped or high is not low else curv
    for where, th in thetas:
        bound = u_b * ca.exp(dlog * (th - b) + curv * (th - b) ** 2 / 2)
        add((), f"interval invariant (high, {where})", u_hi - bound, **model)


def validity_rows(m, f):
    """Validity of the closed forms: forward landings, the start above palm 1, the box's
    pivot places, back stops and masses, gravity beating the pivot friction."""
    l, g, add, box, tau, speeds = m.l, m.g, f.add, f.box, f.tau, f.speeds
    a_lo, a_hi, th_hi = f.a_lo, f.a_hi, f.th_hi
    add(("forward_landing",), "first landing moves the palm forward", f.u1_lo,
        scale=m.k * ca.sqrt(speeds[0]**2 + f.Q_hi**2), kind=VALIDITY)
    add(("forward_landing",), "handover moves the next palm forward",
        phys.landing_speed(ca.cos(th_hi), -ca.sin(th_hi), a_hi, m.q), scale=m.k,
        kind=VALIDITY)
    add(("start_height",), "",
        m.H - f.raise_hi - START_CLEARANCE * l, scale=l, kind=VALIDITY)
    t_x = box.get("pivot_x", 0.0)
    if t_x is not tau and nonzero(t_x):  # the parked palms' count assumes 2 t_x <= l
        add(("palm_clearance",), "pivots' places within half a link", l - 2 * t_x, l,
            kind=VALIDITY)
    if f.linked:  # the parked palms' count takes 2 t_l <= l
        add(("link_length_range",), "every link at least half its length",
            l - 2 * f.t_l, l, kind=VALIDITY)
    if f.stopped:  # the bounds take the stops in [0, pi/2) and a start moving forward
        add(("back_stop_range",), "every back stop at or behind the vertical", a_lo, 1.0,
            kind=VALIDITY)
        add(("forward_landing",), "the start moves forward", speeds[0],
            ca.sqrt(g * l), kind=VALIDITY)
    m_obj = m.scene.body.mass
    for name, mass, t_mass in (("object", m_obj, box.get("object_mass", 0.0)),
                               ("every palm", m_obj / m.mass_ratio,
                                box.get("palm_mass", 0.0))):
        if nonzero(t_mass):  # a build with no mass is none: the mass ratio's ends hold
            add(("positive_mass",), f"{name} keeps a mass within its tolerance",
                (1.0 - MASS_KEPT) * mass - t_mass, mass, kind=VALIDITY)
    g_lo, f_hi = f.terms.g[0], f.terms.f[-1]  # m.gc and m.f when they are exact
    if f.robust and not phys.is_exact_zero(f_hi):
        add(("over_the_top",), "gravity beats the pivot friction at the handover",
            g_lo * f.l_lo * ca.sin(f.th_lo) - f_hi, g_lo * l, kind=VALIDITY)
    carry_box.validity_rows(m, f)


def carry_rows(m, f):
    """Carry conditions on every palm (the first included: u_lo <= u_1 <= u_hi), the next
    palm's clearance and the front stop (sets f.fp_back, f.fp_front: the force points)."""
    b, l, add, u_lo, palm = m.b, m.l, f.add, f.u_lo, m.scene.palm
    if m.steps:  # integrated: the slowest point of the slowest carry is still moving
        add(OVER_THE_TOP, "slowest landing on any palm, slowest point (integrated)",
            m.carry_v2(u_lo, b, lowest=True)[1], u_lo**2)
    else:
        tops = _top_needs(m, f)
        for i, top in enumerate(tops):
            add(OVER_THE_TOP, version("slowest landing on any palm", i, tops),
                u_lo**2 - top, u_lo**2)
    f.fp_back, f.fp_front = (_plain_contact_rows if m.plain else _contact_rows)(m, f)
    # the object's base stays above palm K + 1 while cos th_K <= cos a_K
    clearance = m.pitch_y if not f.stopped else l * (f.d_lo - f.d_hi) + m.pitch_y
    if f.linked:  # palm K + 1's top q_hi higher, the object's start on palm K q_lo
        clearance = m.pitch_y + f.rest.q_lo - f.rest.q_hi
    add("palm_clearance", "next palm below the object until the handover",
        clearance - 2 * f.tau, l, epigraph=False)
    if palm.front_stop < math.pi / 2:
        add("front_stop", "largest handover angle before the front stop",
            palm.front_stop - f.th_hi, palm.front_stop, epigraph=False)


def _top_needs(m, f):
    """The over-the-top need's versions: max over th of 2 g_e l_K (cos th - cos a) + 2 f (th +
    a), a maximum of functions affine in (g_e l_K, f), so convex in them, increasing in f and
    in a: at a_hi, f hi and each end of g_e l_K (g_e and l_K > 0: (g_e lo, l_lo), (g_e hi,
    l_hi)); one version, at l_hi, where f = 0 (the need then increases with g_e l_K)."""
    frictionless = phys.is_exact_zero(m.f) and not f.terms.carry_varies
    if not f.terms.carry_varies and (frictionless or not f.linked):
        return [m.top_needed if not (f.stopped or f.linked) else phys.top_speed_squared_needed(
            f.a_hi, gravity=m.gc, link_length=f.l_hi, friction=m.f)]
    g = f.terms.g
    pairs = [(g[0], f.l_lo), (g[-1], f.l_hi)] if f.linked else [(g_e, m.l) for g_e in g]
    return [phys.top_speed_squared_needed(f.a_hi, gravity=g_e, link_length=length,
                                          friction=f.terms.f[-1]) for g_e, length in pairs]


def _plain_contact_rows(m, f):
    """Lift-off and slip during the carry on the paper's device; (fp_back, fp_front)."""
    g, add, mu, h, a_hi, th_hi = m.g, f.add, f.mu, f.h, f.a_hi, f.th_hi
    held = phys.lift_off_capacity(a_hi, gravity=g, link_length=f.l_lo)
    add(LIFT_OFF, "at the back stop, fastest landing",
        held - f.u_hi**2, held)
    if f.linked:  # held - v2 = 3 g (l cos b + z) - 2 g l_K cos a_K - u^2 with l_K cos th_K =
        # l cos b + z_K (links.py): least at z_lo and l_K cos a_K = l cos a + q_hi
        lowest = m.l * ca.cos(m.b) + f.rest.z_range(f.tau)[0]
        held = g * lowest
        v2 = f.u_hi**2 + 2 * g * (m.l * ca.cos(m.a) + f.rest.q_hi - lowest)
    else:
        v2 = m.carry_v2(f.u_hi, th_hi, a=f.a_lo)
        held = phys.lift_off_capacity(th_hi, gravity=g, link_length=m.l)
    add(LIFT_OFF, "at the handover, fastest carry", held - v2, held)
    add("slip_carry", "at the back stop", mu - phys.friction_demand(a_hi), mu)
    add("slip_carry", "at the largest handover angle",
        mu - phys.friction_demand(th_hi), mu)
    return phys.carry_force_point(-a_hi, h), -phys.carry_force_point(th_hi, h)


def _contact_rows(m, f):
    """Lift-off and slip during the carry on real links or pivots, where the contact force's
    tangential part depends on the speed: both ends of each; (fp_back, fp_front). With the
    carry's g_e and f over a box (carry_box), at every vertex of it: the normal force and the
    friction are affine in (g_e, f, v^2), so each lift-off row is least at a vertex and the
    friction / normal ratio, linear-fractional with a positive denominator, is extreme at one."""
    a, l, g, add, mu, h = m.a, m.l, m.g, f.add, f.mu, f.h
    u_lo, u_hi, th_lo, th_hi = f.u_lo, f.u_hi, f.th_lo, f.th_hi
    back, front, f.inside = [], [], []
    # the links' lengths (stops exact: allocation._check_links): N and F are affine in
    # (u^2 / l_K, 1 / l_K) at fixed (g_e, f) (v^2 / l_K = u^2 / l_K + 2 g_e (cos a - cos th)
    # - 2 f (a + th) / l_K), each (u^2, l_K) end a vertex of that trapezoid: at both links
    lengths = [(None, "")] if not f.linked else [(f.l_lo, "link short"), (f.l_hi, "link long")]
    for (corner, v), (link, lw) in itertools.product(f.terms.corners(m), lengths):
        corner = join(corner, lw)
        if f.stopped:  # over every stop angle in [a_lo, a_hi]: bounds (carry_box.back_contact)
            held, ratios = carry_box.back_contact(m, f, v, u_lo**2, u_hi**2)
            add(LIFT_OFF, join("at every back stop, fastest landing", corner), held, g * l)
        else:
            add(LIFT_OFF, join("at the back stop, fastest landing", corner),
                v.contact(-a, u_hi**2, link)[0] - u_hi**2, g * l)
            ratios = v.carry_ratios([(-a, u_lo**2), (-a, u_hi**2)], link)
        v2 = v.carry_v2(u_hi, th_hi, a=f.a_lo, l=link)
        add(LIFT_OFF, join("at the handover, fastest carry", corner),
            v.contact(th_hi, v2, link)[0] - v2, g * l)
        back += ratios
        # the slowest carry from the highest stop, the fastest from the lowest: v^2's ends
        front += v.carry_ratios([(th, v.carry_v2(u, th, a=stop, l=link))
                                 for th in (th_lo, th_hi)
                                 for u, stop in ((u_lo, f.a_hi), (u_hi, f.a_lo))], link)
        f.inside += _inside_rows(m, f, v, link, corner)
    for i, r in enumerate(back + front):
        add("slip_carry", version("at the ends of the carry", i, back + front),
            mu - phys.friction_demand(None, r), mu)
    return (fmax_all([phys.carry_force_point(-a, h, r) for r in back]),
            fmax_all([-phys.carry_force_point(None, h, r) for r in front]))


def _inside_rows(m, f, v, link, corner):
    """Lift-off and slip over the whole carry on real links or pivots, at one vertex of the
    carry's terms (the model view v) and link (None: the design's); the carries' nodes for the
    tip rows (placement_rows). Every build's carry lies in th in [-a_hi, th_hi] with v^2
    between the slowest carry's (u_lo from a_hi) and the fastest's (u_hi from a_lo: v^2
    decreases in the stop); at a fixed angle each row, a combination c1 N + c2 F >= 0, is
    affine in v^2, so least on one of those two carries. Along each, N and F have |d2/dth2| <=
    S (physics.carry_contact_curvature): on each of CARRY_CELLS cells the row is at least
    `cell_least` of its ends' values (docs/physics.md section 2.1). None with pivot damping
    (no closed-form carry)."""
    if nonzero(m.delta):
        return []
    l, g, mu = m.l if link is None else link, m.g, f.mu
    out = []
    for u, stop, speed in ((f.u_lo, f.a_hi, "slowest"), (f.u_hi, f.a_lo, "fastest")):
        nodes, bend = phys.carry_contact_nodes(
            u, stop, start=f.a_hi, end=f.th_hi, fastest_u2=f.u_hi**2, gravity=g,
            carry_gravity=v.gc, friction=v.f, link_length=l, cells=CARRY_CELLS)
        where = join("during the carry", speed, corner)
        for c1, c2, key, what, scale in (
                (l, 0.0, LIFT_OFF, "", g * l), (mu, -1.0, "slip_carry", "sliding back", mu * g),
                (mu, 1.0, "slip_carry", "sliding forward", mu * g)):
            if key is LIFT_OFF and speed == "slowest":  # N decreases in v^2 (cos th > 0)
                continue
            cells(f, key, join(where, what), nodes, c1, c2, bend, scale)
        out.append((where, nodes, bend))
    return out


def cells(f, key, where, nodes, c1, c2, bend, scale):
    """One row a cell of c1 N + c2 F along the carry's nodes (physics.carry_row_cells)."""
    values = phys.carry_row_cells(nodes, c1, c2, bend)
    for i, value in enumerate(values):
        f.add(key, join(where, f"cell {i + 1} of {len(values)}"), value, scale)


# a lower bound of a row over one cell (physics.carry_cell_least, shared with the analysis
# and the stage maps)
cell_least = phys.carry_cell_least


def _inside_tip_rows(f, o_hi, o_lo):
    """Tip over the whole carry (_inside_rows' carries): the force point -(h/2) F / N within
    d ahead and behind (the object's edges w_lo / 2, the palm's W / 2 -+ o), d N +- (h/2) F
    >= 0 (N > 0: the lift-off rows), a row a cell with |d2/dth2| <= (d + h/2) S."""
    h, g = f.h, f.g
    edges = [(f.w_lo / 2, 1.0, "object's front edge"), (f.w_lo / 2, -1.0, "object's rear edge")]
    edges += [(f.W / 2 - o, 1.0, version("palm's front edge", i, o_hi))
              for i, o in enumerate(o_hi)]
    edges += [(f.W / 2 + o, -1.0, version("palm's rear edge", i, o_lo))
              for i, o in enumerate(o_lo)]
    for where, nodes, bend in f.inside:
        for d, sign, edge in edges:
            cells(f, "tip_carry", join(where, edge), nodes, d, sign * h / 2, bend, d * g)


def placement_rows(m, f):
    """The parked palms, the landing within the palm and the tip during the carry (sets
    f.o1_hi, f.o1_lo, f.o_hi, f.o_lo: the landing offsets' bounds)."""
    l, add, box, tau, palm = m.l, f.add, f.box, f.tau, m.scene.palm
    W, w, w_lo, h, fp_back, fp_front = f.W, f.w, f.w_lo, f.h, f.fp_back, f.fp_front
    (o1_hi, o1_lo), (o_hi, o_lo) = m.landing_ranges(box, f.robust)
    f.o1_hi, f.o1_lo, f.o_hi, f.o_lo = o1_hi, o1_lo, o_hi, o_lo
    # Palms parked at their front stops behind the carrying one stay clear of the object
    # (physics.parked_palm_clearance; each palm's landing offset lies between the smallest
    # of the o_lo versions and the largest of the o_hi ones, each pivot within the box).
    # Deferred: on problems where they do not bind they cost IPOPT 2 of 14 iterations.
    parked = {"alpha": f.a_hi, "theta_end": f.th_hi, "link_length": l,
              "front_stop": palm.front_stop, "pitch_x": m.pitch_x,
              "pitch_y": m.pitch_y, "offset_lo": fmin_all(o_lo),
              "offset_hi": fmax_all(o_hi), "reach": (w + W) / 2,
              "depth": palm.thickness + h, "shift": 2 * larger(tau, box.get("pivot_x", 0.0))}
    if f.linked:  # the parked palm's top and the object's arc each move by at most t_l
        parked["shift"] = parked["shift"] + 2 * f.t_l
    for n in range(1, m.parked + 1):
        add("parked_palms", f"palm {n} back, at its front stop",
            phys.parked_palm_clearance(n, **parked), l, epigraph=False, deferred=True)
    # Landing within the palm: |o| + w/2 <= W/2.
    for i, o in enumerate(o_hi):
        add("landing", version("object furthest ahead", i, o_hi), W / 2 - o - w / 2, W / 2)
    for i, o in enumerate(o_lo):
        add("landing", version("object furthest behind", i, o_lo), W / 2 + o - w / 2, W / 2)
    # Tipping during the carry: the force point within the support (ahead of the centre at
    # the back stop, behind it at the handover).
    add("tip_carry", "at the back stop, object's front edge", w_lo / 2 - fp_back, w_lo / 2)
    for i, o in enumerate(o_hi):
        add("tip_carry", version("at the back stop, palm's front edge", i, o_hi),
            W / 2 - o - fp_back, W / 2 - o)
    add("tip_carry", "at the handover, object's rear edge", w_lo / 2 - fp_front, w_lo / 2)
    for i, o in enumerate(o_lo):
        add("tip_carry", version("at the handover, palm's rear edge", i, o_lo),
            W / 2 + o - fp_front, W / 2 + o)
    _inside_tip_rows(f, o_hi, o_lo)


def impact_conditions(m, f):
    """Impacts: on palms 2.. (velocity along the handover tangent) and the first landing.
    The landing palm's stop angle: each row is a sinusoid in 2 a plus a term free of it,
    of amplitude k |c| / 2 per unit speed (|c| the row's coefficients of the impulse), so
    it lies above the chord between the stops' ends less k |c| (a_hi - a_lo)^2 / 4 / 2
    (docs/optimizer.md section 4a): rows at both ends, less that."""
    a_lo, a_hi, qs, speeds = f.a_lo, f.a_hi, f.qs, f.speeds
    sizes = (f.mu, f.W, f.w, f.w_lo, f.h)
    stop_ends = ends([a_lo, a_hi] if f.stopped else [m.a], "back stop")
    k_max = phys.momentum_fraction(qs[-1])
    sag_a = 0.0 if not f.stopped else k_max * (a_hi - a_lo) ** 2 / 4
    if m.stages >= 2:
        # affine in m / (m + M): at both ends
        for (where, th), (mass, q), (stop, a_k) in itertools.product(
                f.thetas, ends(qs, "mass ratio"), stop_ends):
            px, py = phys.landing_impulse(ca.cos(th), -ca.sin(th), a_k, q)
            impact_rows(f.add, sizes, "slip_impact", "tip_impact",
                        join(where, mass, stop), px, py, f.o_hi, f.o_lo, sag_a)
    # multilinear in (start speed, fall speed, m / (m + M)): each row holds on the box iff
    # at its corners
    sag_1 = 0.0 if not f.stopped else sag_a * ca.sqrt(speeds[-1] ** 2 + f.Q_hi**2)
    for (where, Q), (feed, vx), (mass, q), (stop, a_k) in itertools.product(
            f.Qs, ends(speeds, "feed"), ends(qs, "mass ratio"), stop_ends):
        px, py = phys.landing_impulse(vx, -Q, a_k, q)
        impact_rows(f.add, sizes, "first_slip_impact", "first_tip_impact",
                    join(where, feed, mass, stop), px, py, [f.o1_hi], [f.o1_lo], sag_1)


def scene_sizes(scene):
    """impact_rows' sizes of a scene as specified (no tolerance box)."""
    body, palm = scene.body, scene.palm
    return palm.friction, palm.width, body.width, body.width, body.height


def impact_rows(add, sizes, slip, tip, where, px, py, o_hi, o_lo, sag=0.0):
    """Stick (|px| <= mu py) and no tip (impulse line through the support) at a landing with
    impulse (px, py) and landing offsets o_hi (furthest ahead) and o_lo (furthest behind):
    add(key, where, slack, scale) once per row. sizes: (mu, W, w, w_lo, h), the friction, the
    palm's width, the object's widest and narrowest width and its height (the rows over the
    object's own edges ask most of the narrowest; the palm's edges' rows do not involve it).
    sag: each row c . (px, py) >= 0 asks sag |c| more (a bound between the back stops' ends)."""
    mu, W, _, w, h = sizes

    def less(c1, c2):  # what a row with impulse coefficients (c1, c2) asks more
        return 0.0 if not nonzero(sag) else sag * ca.sqrt(c1**2 + c2**2)

    sep = ", " if where else ""
    add(slip, f"{where}{sep}sliding back", mu * py - px - less(1.0, mu), mu * py)
    add(slip, f"{where}{sep}sliding forward", mu * py + px - less(1.0, mu), mu * py)
    # Force point -(h/2) px/py from the centre: ahead (px < 0) within min(w/2, W/2 - o),
    # behind within min(w/2, W/2 + o). Multiplied by py > 0 (implied by the stick rows).
    edge = less(h / 2, w / 2)
    add(tip, f"{where}{sep}over the object's front edge", w / 2 * py + h / 2 * px - edge,
        w / 2 * py)
    add(tip, f"{where}{sep}over the object's rear edge", w / 2 * py - h / 2 * px - edge,
        w / 2 * py)
    for i, o in enumerate(o_hi):
        add(tip, version(f"{where}{sep}over the palm's front edge", i, o_hi),
            (W / 2 - o) * py + h / 2 * px - less(h / 2, W / 2 - o), (W / 2 - o) * py)
    for i, o in enumerate(o_lo):
        add(tip, version(f"{where}{sep}over the palm's rear edge", i, o_lo),
            (W / 2 + o) * py - h / 2 * px - less(h / 2, W / 2 + o), (W / 2 + o) * py)


def ends(values, what):
    """(label, value) of one value or of both ends of an interval."""
    return [("", values[0])] if len(values) == 1 else [(f"{what} low", values[0]),
                                                       (f"{what} high", values[-1])]


def join(*words) -> str:
    return ", ".join(w for w in words if w)


def nonzero(value) -> bool:
    return not (isinstance(value, (int, float)) and value == 0.0)


def larger(a, b):
    """The larger of two half-widths (one of them itself when they are the same expression)."""
    if a is b or not nonzero(b):
        return a
    return b if not nonzero(a) else ca.fmax(a, b)


def version(text, i, versions):
    """Label of one version of a bound that has several candidate expressions."""
    return text if len(versions) == 1 else f"{text}, bound {i + 1}"
