"""The manipulators NLP: periodic handover, first approach and robust offset tolerance.

Every condition is written with the closed forms of `physics.manipulators` on CasADi symbols.

Decision vector x = [free design variables (alpha, beta, link_length, mass_ratio, first_pivot_x,
first_pivot_y: whichever the spec leaves free), S (periodic handover speed squared), u_lo, u_hi
(an invariant interval of landing speeds), tau (offset box half-width, when robust), t (margin
epigraph, when max_min_margin)].

Robust tolerance (the semi-infinite constraint, docs/optimizer.md has the full argument).
Every pivot K = 1..N (N = verification stages) may be off by (dx_K, dy_K), |dx_K|, |dy_K| <= tau.
Instead of enumerating the 4^N corners we bound each quantity a condition depends on, soundly:

* Handover into K happens at cos th_K = cos b + delta_K / l, delta_K = dy_K - dy_{K-1} in
  [-2 tau, 2 tau]: th_K in [th_lo, th_hi] with cos th_lo = cos b + 2 tau / l, cos th_hi =
  cos b - 2 tau / l.
* Landing speeds u_K: u_{K+1} = F(u_K, th_{K+1}) is increasing in u_K. With M >= d2 ln F/d th2
  on the whole interval (a closed-form curvature bound, M+ = max(M, 0)):
  min_th F >= min(F(th_lo), F(th_hi)) exp(-M+ (th_hi - th_lo)^2 / 8)   (chord bound), and
  max_th F <= max over the ends of F(b) exp(lambda (th - b) + M+ (th - b)^2 / 2)   (Taylor bound,
  lambda = d ln F / d th at b by CasADi AD). When ln F is concave (M <= 0) the low bound is exact.
  An interval [u_lo, u_hi] containing the
  first landing speeds and mapped into itself by these bounds holds every u_K, for any number of
  stages (so it covers the whole approach as well as the periodic orbit).
* Landing position o_K on palm K (from the palm centre): telescoping the per-stage shifts,
      o_K = o_1(dy_1) - dx_K + dx_1... = C0 + vx0 t(dy_1) - dx_K + sum_j g(delta_j),
  g(delta) = l (sin th(delta) - sin b) is concave with g'(0) = -cot b, so sum_j g <= -cot b
  (dy_K - dy_1) and sum_j g >= -cot b (dy_K - dy_1) + min sum_j r(delta_j) with r = g + cot b
  delta <= 0 concave; that minimum is at alternating corners, floor((K-1)/2) (r(2 tau) +
  r(-2 tau)) (+ the worse end for odd K-1): `drift_worst`. t(dy_1) is concave in dy_1.
* Conditions at an impact are A cos th + B sin th >= 0 in th (a sinusoid): on an interval shorter
  than pi it holds everywhere iff it holds at both ends. The first impact's conditions are affine
  in the fall speed Q: ends again.
* Every other condition is monotone in the bounded quantity (worst end used).
Bounds that are not exact are outer bounds, so the box found is sound (never too large).
"""

from __future__ import annotations

import math

import casadi as ca

from ..errors import SpecError
from ..physics import manipulators as phys
from ..scenes import ManipulatorsDesign
from .common import (
    MARGIN,
    MODEL,
    VALIDITY,
    Condition,
    SceneModel,
    design_inputs,
    fmax_all,
    fmin_all,
    objective_scale,
)

DEFAULTS = {"first_pivot_x": 0.0, "first_pivot_y": 0.0}
START_CLEARANCE = 1e-3  # (x link length): the object starts at least this far above palm 1
FALL_FLOOR = 1e-9  # (x g l): the fall speed squared never below this (far below the clearance's)
TOLERANCE_CAP = 10.0  # upper bound of the box half-width variable, in link lengths
# Margins whose periodic and first_ versions are one row (the speed interval covers both): the
# larger of their two requirements holds both.
OVER_THE_TOP = ("over_the_top", "first_over_the_top")
LIFT_OFF = ("lift_off", "first_lift_off")
SHARED_ROWS = (OVER_THE_TOP, LIFT_OFF)
# Reported margins the max_min_margin epigraph leaves out (a clearance that is held, not traded).
OUTSIDE_MIN_MARGIN = ("parked_palms",)
PARKED_ROWS_CAP = 16  # parked palms checked behind the carrying one, at most (docs/optimizer.md)
ACOS_EDGE = 1e-15  # acos is taken of at most 1 - this: a finite slope


