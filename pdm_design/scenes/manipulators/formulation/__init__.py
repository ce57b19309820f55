"""The manipulators NLP: periodic handover, first approach and robust offset tolerance.

Every condition is written with the closed forms of `physics.manipulators` on CasADi symbols;
the rows themselves, one function per group, are in formulation/manipulators/rows.py.

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

Allocated tolerances ([tolerances] with allocate = true, formulation/allocation.py): the same
rows over a box with one half-width per quantity, `box` {quantity: half-width}: the pivots'
places and heights apart, the feed's place and speed, the friction, the object's width, the
masses (the mass ratio's ends; with links or pivot friction the carry's q_e, g_e and f ends,
with the links' masses and the pivots' torques: carry_box.py), the back stops (their ends, and
the drift they add along the row) and the links' lengths (links.py); docs/optimizer.md section
4a derives each.
"""

from __future__ import annotations

import math

import casadi as ca

from ....errors import SpecError
from ....formulation import allocation
from ....formulation.common import SceneModel, design_inputs, fmax_all, fmin_all, objective_scale
from .. import physics as phys
from ..model import ManipulatorsDesign
from . import links, rows, yield_target
from .rows import LIFT_OFF, OVER_THE_TOP
from .rows import nonzero as _nonzero

DEFAULTS = {"first_pivot_x": 0.0, "first_pivot_y": 0.0}
FALL_FLOOR = 1e-9  # (x g l): the fall speed squared never below this (far below the clearance's)
TOLERANCE_CAP = 10.0  # upper bound of the box half-width variable, in link lengths
# Margins whose periodic and first_ versions are one row (the speed interval covers both): the
# larger of their two requirements holds both.
SHARED_ROWS = (OVER_THE_TOP, LIFT_OFF)
# Reported margins the max_min_margin epigraph leaves out (a clearance that is held, not traded).
OUTSIDE_MIN_MARGIN = ("parked_palms",)  # (plugin.Manipulators.outside_min_margin)
PARKED_ROWS_CAP = 16  # parked palms checked behind the carrying one, at most (docs/optimizer.md)


def build(spec, parameters=None):
    """SceneModel and bounds of a manipulators spec. parameters: the SX symbols of the scene
    numbers the spec holds as symbols (formulation/parametric.py): aux_init takes them too."""
    scene = spec.scene
    values, symbols, bounds = design_inputs(spec, ManipulatorsDesign.VARIABLES, DEFAULTS)
    robust = float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0
    if allocation.allocating(spec):
        allocation.check(spec)
    epigraph = float(spec.objective.get("max_min_margin", 0.0)) > 0.0
    stages = spec.verification.stages

    S = ca.SX.sym("periodic_speed_sq")
    u_lo, u_hi = ca.SX.sym("landing_speed_lo"), ca.SX.sym("landing_speed_hi")
    tau = ca.SX.sym("tolerance") if robust else 0.0
    t = ca.SX.sym("min_margin") if epigraph else None
    l_max = bounds["link_length"][1] if "link_length" in bounds else values["link_length"]

    stops, linked = (any(t.quantity == q for t in spec.tolerances) and
                    allocation.allocating(spec) for q in ("back_stop", "link_length"))
    m = _Model(scene, values, stages, parked_rows(scene, values, bounds, stages, stops, linked))
    m.steps = integrated_steps(spec, robust, values, bounds)
    conditions = allocation.box_conditions(
        spec, lambda box: m.conditions(S, u_lo, u_hi, box, robust),
        {"pivot_x": tau, "pivot_y": tau}, tau)
    aux = [("periodic_speed_sq", S, 0.0, math.inf),
           ("landing_speed_lo", u_lo, 0.0, math.inf),
           ("landing_speed_hi", u_hi, 0.0, math.inf)]
    if robust:
        aux.append(("tolerance", tau, 0.0, tolerance_bound(values, bounds, l_max)))
    if epigraph:
        aux.append(("min_margin", t, 0.0, 1.0))
    target = yield_target.target_rows(spec, values, symbols, bounds) \
        if yield_target.active(spec) else None  # tolerances sized for a yield target
    if target is not None:
        conditions = [*conditions, target.condition]
        aux.append((yield_target.AUX, target.scale, *target.bounds))

    xd = ca.vertcat(*symbols.values()) if symbols else ca.SX(0, 1)
    start = m.aux_start()
    if robust:
        start.append(0.0)
    if epigraph:
        start.append(0.0)
    if target is not None:
        start.append(target.start)
    inputs = [xd] if parameters is None else [xd, parameters]
    aux_init = ca.Function("aux_init", inputs, [ca.vertcat(*start)])

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
        extra_objective=target.objective if target is not None else None,
        # max_yield and a yield target walk the row every iteration: the starts are
        # screened (solve/screen.py)
        screened_starts=float(spec.objective.get("max_yield", 0.0)) > 0.0 or target is not None,
    )
    return model, bounds, m


