"""The stairs NLP: periodic bounce, first approach and robust per-step construction errors.

Decision vector x = [free design variables (restitution, launch_speed, rise, tread,
landing_offset: whichever the spec leaves free), V (periodic vertical impact speed, when the rise
is not derived), tau (error box half-width, when robust), t (margin epigraph)].

Stage recursion from the launch (the approach is part of the problem). Step n is tread n with the
riser at its back (from tread n-1, or from the top landing for n = 1), as in the simulator; its
construction errors (er_n, et_n) make that riser rise + er_n high and the tread tread + et_n long.
The launcher is fixed: the ball starts drop_height h0 above the designed tread 1 and reaches the
built one (er_1 lower) with vertical speed v_1 = sqrt(2 g (h0 + er_1)) at
    L_1 = landing_offset + v0 (t(er_1) - t(0)),   t(e) = sqrt(2 (h0 + e) / g)
from its riser (v0 the launch speed). Then horizontal speed vx (the launch speed, or after the
first rolling impact with friction); flight n leaves tread n upward at eps v_n, falls
rise_{n+1} = rise + er_{n+1} to tread n+1, lasts
    T_n = (eps v_n + sqrt(eps^2 v_n^2 + 2 g rise_{n+1})) / g,
and lands at L_{n+1} = L_n + vx T_n - tread_n (tread_n = tread + et_n), v_{n+1}^2 = eps^2 v_n^2 +
2 g rise_{n+1}. Periodicity: V^2 (1 - eps^2) = 2 g rise and tread = vx (1 + eps) V / g.

Nose clearance, smooth and sound: with d the distance from the landing point to the nose, the ball
(radius r) is horizontally over the nose while its centre is in [d - r, d + r]; its centre height
above the take-off level is concave in time, so the ball stays above the nose level (and over the
tread before it) iff its lowest point is above that level at the two ends, x = d - r and d + r:
    eps v vx z - g z^2 / 2 >= 0  for z = d - r, d + r   (times vx^2 > 0).
After x = d + r it is clear of the riser; it then lands on the next tread. This asks up to about
r more than the simulator's disc-to-corner contact (the analysis' margins are exact:
physics.stairs.flight_clearances); the exact gap is a nearest point found from a cubic, whose
branches cost IPOPT 4 to 6 times the iterations (docs/optimizer.md, section 2). The launch must
also clear the top landing's nose (the simulator's step 0, one design rise above tread 1, without
errors): `launch_slack`, the condition `first_nose_clearance`. With the derived rise and no
friction it is flight 1's row at zero error; with friction the launch flies at v0 and the later
flights at the rolling speed, and it is not.

Robust errors |er_n|, |et_n| <= tau: L_n increases with every er_j (j <= n, the first riser's
included) and decreases with every et_j (j < n), v_n increases with every er_j (j <= n): so L_n is
largest on the corner (er, et) = (+tau, -tau), smallest on (-tau, +tau), v_n smallest on
er = -tau (the latter corner). The nose condition is increasing in v and concave in d, so its
worst case over d in [d_lo, d_hi] is at an end: checking both ends with the smallest v is sound.
With friction, the first impact's demand falls with v_1: it is checked at er_1 = -tau. Errors
accumulate (the horizontal landing is neutrally stable), so the tolerance shrinks with the number
of stages checked. The lots of an allocated box (restitution, launch speed, launch place) move
every landing the same way (longer flights, faster, further), so the two trajectories take their
ends too (`_Model.end`); friction enters the first impact's row only (docs/optimizer.md, 4a).

The same NLP at any size of the stairs (lengths x k, speeds x sqrt(k): the same design, the box
x k; docs/optimizer.md, section 4): tau lies in [0, the largest rise of the design box] (a larger
riser error makes the step go up), every row is a pure number (slack and scale divided by the
scene's units h0 and sqrt(2 g h0)) and a number anywhere in that box, the rise row is relative to
the rise, and the objective is divided by its own size (`objective_scale`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import casadi as ca

from ....errors import SpecError
from ....formulation import allocation, yield_target
from ....formulation.common import (
    MARGIN,
    MODEL,
    VALIDITY,
    Condition,
    SceneModel,
    design_inputs,
    objective_scale,
)
from .. import physics as phys
from ..model import StairsDesign
from . import statistical as statistical_stairs

DEFAULTS = {"rise": None, "tread": None, "landing_offset": None}
# The ball keeps moving forward: vx >= this fraction of the first vertical impact speed
# sqrt(2 g h0) (a slope of at most 1000 at the first landing; a ratio, so the same at any scale).
MIN_FORWARD_RATIO = 1e-3
# Every built step still goes down: a rise error of at most (1 - this) of the rise. IPOPT meets a
# row to about 1e-8 of its norm (bound_relax_factor, tol); this keeps a claimed tolerance below
# the rise, not within IPOPT's tolerance above it, and costs a relative 1e-6 of a tolerance
# that the rise bounds.
MIN_STEP_FRACTION = 1e-6
# Square roots of speeds squared are taken of at least this fraction of 2 g h0: nowhere near the
# feasible set (there a flight leaves a tread upward, eps v > 0), but it keeps every row a number
# wherever IPOPT may step, a tolerance above the rise included.
SPEED2_FLOOR = 1e-20
# The flight's two nose rows, by the phase of the flight each guards (solve/words.py reads it).
NOSE_ENDS = ("leading edge: takes off behind the nose", "trailing edge: comes down beyond the nose")
# Requirements that add rows when above 0 (the NLP's shape depends on them: Stairs.nlp_key).
ROW_ADDING_REQUIREMENTS = ("first_nose_clearance", "nose_clearance")
# A nose_clearance requirement covers the launch too (its own name, as manipulators' first_ ones).
LAUNCH_KEYS = ROW_ADDING_REQUIREMENTS


def requires_rows(spec) -> bool:
    return any(float(spec.requirements.get(k, 0.0)) > 0.0 for k in ROW_ADDING_REQUIREMENTS)

# Every reported margin is in the max_min_margin epigraph.
OUTSIDE_MIN_MARGIN = ()
# The exact gaps of one flight (physics.stairs.flight_clearances, in its order) and of the launch
# (launch_clearances), by the phase each guards: the max_min_margin epigraph's nose rows.
EXACT_FLIGHT = ("takes off: height over the nose", "takes off: gap at take-off",
                "takes off: gap while rising", "comes down: gap while falling",
                "comes down: height over the nose")
EXACT_LAUNCH = ("comes down: gap while falling", "comes down: height over the nose")


def build(spec):
    if allocation.allocating(spec):  # refused in words where no bound is derived
        allocation.check(spec)
    scene = spec.scene
    values, symbols, bounds = design_inputs(spec, StairsDesign.VARIABLES, DEFAULTS)
    robust = float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0
    epigraph = float(spec.objective.get("max_min_margin", 0.0)) > 0.0
    # the exact nose rows when the reported nose margins must reach something: the epigraph, or
    # a required nose clearance (the smooth rows measure another quantity, section 2)
    exact = epigraph or requires_rows(spec)
    if exact and allocation.allocating(spec):
        _refuse_exact(spec)
    tau = ca.SX.sym("tolerance") if robust else 0.0
    t = ca.SX.sym("min_margin") if epigraph else None
    top = tolerance_bound(scene.initial.drop_height, values, bounds)
    m = _Model(scene, values, spec.verification.stages, rise_unit=top)

    aux, start = [], []
    if m.V_symbol is not None:
        aux.append(("periodic_vertical_speed", m.V_symbol, 0.0, math.inf))
        start.append(ca.sqrt(2 * m.g * m.rise / ca.fmax(1 - m.eps**2, 1e-9)))
    if robust:
        aux.append(("tolerance", tau, 0.0, scale_bound(spec, values, bounds, top)))
        start.append(0.01 * top)
    if epigraph:
        aux.append(("min_margin", t, 0.0, 1.0))
        start.append(0.0)
    target = (statistical_stairs.target_rows(spec, m, symbols, bounds)
              if yield_target.active(spec) else None)
    if target is not None:  # tolerances sized for a yield target
        aux.append((yield_target.AUX, target.scale, *target.bounds))
        start.append(target.start)
    xd = ca.vertcat(*symbols.values()) if symbols else ca.SX(0, 1)
    aux_init = ca.Function("aux_init", [xd], [ca.vertcat(*start) if start else ca.SX(0, 1)])

    conditions = allocation.box_conditions(spec, lambda box: m.conditions(box, robust, exact),
                                           {"rise": tau, "tread": tau}, tau)
    model = SceneModel(
        kind="stairs", design_symbols=symbols, aux=tuple(aux),
        conditions=tuple(conditions) + ((target.condition,) if target is not None else ()),
        objective_terms={
            "max_offset_tolerance": tau if robust else ca.SX(0.0),
            "max_min_margin": t if epigraph else ca.SX(0.0),
            "min_drop": ca.SX(m.rise) if not isinstance(m.rise, ca.SX) else m.rise,
            "fastest_convergence": m.eps**2,
            "max_yield": statistical_stairs.objective_term(spec, m),
        },
        margin_symbol=t, aux_init=aux_init,
        derived={"rise": m.rise, "tread": m.tread, "landing_offset": m.L1,
                 "horizontal_speed": m.vx, "periodic_vertical_speed": m.V},
        tolerance_axes=("rise", "tread"),
        objective_scale=objective_scale(spec.objective, _scale_size(spec, top) or
                                        scene.initial.drop_height),
        # One start at a time: stairs_design's 8 starts need 9-19 iterations alone, 28 stacked, so
        # stacking saved nothing (26.9 ms against 26.7 ms); with the exact nose rows (about 1 ms an
        # iteration to evaluate) they need 10-82, and the stacked run hit its cap of 100 after
        # 611 ms against 303 ms one at a time, before the stacked solver's creation
        # (results/bench_optimize.md).
        stack_starts=False,
        extra_objective=target.objective if target is not None else None,
    )
    return model, bounds, m


# Lots the exact nose rows are not shown monotone in (docs/optimizer.md section 4a): why.
EXACT_UNBOUNDED = {
    "launch_x": "the exact launch rows' worst launch place is not derived",
    "restitution": "the exact gaps' worst restitution is not derived",
    "launch_speed": "the exact gaps' worst launch and flight speeds are not derived",
}


def _refuse_exact(spec):
    """Refuse (exit 2) a lot whose bound the exact nose rows lack, in an allocated box."""
    for tol in spec.tolerances:
        if tol.quantity in EXACT_UNBOUNDED:
            raise SpecError(spec.source or "<spec>", f"tolerances.{tol.quantity}",
                            "no max_min_margin and no nose requirement with an allocated box ("
                            + EXACT_UNBOUNDED[tol.quantity] + ")", found="the exact nose rows")


def scale_bound(spec, values, bounds, top):
    """The tolerance scale's upper bound: `top` (tolerance_bound), or more where an allocated
    lot can use more than the rise allows, its physical end divided by its share: a
    restitution's tolerance up to the restitution, a friction's up to the friction, a launch
    speed's up to the launch speed (each the largest of the design box). Its rows hold it
    below that (restitution_range, first_impact_friction, forward_flight): the bound only
    keeps the variable finite, and the rise's rows hold the rise's share below the rise."""
    if not allocation.allocating(spec):
        return top

    def largest(name):
        return float(bounds[name][1] if name in bounds else values[name])

    ends = {"restitution": lambda: largest("restitution"),
            "friction": lambda: spec.scene.friction,
            "launch_speed": lambda: largest("launch_speed")}
    return max([top] + [ends[q]() / share for q, share in allocation.coefficients(spec).items()
                        if q in ends])


def _scale_size(spec, top):
    """The tolerance scale's size, for the objective's (common.objective_scale): `top` when it
    is a length's tolerance (the dearest allocated quantity, share 1, is a length, or nothing
    is allocated), else that quantity's unit: sqrt(2 g h0) for the launch speed, 1 for a
    restitution or friction (so IPOPT's tolerances stay relative at any size of the stairs)."""
    dearest = {q for q, share in allocation.coefficients(spec).items() if share == 1.0}
    if not dearest or dearest & {"rise", "tread", "launch_x"}:
        return top
    if "launch_speed" in dearest:
        return phys.impact_speed_vertical(spec.scene.gravity, spec.scene.initial.drop_height)
    return 1.0


class _End(NamedTuple):
    """One end of the lots' box (docs/optimizer.md section 4a): the ball's restitution, the
    launch speed, the horizontal speed of the flights after the first impact. Every landing
    increases with each of them (and with the launcher's place, which the rows add alike)."""

    eps: object
    v0: object
    vx: object


def _moved(x, t, sign):
    """x + sign t; x itself (the same expression) when the quantity has no tolerance."""
    return x if isinstance(t, float) and t == 0.0 else x + sign * t


def tolerance_bound(h0, values, bounds):
    """The largest error box the design box can allow: no larger than the largest rise (a riser
    error beyond the rise makes the step go up: the `step_down` row) nor h0 (tread 1 stays below
    the launcher). A bound in the problem's own lengths, so the variable, IPOPT's push of its
    start off the bound (0.01 of it) and every row at that start scale with the scene; a fixed
    bound of 1 m started it at 1 cm, above any rise below 1 cm, where the flights' square roots
    were of negative numbers (Invalid_Number_Detected on every start)."""
    if values["rise"] is None:  # derived: (1 - eps^2) h0, largest at the smallest restitution
        eps = bounds["restitution"][0] if "restitution" in bounds else values["restitution"]
        rise = (1.0 - float(eps) ** 2) * h0
    else:
        rise = bounds["rise"][1] if "rise" in bounds else values["rise"]
    return max(min(float(rise), h0), 0.0)


class _Model:
    """Closed forms of one stairs scene on (possibly symbolic) design values."""

    def __init__(self, scene, values, stages, rise_unit=0.0):
        self.scene, self.stages, self.g = scene, stages, scene.gravity
        self.eps, self.v0 = values["restitution"], values["launch_speed"]
        h0 = self.h0 = scene.initial.drop_height
        self.vy1 = phys.impact_speed_vertical(self.g, h0)
        # the scene's own units: every row's slack and scale are divided by their unit, so rows
        # (and their norms, the scales at the guess) are pure numbers at any size of the scene
        self.length, self.speed = h0, self.vy1
        self.rise_unit = rise_unit or h0  # the largest rise in the design box
        self.vx = self.horizontal(self.v0)
        self.rise_derived = values["rise"] is None
        if self.rise_derived:
            self.rise = phys.periodic_rise(h0, self.eps)
            self.V, self.V_symbol = self.vy1, None
        else:
            self.rise = values["rise"]
            self.V = self.V_symbol = ca.SX.sym("periodic_vertical_speed")
        self.tread_derived = values["tread"] is None
        orbit_tread = phys.periodic_tread(self.vx, self.g, self.V**2 / (2 * self.g), self.eps)
        self.orbit_tread = orbit_tread
        self.tread = orbit_tread if self.tread_derived else values["tread"]
        self.L1 = self.tread / 2 if values["landing_offset"] is None else values["landing_offset"]

    def horizontal(self, v0):
        """The horizontal speed of every flight after the first impact, launched at v0: v0
        itself, or with friction the rolling speed (affine, increasing in v0)."""
        if self.scene.frictionless:
            return v0
        ball = self.scene.ball
        vx, _ = phys.rolling_impact(v0, self.scene.initial.spin, radius=ball.radius,
                                    mass=ball.mass, inertia=ball.inertia)
        return vx

    def end(self, box, sign):
        """The far (sign +1: every landing furthest) or near (-1: nearest and slowest) end of the
        lots' box: restitution eps + sign t_e, launch speed v0 + sign t_v and its horizontal
        speed (the design's own expressions where a quantity has no tolerance)."""
        eps = _moved(self.eps, box.get("restitution", 0.0), sign)
        v0 = _moved(self.v0, box.get("launch_speed", 0.0), sign)
        return _End(eps, v0, self.vx if v0 is self.v0 else self.horizontal(v0))

    def flight(self, v, rise_n, eps=None):
        """(time, next vertical impact speed) of a flight leaving at eps v, falling rise_n."""
        up = (self.eps if eps is None else eps) * v
        down = ca.sqrt(ca.fmax(up**2 + 2 * self.g * rise_n, SPEED2_FLOOR * self.speed**2))
        return (up + down) / self.g, down

    def first_landing(self, er1, v0=None):
        """(L_1, v_1) when the first riser is er1 too high: tread 1 is er1 below its design
        level and the launcher is not, so the ball falls h0 + er1, further and faster.
        L_1 - landing_offset = v0 (t(er1) - t(0)), written without cancellation. v0: a launch
        speed other than the design's (the launcher placed for the design's): the landing
        moves (v0 - design v0) t(er1) further."""
        h0 = self.h0
        v1 = phys.impact_speed_vertical(self.g, ca.fmax(h0 + er1, SPEED2_FLOOR * h0))
        if v0 is None or v0 is self.v0:
            return self.L1 + self.v0 * 2 * er1 / (v1 + self.vy1), v1
        return self.L1 + v0 * 2 * er1 / (v1 + self.vy1) + (v0 - self.v0) * self.vy1 / self.g, v1

    def trajectory(self, er, et, end=None):
        """Landing offsets L_1..L_N and vertical impact speeds v_1..v_N with every step's errors
        (er, et) (numbers, symbols or per-step sequences): er[n] is step n+1's riser (er[0] the
        first, from the top landing), et[n] tread n+1; end: the lots' values (`end`; None: the
        design's)."""

        def at(e, n):
            return e[n] if isinstance(e, (list, tuple)) else e

        eps, v0, vx = (None, None, self.vx) if end is None else end
        L1, v1 = self.first_landing(at(er, 0), v0)
        L, v = [L1], [v1]
        for n in range(self.stages - 1):
            T, v_next = self.flight(v[-1], self.rise + at(er, n + 1), eps)
            L.append(L[-1] + vx * T - (self.tread + at(et, n)))
            v.append(v_next)
        return L, v

    def nose_slack(self, v, dist, end=None):
        """Clearance rows of one flight over a nose `dist` ahead: [(where, slack), ...]; end:
        the restitution and horizontal speed of the lots' near end (None: the design's)."""
        r, g = self.scene.ball.radius, self.g
        eps, vx = (self.eps, self.vx) if end is None else (end.eps, end.vx)
        ends = list(zip(NOSE_ENDS, (dist - r, dist + r), strict=True))
        if r == 0.0:
            ends = [("passes over the nose", dist)]
        return [(where, eps * v * vx * z - g * z**2 / 2) for where, z in ends]

    def launch_slack(self, back=0.0, v0=None):
        """The launch clears the top landing (step 0, one design rise above the designed tread 1;
        neither it nor the launcher has construction errors). The ball starts at its apex,
        a = h0 - rise above that landing, horizontal speed v0, and the landing's nose is
        x_n = v0 t(0) - landing_offset ahead. The lowest point falls for x > 0, so it is above the
        nose level while the centre is within r of the nose iff it is at x_n + r (nothing to
        check when x_n + r <= 0): a v0^2 - g max(x_n + r, 0)^2 / 2 >= 0 (the height times v0^2;
        C1). Conservative when the launch is below the top landing (a < 0) but already past it.
        back: the launcher that far further back (the slack decreases with x_n: a launch_x
        tolerance's worst end). v0: the ball launched at that speed from the design's launcher
        (the slack increases with it where it holds, a >= 0: a launch_speed tolerance's slow
        end)."""
        h0, r = self.scene.initial.drop_height, self.scene.ball.radius
        a = h0 - self.rise
        x = self.v0 * self.vy1 / self.g - self.L1 + back + r
        speed = self.v0 if v0 is None else v0
        return a * speed**2 - self.g * ca.fmax(x, 0.0) ** 2 / 2

    def conditions(self, box, robust, exact=False):
        """Every row. exact (max_min_margin asked, or a nose clearance required): the smooth
        nose rows keep the ball off the noses, as always, but the exact gaps (the analysis' nose
        margins, gap / tread) hold the requirement and bound the epigraph t: the smooth rows'
        slack / scale is the lowest point's height where the ball passes over the nose, divided
        by the tread, which is not the reported margin (0.65 where the exact gap was 0.16 of the
        tread: the take-off gap). That height is never below the gap, so the exact rows imply
        the smooth ones. box: {quantity: half-width} (docs/optimizer.md sections 4, 4a): every
        step's rise and tread errors, and the lots (restitution, friction, launch speed and
        place), whose far and near ends (`end`) the scenario trajectories take."""
        out: list[Condition] = []

        def add(key, where, slack, scale=1.0, kind=MARGIN, unit=1.0, keys=None, **kw):
            keys = keys if keys is not None else ((key,) if key else ())
            out.append(Condition(keys, where, slack / unit, scale / unit, kind, **kw))

        far, near = self.end(box, 1.0), self.end(box, -1.0)
        self._design_rows(add, box, robust, far, near)
        self._launch_rows(add, box, exact, near)
        self._landing_rows(add, box, robust, exact, far, near)
        return out

    def _design_rows(self, add, box, robust, far, near):
        """The periodic orbit's rows (the design's own restitution: the stairs are built for
        it), the first impact's friction, the forward flight and the steps going down."""
        g, speed = self.g, self.speed
        tau = box.get("rise", 0.0)
        if self.V_symbol is not None:
            # scaled by the size of either side (2 g rise at the orbit), not by 1 m^2/s^2
            lhs, rhs = self.V**2 * (1 - self.eps**2), 2 * g * self.rise
            add(None, "periodic vertical speed: V^2 (1 - eps^2) = 2 g rise", lhs - rhs,
                lhs + rhs, kind=MODEL, unit=speed**2, equality=True)
        if not self.tread_derived:
            add("periodic_tread", "tread = horizontal speed x periodic flight time",
                self.tread - self.orbit_tread, self.tread, equality=True)
        if not self.scene.frictionless:
            for where, slack in self.friction_slack(box, robust, far, near):
                add("first_impact_friction", where, slack, self.scene.friction)
        # the slowest build's flights (near.vx: the launch speed's slow end)
        add("forward_flight", "the ball keeps moving down the stairs",
            near.vx - MIN_FORWARD_RATIO * speed, speed, kind=VALIDITY, unit=speed)
        if near.v0 is not self.v0 and not self.scene.frictionless:
            add("forward_flight", "the slowest launch goes down the stairs",
                near.v0 - MIN_FORWARD_RATIO * speed, speed, kind=VALIDITY, unit=speed)
        if near.eps is not self.eps:  # every build's ball rebounds (the nose rows' signs)
            add("restitution_range", "the lowest restitution rebounds", near.eps, 1.0,
                kind=VALIDITY)
        # Relative to the rise itself (its value at the guess is the row's norm): IPOPT's
        # tolerances are then fractions of the rise, however small (restitution near 1). In
        # units of the largest rise, so that norm is not below the smallest assemble takes.
        keep = 1.0 - MIN_STEP_FRACTION
        if robust or not (self.rise_derived and isinstance(self.eps, float)):
            # (a rise (1 - eps^2) h0 of a fixed restitution, unmoved, is no row: >= 0 for
            # every restitution, 0 at eps = 1, the flat floor a fixed design evaluates)
            add("step_down", "every step goes down", keep * self.rise - tau, self.rise,
                kind=VALIDITY, unit=self.rise_unit)
        if robust:
            add("step_down", "tread 1 stays below the launch", keep * self.h0 - tau, self.h0,
                kind=VALIDITY, unit=self.length)

    def friction_slack(self, box, robust, far, near):
        """[(where, slack)] of first_impact_friction: the friction's low end against the
        demand, which falls with the normal impulse (the first riser tau too low, the lowest
        restitution) and grows with the slip |v0 + r omega0| (convex in the launch speed: at
        either end of its tolerance)."""
        ball = self.scene.ball
        vy1 = self.first_landing(-box.get("rise", 0.0))[1] if robust else self.vy1
        mu = _moved(self.scene.friction, box.get("friction", 0.0), -1.0)
        launches = [("", self.v0)] if near.v0 is self.v0 else [
            (", slowest launch", near.v0), (", fastest launch", far.v0)]
        return [(f"first impact ends rolling{suffix}",
                 mu - phys.rolling_impulse_ratio(v0, self.scene.initial.spin, vy1, near.eps,
                                                 radius=ball.radius, mass=ball.mass,
                                                 inertia=ball.inertia))
                for suffix, v0 in launches]

    def _launch_rows(self, add, box, exact, near):
        """The launch clears the top landing's nose: the launcher t_x further back, the
        slowest launch; the exact rows (one design rise above tread 1, to land a rise tau
        higher at worst: the longer flight's gap is the smaller)."""
        g, r, tread = self.g, self.scene.ball.radius, self.tread
        length, speed = self.length, self.speed
        add(None, "launch: comes down beyond the top landing's nose",
            self.launch_slack(box.get("launch_x", 0.0), near.v0), tread * self.v0**2,
            unit=length * speed**2, keys=LAUNCH_KEYS, epigraph=not exact)
        if exact:  # the analysis' first_nose_clearance
            gaps = phys.launch_clearances(self.v0, g, r, self.h0 - self.rise,
                                          self.v0 * self.vy1 / g - self.L1,
                                          self.rise + box.get("rise", 0.0))
            for phase, gap in zip(EXACT_LAUNCH, gaps, strict=True):
                add(None, f"launch, exact {phase}", gap, tread, unit=length, keys=LAUNCH_KEYS)

    def _landing_rows(self, add, box, robust, exact, far, near):
        """Every landing clear of the riser behind it (nearest), every flight over the nose
        ahead (both ends of its distance, the slowest take-off)."""
        g, r, tread, length, speed = self.g, self.scene.ball.radius, self.tread, self.length, \
            self.speed
        tau, t_t = box.get("rise", 0.0), box.get("tread", 0.0)
        scale = tread * self.vx**2
        if robust:
            L_long, _ = self.trajectory(tau, -t_t, far)
            L_short, v_short = self.trajectory(-tau, t_t, near)
            t_x = box.get("launch_x", 0.0)  # every landing moves with the launcher, alike
            L_long, L_short = [_moved(L, t_x, 1.0) for L in L_long], \
                [_moved(L, t_x, -1.0) for L in L_short]
        else:
            L_long, v_short = self.trajectory(0.0, 0.0)
            L_short = L_long
        for n in range(self.stages):
            stage = n + 1
            where = f"landing {stage}, shortest drift" if robust else f"landing {stage}"
            # the riser behind landing n, tau too high at worst, reaches furthest
            add("riser_clearance", where, L_short[n] - phys.riser_reach(self.rise + tau, r),
                tread, unit=length)
            ends = [("", tread - L_long[n])] if not robust else [
                (", nose nearest", tread - t_t - L_long[n]),
                (", nose furthest", tread + t_t - L_short[n]),
            ]
            # exact gaps: the flights the analysis judges (a simulation of N bounces flies N - 1)
            judged = exact and (stage < self.stages or self.stages == 1)
            for suffix, dist in ends:
                for where, slack in self.nose_slack(v_short[n], dist, near):
                    add("nose_clearance", f"flight {stage}{suffix}, {where}", slack, scale,
                        unit=length * speed**2, epigraph=not exact)
                if judged:
                    gaps = phys.flight_clearances(self.vx, self.eps * v_short[n], g, r, dist,
                                                  self.rise + tau)
                    for phase, gap in zip(EXACT_FLIGHT, gaps, strict=True):
                        add("nose_clearance", f"flight {stage}{suffix}, exact {phase}", gap,
                            tread, unit=length)