def build(spec):
    """SceneModel and bounds of a manipulators spec."""
    scene = spec.scene
    values, symbols, bounds = design_inputs(spec, ManipulatorsDesign.VARIABLES, DEFAULTS)
    robust = float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0
    epigraph = float(spec.objective.get("max_min_margin", 0.0)) > 0.0
    stages = spec.verification.stages

    S = ca.SX.sym("periodic_speed_sq")
    u_lo, u_hi = ca.SX.sym("landing_speed_lo"), ca.SX.sym("landing_speed_hi")
    tau = ca.SX.sym("tolerance") if robust else 0.0
    t = ca.SX.sym("min_margin") if epigraph else None
    l_max = bounds["link_length"][1] if "link_length" in bounds else values["link_length"]

    m = _Model(scene, values, stages, parked_rows(scene, values, bounds, stages))
    m.steps = integrated_steps(spec, robust, values, bounds)
    conditions = m.conditions(S, u_lo, u_hi, tau, robust)
    aux = [("periodic_speed_sq", S, 0.0, math.inf),
           ("landing_speed_lo", u_lo, 0.0, math.inf),
           ("landing_speed_hi", u_hi, 0.0, math.inf)]
    if robust:
        aux.append(("tolerance", tau, 0.0, tolerance_bound(values, bounds, l_max)))
    if epigraph:
        aux.append(("min_margin", t, 0.0, 1.0))

    xd = ca.vertcat(*symbols.values()) if symbols else ca.SX(0, 1)
    start = m.aux_start()
    if robust:
        start.append(0.0)
    if epigraph:
        start.append(0.0)
    aux_init = ca.Function("aux_init", [xd], [ca.vertcat(*start)])

    objective_terms = {
        "max_offset_tolerance": tau if robust else ca.SX(0.0),
        "max_min_margin": t if epigraph else ca.SX(0.0),
        "min_drop": m.pitch_y,
        "fastest_convergence": m.c,
        "max_yield": _yield_term(spec, values),
    }
    model = SceneModel(
        kind="manipulators", design_symbols=symbols, aux=tuple(aux),
        conditions=tuple(conditions), objective_terms=objective_terms,
        margin_symbol=t, aux_init=aux_init,
        derived={}, tolerance_axes=("dx", "dy"),
        # a device under a metre long: IPOPT's absolute tolerances on an objective in metres
        # stopped it 2e-5 short at 40-micron links; at a metre and above they are fine as they
        # are, and the shipped problems' NLP stays as measured (results/bench_optimize.md)
        objective_scale=objective_scale(spec.objective, min(l_max, 1.0)),
    )
    return model, bounds, m


def _yield_term(spec, values):
    """max_yield: nines of the linearised yield (formulation/statistical.py), when asked."""
    if not float(spec.objective.get("max_yield", 0.0)) > 0.0:
        return ca.SX(0.0)
    from .statistical import yield_term

    return yield_term(spec.scene, values, spec.tolerances, spec.verification.stages)