def _yield_term(spec, values):
    """max_yield: nines of the linearised yield (formulation/manipulators/statistical.py), when
    asked."""
    if not float(spec.objective.get("max_yield", 0.0)) > 0.0:
        return ca.SX(0.0)
    from .statistical import yield_term

    yield_target.modelled_quantities(spec, "objective.max_yield")
    return yield_term(spec.scene, values, spec.tolerances, spec.verification.stages)


def integrated_steps(spec, robust, values, bounds) -> int:
    """Steps of the integrated carry (0: the closed form): with pivot damping, which has no
    closed form, or when the accuracy asks (carry = "integrated": results/bench_links.py
    measures the trade), enough for a tenth of the accuracy's agreement over the widest carry
    alpha + beta the bounds allow (physics.carry_steps). The robust rows' bounds need the
    closed form: robust with damping, or with the integrated carry asked, is refused in words."""
    forced = spec.verification.accuracy.carry == "integrated"
    if spec.scene.pivots.damping == 0.0 and not forced:
        return 0
    if robust and forced:
        raise SpecError(spec.source or "<spec>", "verification.accuracy.carry",
                        '"closed" with objective.max_offset_tolerance (the robust tolerance '
                        "rows bound the closed-form carry)", found='"integrated"')
    if robust:
        raise SpecError(spec.source or "<spec>", "scene.pivots.damping",
                        "0 with objective.max_offset_tolerance (the robust tolerance rows bound "
                        "the closed-form carry; damping has none)",
                        found=repr(spec.scene.pivots.damping))
    span = sum(bounds[k][1] if k in bounds else values[k] for k in ("alpha", "beta"))
    # a tenth of the agreement verification demands of the simulator (results/bench_links.md)
    return phys.carry_steps(spec.verification.accuracy.agreement / 10.0, span=span)