def integrated_steps(spec, robust, values, bounds, force=False) -> int:
    """Steps of the integrated carry (0: the closed form): with pivot damping, which has no
    closed form, or when asked (force: results/bench_links.py measures the trade), enough for
    a tenth of the accuracy's agreement over the widest carry alpha + beta the bounds allow
    (physics.carry_steps). The robust rows'
    bounds need the closed form: robust with damping is refused in words."""
    if spec.scene.pivots.damping == 0.0 and not force:
        return 0
    if robust:
        raise SpecError(spec.source or "<spec>", "scene.pivots.damping",
                        "0 with objective.max_offset_tolerance (the robust tolerance rows bound "
                        "the closed-form carry; damping has none)",
                        found=repr(spec.scene.pivots.damping))
    span = sum(bounds[k][1] if k in bounds else values[k] for k in ("alpha", "beta"))
    # a tenth of the agreement verification demands of the simulator (results/bench_links.md)
    return phys.carry_steps(spec.verification.accuracy.agreement / 10.0, span=span)


def parked_rows(scene, values, bounds, stages) -> int:
    """How many palms behind the carrying one can meet the carried object somewhere in the
    design box (at most PARKED_ROWS_CAP and stages - 1). The palm n places back is behind the
    object from the start of the carry once n pitch_x >= l (sin f + sin a) + (w + W) / 2 - o +
    2 tol, with -o <= (W - w) / 2 (the landing rows) and 2 tol <= pitch_y <= l (the
    palm_clearance row); each term is bounded over the box."""
    def low(name):
        return bounds[name][0] if name in bounds else values[name]

    def high(name):
        return bounds[name][1] if name in bounds else values[name]

    palm = scene.palm
    l_max = high("link_length")
    pitch_min = low("link_length") * (math.sin(max(low("alpha"), 0.0))
                                      + math.sin(max(low("beta"), 0.0)))
    far = (l_max * (max(math.sin(palm.front_stop), 0.0) + math.sin(min(high("alpha"), 1.5)))
           + palm.width + l_max)
    reach = math.ceil(far / pitch_min) if pitch_min > 0.0 else PARKED_ROWS_CAP
    return max(0, min(stages - 1, reach, PARKED_ROWS_CAP))


def tolerance_bound(values, bounds, l_max) -> float:
    """The tolerance variable's upper bound: TOLERANCE_CAP link lengths, or 50 times the largest
    box the design box allows if that is less (the palm_clearance row asks 2 tol <= l (cos a -
    cos b) <= l (1 - cos b)), and below a metre at most one link length. IPOPT pushes tol off 0
    by a hundredth of this bound (at most 1 cm): that stays within half the handover drop, where
    the robust rows are numbers; with 10 link lengths it was 1 cm above a 9.6 mm drop, and every
    start failed. Under a metre the hundredth of 10 link lengths was 5 to 16 times the push a
    2 m row gets, relative to its size: 1 of 8 starts at 0.2 m links and 3 of 8 at 2 mm and at
    40 microns ended Invalid_Number_Detected. (A bound as tight as the drop itself cost the
    shipped problems 40 % more iterations.)"""
    b_max = bounds["beta"][1] if "beta" in bounds else values["beta"]
    bound = min(TOLERANCE_CAP, 50.0 * (1.0 - math.cos(b_max)) / 2.0) * l_max
    return min(bound, l_max) if l_max < 1.0 else bound


class _Model:
    """The closed forms of one manipulators scene on (possibly symbolic) design values."""

    def __init__(self, scene, values, stages, parked=0):
        self.scene, self.stages, self.parked = scene, stages, parked
        self.g = scene.gravity
        self.a, self.b = values["alpha"], values["beta"]
        self.l, self.q = values["link_length"], values["mass_ratio"]
        self.pivot = (values["first_pivot_x"], values["first_pivot_y"])
        # links and pivot friction (physics.carry_terms): effective mass ratio and gravity of
        # the carry, friction per carried mass; q and g themselves on the paper's device
        self.q, self.gc, self.f = phys.carry_terms(
            self.q, object_mass=scene.body.mass, gravity=self.g, link_length=self.l,
            **scene.mechanism())
        self.plain = scene.plain_mechanism
        # pivot damping: the carry is integrated (steps from the accuracy's rtol, set by build)
        self.delta = phys.damping_rate(self.q, object_mass=scene.body.mass, link_length=self.l,
                                       damping=scene.pivots.damping)
        self.steps = 0
        a, b, l, q, gc = self.a, self.b, self.l, self.q, self.gc
        self.k = phys.momentum_fraction(q)
        self.c = phys.contraction(a, b, q)
        self.D = phys.energy_gain_squared(a, b, gravity=gc, link_length=l, friction=self.f)
        self.pitch_x, self.pitch_y = phys.pitch(a, b, l)
        px1, py1 = phys.palm_centre(self.pivot[0], self.pivot[1], -a, l)
        (x0, y0), (self.vx0, self.vy0) = scene.initial.position, scene.initial.velocity
        self.H = y0 - py1  # fall height onto palm 1 (nominal)
        self.C0 = x0 - px1  # object ahead of palm 1's centre at the start
        self.top_needed = phys.top_speed_squared_needed(a, gravity=gc, link_length=l,
                                                        friction=self.f)

    # -- pieces --------------------------------------------------------------------------------
    def fall_speed(self, dy):
        """Vertical speed Q at the first landing when palm 1 is raised by dy. Where the object
        would start below palm 1 (the start_height row is broken there) it is a small number,
        not NaN: a start there ended IPOPT at once (solver_error) instead of moving on."""
        square = self.vy0**2 + 2.0 * self.g * (self.H - dy)
        return ca.sqrt(ca.fmax(square, FALL_FLOOR * self.g * self.l))

    def flight_time(self, dy):
        return (self.vy0 + self.fall_speed(dy)) / self.g

    def first_speed(self, Q):
        return phys.landing_speed(self.vx0, -Q, self.a, self.q)

    def next_speed(self, u, th):
        """Landing speed on the next palm after carrying at u from -alpha to the handover th."""
        v = ca.sqrt(self.carry_v2(u, th))
        return phys.landing_speed(v * ca.cos(th), -v * ca.sin(th), self.a, self.q)

    def carry_v2(self, u, th, lowest=False):
        """v^2 at th on a carry that left -alpha at u: the closed form, or with pivot damping
        (or integrated_steps set) fourth-order steps in the angle (lowest: also the smallest
        v^2 on the way)."""
        kw = dict(gravity=self.gc, link_length=self.l, friction=self.f)
        if not self.steps:
            v2 = phys.carry_speed_squared(u, self.a, th, **kw)
            return (v2, None) if lowest else v2
        return phys.integrated_carry_speed_squared(u, self.a, th, damping=self.delta,
                                                   steps=self.steps, lowest=lowest, **kw)

    def contact(self, th, v2):
        """(lift-off capacity of v^2, friction demand, force point / height) of the stuck
        object at th moving at v^2 on real links or pivots (physics.carry_force_ratio)."""
        along = phys.carry_along(th, gravity=self.g, carry_gravity=self.gc, friction=self.f)
        ratio = phys.carry_force_ratio(th, v2, gravity=self.g, link_length=self.l, along=along)
        held = phys.lift_off_capacity(th, gravity=self.g, link_length=self.l, along=along)
        return held, phys.friction_demand(th, ratio), phys.carry_force_point(th, 1.0, ratio)

    def carry_ratios(self, ends):
        """Friction / normal of the stuck object's contact force at each (th, v^2) of `ends`
        (links or pivot friction: physics.carry_force_ratio, monotone in v^2)."""
        out = []
        for th, v2 in ends:
            along = phys.carry_along(th, gravity=self.g, carry_gravity=self.gc, friction=self.f)
            out.append(phys.carry_force_ratio(th, v2, gravity=self.g, link_length=self.l,
                                              along=along))
        return out

    def aux_start(self):
        """Feasible auxiliaries at tau = 0: S from the fixed point, [u_lo, u_hi] spanning the
        first and the periodic landing speeds."""
        S = phys.handover_speed_squared(self.a, self.b, self.q, gravity=self.gc,
                                        link_length=self.l, friction=self.f)
        u_star = self.k * ca.sqrt(ca.fmax(S, 0.0)) * ca.cos(self.a + self.b)
        u1 = self.first_speed(self.fall_speed(0.0))
        return [S, ca.fmax(ca.fmin(u1, u_star), 0.0), ca.fmax(u1, u_star)]

    def landing_ranges(self, tau, robust):
        """(o1_hi, o1_lo), (later o_hi versions, later o_lo versions): outer bounds of the landing
        offset on palm 1 and on every palm (module docstring)."""
        vx0, C0, N = self.vx0, self.C0, self.stages
        if not robust:
            o = C0 + vx0 * self.flight_time(0.0)
            return (o, o), ([o], [o])
        t_up, t_down = self.flight_time(-tau), self.flight_time(tau)  # palm lower: longer flight
        if vx0 >= 0:
            o1 = (C0 + vx0 * t_up + tau, C0 + vx0 * t_down - tau)
        else:
            o1 = (C0 + vx0 * t_down + tau, C0 + vx0 * t_up - tau)
        if N < 2:
            return o1, ([o1[0]], [o1[1]])
        b, l = self.b, self.l
        cot_b = ca.cos(b) / ca.sin(b)
        phi0 = vx0 * self.flight_time(0.0)
        slope = cot_b - vx0 / self.fall_speed(0.0)  # d phi / d dy_1 at 0
        phi_plus = vx0 * t_down + cot_b * tau
        phi_minus = vx0 * t_up - cot_b * tau
        if vx0 >= 0:  # phi concave: tangent above, ends below
            phi_max = [phi0 + slope * tau, phi0 - slope * tau]
            phi_min = [phi_plus, phi_minus]
        else:  # phi convex: ends above, tangent below
            phi_max = [phi_plus, phi_minus]
            phi_min = [phi0 + slope * tau, phi0 - slope * tau]
        cm, cp = ca.cos(b) - 2 * tau / l, ca.cos(b) + 2 * tau / l
        r_ends = [l * (ca.sqrt(1 - cp**2) - ca.sin(b)) + 2 * tau * cot_b,
                  l * (ca.sqrt(1 - cm**2) - ca.sin(b)) - 2 * tau * cot_b]
        spread = tau * (1 + cot_b)
        o_hi = [C0 + p + spread for p in phi_max]
        o_lo = [C0 + p - spread + d for p in phi_min for d in drift_worst(N, r_ends)]
        return o1, (o_hi, o_lo)

    # -- the conditions -----------------------------------------------------------------------
    def conditions(self, S, u_lo, u_hi, tau, robust):
        a, b, l, g = self.a, self.b, self.l, self.g
        body, palm = self.scene.body, self.scene.palm
        mu, W, w, h = palm.friction, palm.width, body.width, body.height
        out: list[Condition] = []

        def add(keys, where, slack, scale=1.0, kind=MARGIN, **kw):
            out.append(Condition(tuple(keys) if isinstance(keys, (tuple, list)) else (keys,),
                                 where, slack, scale, kind, **kw))

        if robust:
            cm, cp = ca.cos(b) - 2 * tau / l, ca.cos(b) + 2 * tau / l
            # a number wherever IPOPT may step: its push of tau off 0 (1 cm, say) can take
            # cos b + 2 tau / l past 1 where the handover drop l (1 - cos b) / 2 is smaller
            # (every start Invalid_Number_Detected); the palm_clearance row keeps the feasible
            # set inside, so the clip changes no answer
            edge = 1.0 - ACOS_EDGE
            th_hi, th_lo = ca.acos(ca.fmax(cm, -edge)), ca.acos(ca.fmin(cp, edge))
            thetas = [("smallest handover angle", th_lo), ("largest handover angle", th_hi)]
            Qs = [("palm 1 high", self.fall_speed(tau)), ("palm 1 low", self.fall_speed(-tau))]
        else:
            th_hi = th_lo = b
            thetas = [("at beta", b)]
            Qs = [("", self.fall_speed(0.0))]
        Q_hi = Qs[-1][1]

        # Model: the periodic fixed point and the invariant interval of landing speeds.
        if self.steps:  # integrated: S is v(b)^2 after landing at k sqrt(S) cos(a + b)
            u_star = self.k * ca.sqrt(ca.fmax(S, 0.0)) * ca.cos(a + b)
            add((), "periodic handover speed: S = v(beta)^2 (integrated)",
                self.carry_v2(u_star, b) - S, kind=MODEL, equality=True)
        else:
            add((), "periodic handover speed: S (1 - c) = D", S * (1 - self.c) - self.D,
                kind=MODEL, equality=True)
        u1_lo, u1_hi = self.first_speed(Q_hi), self.first_speed(Qs[0][1])
        # The interval rows keep the backoff in speed units (sqrt(g l)): without it, an
        # interval met only to IPOPT's tolerance let the first landing stall 1e-4 rad short of
        # the top in 3 of 900 random specs; in m/s it would be a size-dependent 1e-6 m/s.
        model = {"kind": MODEL, "backoff_unit": ca.sqrt(g * l)}
        add((), "interval holds the first landing speed (low)", u1_lo - u_lo, **model)
        add((), "interval holds the first landing speed (high)", u_hi - u1_hi, **model)
        if robust:
            # Curvature bound of ln F(u, th) on the whole interval, for every u (docs/optimizer.md):
            # d2 ln F / d th2 = -sec^2(a + th) + (y cos th - y^2 sin^2 th) / 2 with y = 2 g l / v^2
            # <= cot^2(th_lo) / 8 - sec^2(a + th_lo) =: M; M+ = smooth max(M, 0) >= max(M, 0).
            # (with pivot friction f: cot th_lo becomes cos th_lo / (sin th_lo - f / (g l)),
            # the same maximum over 1 / v^2 of g l cos th / v^2 - 2 (g l sin th - f)^2 / v^4)
            lean = ca.sin(th_lo) if phys.is_exact_zero(self.f) else (
                ca.sin(th_lo) - self.f / (self.gc * l))
            curv = (ca.cos(th_lo) / lean) ** 2 / 8 - 1 / ca.cos(a + th_lo) ** 2
            curv = (curv + ca.sqrt(curv**2 + 1e-12)) / 2
            # Low end: ln F >= chord - M+ (th - th_lo)(th_hi - th) / 2 >= min over the ends
            # - M+ (th_hi - th_lo)^2 / 8.
            sag = ca.exp(-curv * (th_hi - th_lo) ** 2 / 8)
            for where, th in thetas:
                add((), f"interval invariant (low, {where})",
                    self.next_speed(u_lo, th) * sag - u_lo, **model)
            # High end: ln F <= ln F(b) + lambda (th - b) + M+ (th - b)^2 / 2 (Taylor), convex in
            # th so largest at an end; lambda = d ln F / d th at b by CasADi AD.
            th_s = ca.SX.sym("th")
            dlog = ca.substitute(ca.jacobian(ca.log(self.next_speed(u_hi, th_s)), th_s), th_s, b)
            u_b = self.next_speed(u_hi, b)
            for where, th in thetas:
                bound = u_b * ca.exp(dlog * (th - b) + curv * (th - b) ** 2 / 2)
                add((), f"interval invariant (high, {where})", u_hi - bound, **model)
        else:
            add((), "interval invariant (low)", self.next_speed(u_lo, b) - u_lo, **model)
            add((), "interval invariant (high)", u_hi - self.next_speed(u_hi, b), **model)

        # Validity of the closed forms.
        add(("forward_landing",), "first landing moves the palm forward", self.first_speed(Q_hi),
            scale=self.k * ca.sqrt(self.vx0**2 + Q_hi**2), kind=VALIDITY)
        add(("forward_landing",), "handover moves the next palm forward",
            phys.landing_speed(ca.cos(th_hi), -ca.sin(th_hi), a, self.q), scale=self.k,
            kind=VALIDITY)
        add(("start_height",), "",
            self.H - tau - START_CLEARANCE * l, scale=l, kind=VALIDITY)
        if robust and not phys.is_exact_zero(self.f):
            add(("over_the_top",), "gravity beats the pivot friction at the handover",
                self.gc * l * ca.sin(th_lo) - self.f, self.gc * l, kind=VALIDITY)

        # Carry conditions on every palm (the first included: u_lo <= u_1 <= u_hi).
        if self.steps:  # integrated: the slowest point of the slowest carry is still moving
            add(OVER_THE_TOP, "slowest landing on any palm, slowest point (integrated)",
                self.carry_v2(u_lo, b, lowest=True)[1], u_lo**2)
        else:
            add(OVER_THE_TOP, "slowest landing on any palm",
                u_lo**2 - self.top_needed, u_lo**2)
        v2 = self.carry_v2(u_hi, th_hi)
        if self.plain:
            held = phys.lift_off_capacity(a, gravity=g, link_length=l)
            add(LIFT_OFF, "at the back stop, fastest landing",
                held - u_hi**2, held)
            held = phys.lift_off_capacity(th_hi, gravity=g, link_length=l)
            add(LIFT_OFF, "at the handover, fastest carry", held - v2, held)
            add("slip_carry", "at the back stop", mu - phys.friction_demand(a), mu)
            add("slip_carry", "at the largest handover angle",
                mu - phys.friction_demand(th_hi), mu)
            fp_back = phys.carry_force_point(-a, h)
            fp_front = -phys.carry_force_point(th_hi, h)
        else:  # the contact force's tangential part depends on the speed: both ends of each
            for where, th, speed2 in (("at the back stop, fastest landing", -a, u_hi**2),
                                      ("at the handover, fastest carry", th_hi, v2)):
                add(LIFT_OFF, where, self.contact(th, speed2)[0] - speed2, g * l)
            back = self.carry_ratios([(-a, u_lo**2), (-a, u_hi**2)])
            front = self.carry_ratios([(th, self.carry_v2(u, th)) for th in (th_lo, th_hi)
                                       for u in (u_lo, u_hi)])
            for i, r in enumerate(back + front):
                add("slip_carry", _v("at the ends of the carry", i, back + front),
                    mu - phys.friction_demand(None, r), mu)
            fp_back = fmax_all([phys.carry_force_point(-a, h, r) for r in back])
            fp_front = fmax_all([-phys.carry_force_point(None, h, r) for r in front])
        add("palm_clearance", "next palm below the object until the handover",
            self.pitch_y - 2 * tau, l, epigraph=False)
        if palm.front_stop < math.pi / 2:
            add("front_stop", "largest handover angle before the front stop",
                palm.front_stop - th_hi, palm.front_stop, epigraph=False)

        (o1_hi, o1_lo), (o_hi, o_lo) = self.landing_ranges(tau, robust)
        # Palms parked at their front stops behind the carrying one stay clear of the object
        # (physics.parked_palm_clearance; each palm's landing offset lies between the smallest
        # of the o_lo versions and the largest of the o_hi ones, each pivot within the box).
        # Deferred: on problems where they do not bind they cost IPOPT 2 of 14 iterations.
        parked = {"alpha": a, "theta_end": th_hi, "link_length": l,
                  "front_stop": palm.front_stop, "pitch_x": self.pitch_x,
                  "pitch_y": self.pitch_y, "offset_lo": fmin_all(o_lo),
                  "offset_hi": fmax_all(o_hi), "reach": (w + W) / 2,
                  "depth": palm.thickness + h, "shift": 2 * tau}
        for n in range(1, self.parked + 1):
            add("parked_palms", f"palm {n} back, at its front stop",
                phys.parked_palm_clearance(n, **parked), l, epigraph=False, deferred=True)
        # Landing within the palm: |o| + w/2 <= W/2.
        for i, o in enumerate(o_hi):
            add("landing", _v("object furthest ahead", i, o_hi), W / 2 - o - w / 2, W / 2)
        for i, o in enumerate(o_lo):
            add("landing", _v("object furthest behind", i, o_lo), W / 2 + o - w / 2, W / 2)
        # Tipping during the carry: the force point within the support (ahead of the centre at
        # the back stop, behind it at the handover).
        add("tip_carry", "at the back stop, object's front edge", w / 2 - fp_back, w / 2)
        for i, o in enumerate(o_hi):
            add("tip_carry", _v("at the back stop, palm's front edge", i, o_hi),
                W / 2 - o - fp_back, W / 2 - o)
        add("tip_carry", "at the handover, object's rear edge", w / 2 - fp_front, w / 2)
        for i, o in enumerate(o_lo):
            add("tip_carry", _v("at the handover, palm's rear edge", i, o_lo),
                W / 2 + o - fp_front, W / 2 + o)

        # Impacts: on palms 2.. (velocity along the handover tangent) and the first landing.
        if self.stages >= 2:
            for where, th in thetas:
                px, py = phys.landing_impulse(ca.cos(th), -ca.sin(th), a, self.q)
                impact_rows(add, self.scene, "slip_impact", "tip_impact", where, px, py, o_hi,
                            o_lo)
        for where, Q in Qs:
            px, py = phys.landing_impulse(self.vx0, -Q, a, self.q)
            impact_rows(add, self.scene, "first_slip_impact", "first_tip_impact", where, px, py,
                        [o1_hi], [o1_lo])
        return out