def parked_rows(scene, values, bounds, stages, stops=False, linked=False) -> int:
    """How many palms behind the carrying one can meet the carried object somewhere in the
    design box (at most PARKED_ROWS_CAP and stages - 1). The palm n places back is behind the
    object from the start of the carry once n pitch_x >= l (sin f + sin a) + (w + W) / 2 - o +
    2 tol, with -o <= (W - w) / 2 (the landing rows) and 2 tol <= pitch_y <= l (the
    palm_clearance row); each term is bounded over the box. linked: the link lengths
    toleranced, whose errors add 2 t_l <= l (link_length_range) to the pivots' relative move."""
    def low(name):
        return bounds[name][0] if name in bounds else values[name]

    def high(name):
        return bounds[name][1] if name in bounds else values[name]

    palm = scene.palm
    l_max = high("link_length")
    pitch_min = low("link_length") * (math.sin(max(low("alpha"), 0.0))
                                      + math.sin(max(low("beta"), 0.0)))
    # stops: the back stops toleranced, at most 2 alpha (back_stop_range keeps t_a <= alpha)
    a_max = min((2.0 if stops else 1.0) * high("alpha"), 1.5)
    far = (l_max * (max(math.sin(palm.front_stop), 0.0) + math.sin(a_max))
           + palm.width + (2.0 if linked else 1.0) * l_max)
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
        self.mass_ratio = self.q  # the design's m / M (self.q becomes the carry's q_e below)
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

    def first_speed(self, Q, vx=None, q=None, a=None):
        return phys.landing_speed(self.vx0 if vx is None else vx, -Q, self.a if a is None else a,
                                  self.q if q is None else q)

    def stops(self, box):
        """(a_lo, a_hi): the back stops' angles the box allows (the spec's alpha twice, the
        same expression, when exact). Kept at or above 0 by a validity row."""
        t_a = box.get("back_stop", 0.0)
        return (self.a, self.a) if not _nonzero(t_a) else (self.a - t_a, self.a + t_a)

    def mass_ratios(self, box):
        """The mass ratios m / M the box allows, as [q] or [q_lo, q_hi] (the object's mass and
        the palms' within their tolerances; the paper's device: allocation.check). Every
        landing speed is m / (m + M), increasing in q, times a factor free of the masses, and
        the carry is free of them (docs/optimizer.md section 4a)."""
        t_m, t_M = box.get("object_mass", 0.0), box.get("palm_mass", 0.0)
        if not (_nonzero(t_m) or _nonzero(t_M)):
            return [self.q]
        m = self.scene.body.mass
        M = m / self.q
        return [(m - t_m) / (M + t_M), (m + t_m) / (M - t_M)]

    def feed_speeds(self, box):
        """The horizontal start speeds the box allows: the spec's, or both ends of the feed
        speed's tolerance (a horizontal start: allocation.check; u_1 and the first impact's
        rows are affine in it, the landing place bilinear, docs/optimizer.md section 4a)."""
        t_v = box.get("feed_speed", 0.0)
        return [self.vx0] if not _nonzero(t_v) else [self.vx0 - t_v, self.vx0 + t_v]

    def next_speed(self, u, th, q=None, a=None, l=None):
        """Landing speed on the next palm after carrying at u from -alpha to the handover th
        (q: that palm's mass ratio, the spec's by default; a: both palms' stop angle, the
        spec's alpha by default; l: the carrying palm's link, the design's by default)."""
        a = self.a if a is None else a
        v = ca.sqrt(self.carry_v2(u, th, a=a, l=l))
        return phys.landing_speed(v * ca.cos(th), -v * ca.sin(th), a,
                                  self.q if q is None else q)

    def carry_v2(self, u, th, lowest=False, a=None, l=None):
        """v^2 at th on a carry that left -alpha at u: the closed form, or with pivot damping
        (or integrated_steps set) fourth-order steps in the angle (lowest: also the smallest
        v^2 on the way; l: the link, the design's by default)."""
        kw = dict(gravity=self.gc, link_length=self.l if l is None else l, friction=self.f)
        if not self.steps:
            v2 = phys.carry_speed_squared(u, self.a if a is None else a, th, **kw)
            return (v2, None) if lowest else v2
        return phys.integrated_carry_speed_squared(u, self.a, th, damping=self.delta,
                                                   steps=self.steps, lowest=lowest, **kw)

    def contact(self, th, v2, l=None):
        """(lift-off capacity of v^2, friction demand, force point / height) of the stuck
        object at th moving at v^2 on real links or pivots (physics.carry_force_ratio; l: the
        carrying palm's link, the design's by default)."""
        l = self.l if l is None else l
        along = phys.carry_along(th, gravity=self.g, carry_gravity=self.gc, friction=self.f,
                                 link_length=l)
        ratio = phys.carry_force_ratio(th, v2, gravity=self.g, link_length=l, along=along)
        held = phys.lift_off_capacity(th, gravity=self.g, link_length=l, along=along)
        return held, phys.friction_demand(th, ratio), phys.carry_force_point(th, 1.0, ratio)

    def carry_ratios(self, ends, l=None):
        """Friction / normal of the stuck object's contact force at each (th, v^2) of `ends`
        (links or pivot friction: physics.carry_force_ratio, monotone in v^2; l: the carrying
        palm's link, the design's by default)."""
        l = self.l if l is None else l
        out = []
        for th, v2 in ends:
            along = phys.carry_along(th, gravity=self.g, carry_gravity=self.gc, friction=self.f,
                                     link_length=l)
            out.append(phys.carry_force_ratio(th, v2, gravity=self.g, link_length=l,
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

    def landing_ranges(self, box, robust):
        """(o1_hi, o1_lo), (later o_hi versions, later o_lo versions): outer bounds of the landing
        offset on palm 1 and on every palm (module docstring) over the box {quantity:
        half-width}: pivot_y (tau below), pivot_x and feed_x (the start's place: it moves
        every landing place by its own error, docs/optimizer.md section 4a)."""
        vx0, C0, N = self.vx0, self.C0, self.stages
        if not robust:
            o = C0 + vx0 * self.flight_time(0.0)
            return (o, o), ([o], [o])
        tau, t_x, t_f, t_l = (box.get(q, 0.0)
                              for q in ("pivot_y", "pivot_x", "feed_x", "link_length"))
        stops = self.stops(box)
        o1, (o_hi, o_lo) = self._landing_ranges(tau, t_x, N, self.vx0, stops, t_l)
        if len(speeds := self.feed_speeds(box)) > 1:  # a bound for each end; the worst holds
            ranges = [self._landing_ranges(tau, t_x, N, vx, stops, t_l) for vx in speeds]
            o1 = (fmax_all([r[0][0] for r in ranges]), fmin_all([r[0][1] for r in ranges]))
            o_hi = [o for r in ranges for o in r[1][0]]
            o_lo = [o for r in ranges for o in r[1][1]]
        shift = (lambda o, sign: o + sign * t_f) if _nonzero(t_f) else (lambda o, sign: o)
        return ((shift(o1[0], 1), shift(o1[1], -1)),
                ([shift(o, 1) for o in o_hi], [shift(o, -1) for o in o_lo]))

    def _landing_ranges(self, tau, t_x, N, vx0, stops, t_l=0.0):
        """landing_ranges without the feed place's error: tau the pivots' heights, t_x their
        places, vx0 the start speed (a number, or an expression of unknown sign: then both
        cases' bounds, the larger and the smaller of them), stops the back stops' angles
        (docs/optimizer.md section 4a: palm 1's top and every palm's centre move with them),
        t_l the links' lengths (formulation/manipulators/links.py: with them every palm's rest,
        link and stop together, is a links.Rest)."""
        a, b, l = self.a, self.b, self.l
        stopped, linked = stops[0] is not stops[1], _nonzero(t_l)
        C0 = self.C0
        # palm 1's top raised by [lo, hi]: its pivot's error and its stop's (and its link's)
        lo, hi = (-tau, tau) if not stopped else (-tau + l * (ca.cos(stops[1]) - ca.cos(a)),
                                                  tau + l * (ca.cos(stops[0]) - ca.cos(a)))
        rest = links.Rest(self, t_l, stops) if linked else None
        if linked:
            lo, hi = -tau + rest.q_lo, tau + rest.q_hi
        # each palm's centre moves l (sin a_K - sin a) - cot b l (cos a_K - cos a) = h(a_K)
        # along its landing place, once per palm up to K (increasing in a_K)
        cot_b = ca.cos(b) / ca.sin(b)
        h_end = [0.0, 0.0] if not stopped or linked else [
            l * ((ca.sin(s) - ca.sin(a)) - cot_b * (ca.cos(s) - ca.cos(a))) for s in stops]
        signed = isinstance(vx0, (int, float))
        t_up, t_down = self.flight_time(lo), self.flight_time(hi)  # palm lower: longer flight
        shift1 = [0.0, 0.0] if not stopped else [l * (ca.sin(s) - ca.sin(a)) for s in stops]
        if linked:  # palm 1's top p_1 further back
            shift1 = [rest.p_lo, rest.p_hi]
        if not signed:  # vx0 t over t in [t_down, t_up]: at an end
            o1 = (fmax_all([vx0 * t_up, vx0 * t_down]) + C0 + t_x + shift1[1],
                  fmin_all([vx0 * t_up, vx0 * t_down]) + C0 - t_x + shift1[0])
        elif vx0 >= 0:
            o1 = (C0 + vx0 * t_up + t_x + shift1[1], C0 + vx0 * t_down - t_x + shift1[0])
        else:
            o1 = (C0 + vx0 * t_down + t_x + shift1[1], C0 + vx0 * t_up - t_x + shift1[0])
        if N < 2:
            return o1, ([o1[0]], [o1[1]])
        phi0 = vx0 * self.flight_time(0.0)
        slope = cot_b - vx0 / self.fall_speed(0.0)  # d phi / d dy_1 at 0
        phi_plus = vx0 * t_down + cot_b * hi
        phi_minus = vx0 * t_up + cot_b * lo
        tangent = [phi0 + slope * hi, phi0 + slope * lo]
        if not signed:  # concave or convex: the tangent and the ends bound it either way
            phi_max = phi_min = [*tangent, phi_plus, phi_minus]
        elif vx0 >= 0:  # phi concave: tangent above, ends below
            phi_max, phi_min = tangent, [phi_plus, phi_minus]
        else:  # phi convex: ends above, tangent below
            phi_max, phi_min = [phi_plus, phi_minus], tangent
        spread = tau * (1 + cot_b) if t_x is tau else t_x + tau * cot_b
        if linked:  # every link's R(e, z) at its worst, stage by stage
            drifts = [rest.second_order(N, tau)]
        elif not stopped:
            cm, cp = ca.cos(b) - 2 * tau / l, ca.cos(b) + 2 * tau / l
            r_ends = [l * (ca.sqrt(1 - cp**2) - ca.sin(b)) + 2 * tau * cot_b,
                      l * (ca.sqrt(1 - cm**2) - ca.sin(b)) - 2 * tau * cot_b]
            drifts = drift_worst(N, r_ends)
        else:  # each step's r at the worse end of its own range: (N - 1) of them
            ends = [-2 * tau + l * (ca.cos(stops[1]) - ca.cos(a)),
                    2 * tau + l * (ca.cos(stops[0]) - ca.cos(a))]
            drifts = [(N - 1) * (l * (ca.sqrt(1 - (ca.cos(b) + e / l) ** 2) - ca.sin(b))
                                 + cot_b * e) for e in ends]
        o_hi = [C0 + p + spread + N * h_end[1] for p in phi_max]
        o_lo = [C0 + p - spread + N * h_end[0] + d for p in phi_min for d in drifts]
        if linked:  # the links' and stops' first-order moves add up along the row; palm 1
            least, largest = rest.first_order(N)
            o_hi, o_lo = [o + largest for o in o_hi] + [o1[0]], [o + least for o in o_lo] + [o1[1]]
        return o1, (o_hi, o_lo)

    # -- the conditions -----------------------------------------------------------------------
    def conditions(self, S, u_lo, u_hi, box, robust):
        """Every condition over the box {quantity: half-width} (pivot_x, pivot_y, feed_x,
        friction, object_width; a quantity left out is exact): outer bounds, module docstring
        and docs/optimizer.md section 4a; one function per group of rows in rows.py."""
        return rows.conditions(self, S, u_lo, u_hi, box, robust)


def drift_worst(stages: int, r_ends) -> list:
    """The smallest second-order drift sum_{j=2..N} r(dy_j - dy_{j-1}) over |dy_j| <= tol, in
    closed form (docs/optimizer.md section 4): concave in the offsets, so least at a corner,
    where the steps of +-2 tol alternate in sign: floor((N-1)/2) (r(2 tol) + r(-2 tol)) plus,
    for an odd count of steps, the worse end once more (each candidate its own row)."""
    pairs, odd = divmod(stages - 1, 2)
    both = pairs * (r_ends[0] + r_ends[1])
    return [both + r for r in r_ends] if odd else [both]