def drift_worst(stages: int, r_ends) -> list:
    """The smallest second-order drift sum_{j=2..N} r(dy_j - dy_{j-1}) over |dy_j| <= tol, in
    closed form (docs/optimizer.md section 4): concave in the offsets, so least at a corner,
    where the steps of +-2 tol alternate in sign: floor((N-1)/2) (r(2 tol) + r(-2 tol)) plus,
    for an odd count of steps, the worse end once more (each candidate its own row)."""
    pairs, odd = divmod(stages - 1, 2)
    both = pairs * (r_ends[0] + r_ends[1])
    return [both + r for r in r_ends] if odd else [both]


def impact_rows(add, scene, slip, tip, where, px, py, o_hi, o_lo):
    """Stick (|px| <= mu py) and no tip (impulse line through the support) at a landing with
    impulse (px, py) and landing offsets o_hi (furthest ahead) and o_lo (furthest behind):
    add(key, where, slack, scale) once per row."""
    body, palm = scene.body, scene.palm
    mu, W, w, h = palm.friction, palm.width, body.width, body.height
    sep = ", " if where else ""
    add(slip, f"{where}{sep}sliding back", mu * py - px, mu * py)
    add(slip, f"{where}{sep}sliding forward", mu * py + px, mu * py)
    # Force point -(h/2) px/py from the centre: ahead (px < 0) within min(w/2, W/2 - o),
    # behind within min(w/2, W/2 + o). Multiplied by py > 0 (implied by the stick rows).
    add(tip, f"{where}{sep}over the object's front edge", w / 2 * py + h / 2 * px, w / 2 * py)
    add(tip, f"{where}{sep}over the object's rear edge", w / 2 * py - h / 2 * px, w / 2 * py)
    for i, o in enumerate(o_hi):
        add(tip, _v(f"{where}{sep}over the palm's front edge", i, o_hi),
            (W / 2 - o) * py + h / 2 * px, (W / 2 - o) * py)
    for i, o in enumerate(o_lo):
        add(tip, _v(f"{where}{sep}over the palm's rear edge", i, o_lo),
            (W / 2 + o) * py - h / 2 * px, (W / 2 + o) * py)


def _v(text, i, versions):
    """Label of one version of a bound that has several candidate expressions."""
    return text if len(versions) == 1 else f"{text}, bound {i + 1}"
