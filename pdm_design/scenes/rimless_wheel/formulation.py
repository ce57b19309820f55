"""The rimless wheel NLP rows (docs/rimless_wheel.md, section 9): periodicity, the margins and
the robust worst case over every step's own slope (or rise and tread) and the start speed.

Decision vector x = [free design variables (leg_length, slope on a ramp; rise, tread,
landing_offset on stairs: whichever the spec leaves free), W (the orbit's post-impact speed),
tau (the error box's half-width, when robust), t (the margin epigraph, when max_min_margin)].
The number of spokes is an integer: a spec with it free is solved once per count in its bounds
(`spoke_counts`, `with_spokes`); `build` takes a spec whose count is fixed.

Robust box: every step k's chord slope is the design's +- tau (a ramp: the slope error; stairs:
the rise error moves the chord angle asin((rise + e) / chord), the tread error moves the
footholds), and the start speed is speed +- speed_tolerance. The stance energy map
E_k = eta^2 E_{k-1} + b(beta_k) is increasing in E_{k-1} and in beta_k (b' > 0 below psi0 >
alpha), so every E_k lies between E_0 and the orbit of the slope's end, E*(beta -+ tau), on the
trajectory of all slopes low (high) and the slowest (fastest) start: those two ends bound every
stance energy of every build, for any number of steps. over_the_top (E > 0 where the stance
starts behind the vertical) grows with E: its rows are exact worst cases at the low ends. The
force conditions (no_flight, no_slip) are judged at both energy ends over the widest arc
[beta - tau - alpha, beta + tau + alpha] at ARC_ROWS angles; impact_friction at the two chord
ends. On stairs the footholds drift linearly: s_k = s_0 + sum_j (chord cos beta_j - tread_{j-1}),
largest on (rise - tau, tread - tau), smallest on (rise + tau, tread + tau); the landing and
nose rows take those at the first and the last step (a straight run's ends), the nose's reach
at the high chord: it shrinks as the chord steepens (a long rise of the step the spoke lands
on), and the nose's distance does not depend on that step's rise.

Allocated ([tolerances] with allocate = true: formulation/allocation.py), the box holds one
half-width per quantity: slope, or rise and tread; start_speed (the scene's speed_tolerance
when not listed); and with leg_length (each spoke, or a lot) or the hub's mass, spread.py's
rows over the corners of each step's two spokes and the hub's k^2.
"""

from __future__ import annotations

import math

import casadi as ca

from ...errors import SpecError
from ...formulation import allocation, yield_target
from ...formulation.common import (
    MARGIN,
    MODEL,
    VALIDITY,
    Condition,
    SceneModel,
    design_inputs,
    objective_scale,
)
from ...spec.model import Bounds
from . import nlp_yield
from . import physics as phys
from .counts import spoke_counts, with_spokes  # noqa: F401 (the NLP's callers take them here)
from .model import RimlessWheelDesign

DEFAULTS = {"slope": None, "rise": None, "tread": None, "landing_offset": None}
ARC_ROWS = 9  # angles of the widest stance arc at which the force rows are written
MIN_SLOPE = 1e-6  # the chord slope's least value (rad): the ground goes down


def build(spec):
    """(SceneModel, bounds, closed forms) of a spec whose spoke count is fixed."""
    if isinstance(spec.design.get("spokes"), Bounds):
        raise SpecError(spec.source or "<spec>", "design.spokes",
                        "a fixed count here (solve each of spoke_counts(spec))",
                        found="a free count")
    if allocation.allocating(spec):  # refused in words where no bound is derived
        allocation.check(spec)
    scene = spec.scene
    names = tuple(n for n in RimlessWheelDesign.VARIABLES if n != "spokes")
    values, symbols, bounds = design_inputs(spec, names, DEFAULTS)
    robust = float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0
    epigraph = float(spec.objective.get("max_min_margin", 0.0)) > 0.0
    m = _Model(scene, int(spec.design["spokes"]), values, spec.verification.stages)
    top = scale_bound(spec, m, values, bounds)
    tau = ca.SX.sym("tolerance") if robust else 0.0
    t = ca.SX.sym("min_margin") if epigraph else None
    aux = [("periodic_speed", m.W, 0.0, math.inf)]
    start = [ca.sqrt(ca.fmax(m.orbit_speed2(m.beta), 0.0))]
    if robust:
        aux.append(("tolerance", tau, 0.0, top))
        start.append(0.01 * top)
    if epigraph:
        aux.append(("min_margin", t, 0.0, 1.0))
        start.append(0.0)
    target = (nlp_yield.target_rows(spec, m, symbols, bounds) if yield_target.active(spec)
              else None)
    if target is not None:  # tolerances sized for a yield target
        aux.append((yield_target.AUX, target.scale, *target.bounds))
        start.append(target.start)
    xd = ca.vertcat(*symbols.values()) if symbols else ca.SX(0, 1)
    aux_init = ca.Function("aux_init", [xd], [ca.vertcat(*start)])
    today = {axis: tau for axis in m.axes}
    each = any(t.quantity == "leg_length" and t.applies_to == "each"
               for t in getattr(spec, "tolerances", ()))
    conditions = allocation.box_conditions(spec, lambda box: m.conditions(box, each), today,
                                           tau)
    model = SceneModel(
        kind="rimless_wheel", design_symbols=symbols, aux=tuple(aux),
        conditions=tuple(conditions) + ((target.condition,) if target else ()),
        margin_symbol=t, aux_init=aux_init,
        objective_terms={
            "max_offset_tolerance": tau if robust else ca.SX(0.0),
            "max_min_margin": t if epigraph else ca.SX(0.0),
            "min_drop": ca.SX(0.0) + m.chord * ca.sin(m.beta),
            "fastest_convergence": ca.SX(0.0) + m.eta**2,
            "max_yield": nlp_yield.objective_term(spec, m),
        },
        derived=m.derived(), tolerance_axes=m.axes,
        objective_scale=objective_scale(spec.objective, _scale_size(spec, m, values, bounds,
                                                                           top)),
        stack_starts=False,
        extra_objective=target.objective if target is not None else None,
    )
    return model, bounds, m


def _ends(spec, m, values, bounds):
    """{quantity: its half-width's physical end}: a slope's half pitch, a rise's (tread's,
    spoke's) largest length, the start speed, the hub's mass."""
    def largest(name):
        if name in bounds:
            return float(bounds[name][1])
        value = values.get(name)
        return float(value) if isinstance(value, (int, float)) else None

    leg = largest("leg_length")
    rise = largest("rise") if m.stairs else None
    chord = 2.0 * leg * math.sin(m.alpha)
    return {"slope": m.alpha, "rise": rise or chord, "tread": largest("tread") or chord,
            "start_speed": spec.scene.initial.speed, "leg_length": leg,
            "mass": spec.scene.wheel.mass}


def scale_bound(spec, m, values, bounds):
    """The tolerance scale's upper bound: the chord's (tolerance_bound), or, allocating, the
    largest of each allocated quantity's physical end over its share (its rows hold it below
    that; the bound keeps the variable finite)."""
    top = m.tolerance_bound(bounds)
    if not allocation.allocating(spec):
        return top
    ends = _ends(spec, m, values, bounds)
    return max([top] + [ends[q] / share for q, share in allocation.coefficients(spec).items()])


def _scale_size(spec, m, values, bounds, top):
    """The tolerance scale's size for the objective's: the dearest allocated quantity's
    physical end (`top` when nothing is allocated)."""
    dearest = [q for q, share in allocation.coefficients(spec).items() if share == 1.0] \
        if allocation.allocating(spec) else []
    if not dearest:
        return top
    return _ends(spec, m, values, bounds)[dearest[0]]


class _Model:
    """Closed forms of one wheel (a fixed spoke count) on possibly symbolic design values."""

    def __init__(self, scene, spokes, values, stages):
        self.scene, self.stages, self.n = scene, stages, spokes
        w, g = scene.wheel, scene.gravity
        self.alpha = phys.half_pitch(spokes)
        self.leg = values["leg_length"]
        self.k2 = phys.gyration_squared(w.mass, w.gyration, w.spoke_mass, spokes, self.leg)
        self.eta = phys.impact_ratio(self.k2, self.leg, self.alpha)
        self.loss = phys.energy_loss(self.k2, self.leg, self.alpha)
        self.rate = phys.stance_rate(g, self.k2, self.leg)
        self.chord = phys.chord(self.leg, self.alpha)
        self.stairs = scene.ground == "stairs"
        self.values = values
        self.W = ca.SX.sym("periodic_speed")
        if self.stairs:
            self.rise = values["rise"]
            self.beta = self.chord_angle(0.0)
            advance = phys.stairs_advance(self.rise, self.leg, self.alpha)
            self.tread_derived = values["tread"] is None
            self.tread = advance if self.tread_derived else values["tread"]
            reach = phys.nose_reach(self.leg, self.alpha, self.beta)
            self.s0 = (self.tread - ca.fmin(reach, self.tread) / 2
                       if values["landing_offset"] is None
                       else values["landing_offset"])
            self.ground, self.axes = 0.0, ("rise", "tread")
        else:
            self.beta = self.ground = values["slope"]
            self.axes = ("slope",)

    def chord_angle(self, error):
        return (asin_sx(self.rise + error, self.chord) if self.stairs
                else self.beta + error)

    def orbit_speed2(self, beta):
        return phys.periodic_speed_squared(beta, self.alpha, self.eta, self.rate, self.loss)

    def tolerance_bound(self, bounds):
        """The box's largest half-width: the largest half pitch (a ramp: a slope error beyond it
        turns a step's chord past a spoke), or the largest rise (stairs)."""
        if not self.stairs:
            return self.alpha
        rise = bounds["rise"][1] if "rise" in bounds else float(self.values["rise"])
        return float(rise)

    def derived(self):
        out = {"periodic_speed": self.W, "contraction": _sx(self.eta**2),
               "chord_angle": _sx(self.beta)}
        if self.stairs:
            out.update(tread=_sx(self.tread), landing_offset=_sx(self.s0))
        return out

    def energy_ends(self, tau, dw):
        """(low, high): each a list of (energy, chord angle its stances start on) bounding every
        stance of every build (module docstring); dw: the start speed's half-width."""
        speed = self.scene.initial.speed
        start_angle = self.beta - self.alpha
        ends = []
        for sign in (-1.0, 1.0):
            beta = self.chord_angle(sign * tau)
            orbit = self.orbit_speed2(beta) - self.rate * phys.versine(beta - self.alpha)
            first = phys.stance_energy(speed + sign * dw, start_angle, self.rate)
            ends.append([(first, self.beta), (orbit, beta)])
        return ends

    def conditions(self, box, each=True):
        """The rows over a box {quantity: half-width} (slope, or rise and tread; start_speed,
        the scene's speed_tolerance when left out; leg_length and mass: spread.py's rows)."""
        out: list[Condition] = []

        def add(key, where, slack, scale=1.0, kind=MARGIN, **kw):
            out.append(Condition((key,) if key else (), where, slack, scale, kind, **kw))

        chord = box.get("rise" if self.stairs else "slope", 0.0)
        tread = box.get("tread", 0.0)
        dw = box.get("start_speed", self.scene.initial.speed_tolerance)
        if "leg_length" in box or "mass" in box:
            from .spread import Box, Spread

            self._periodic_rows(add)
            if self.stairs:
                self._tread_row(add)
            Spread(self, Box(chord, tread, dw, box.get("leg_length", 0.0),
                             box.get("mass", 0.0), each)).rows(add, VALIDITY)
            return out
        self._periodic_rows(add)
        self._box_rows(add, chord, tread, dw)
        return out

    def _periodic_rows(self, add):
        lhs = self.W**2 * self.loss
        rhs = self.eta**2 * self.rate * 2.0 * ca.sin(self.alpha) * ca.sin(self.beta)
        add(None, "periodic speed: W^2 (1 - eta^2) = eta^2 rate 2 sin(alpha) sin(beta)",
            lhs - rhs, lhs + rhs, kind=MODEL, equality=True)

    def _tread_row(self, add):
        if not self.tread_derived:
            advance = phys.stairs_advance(self.rise, self.leg, self.alpha)
            add("periodic_tread", "tread = the chord's horizontal span", self.tread - advance,
                self.tread, equality=True)

    def _box_rows(self, add, tau, tread_tau, dw):
        """The rows over a box of every step's chord (+-tau) and tread (+-tread_tau) and the
        start speed (+-dw) (module docstring)."""
        low_beta, high_beta = self.chord_angle(-tau), self.chord_angle(tau)
        add("descends", "every step's chord goes down", low_beta - MIN_SLOPE, self.alpha,
            kind=VALIDITY)
        add("impact_ratio", "an impact keeps the wheel rolling forward", self.eta, 1.0,
            kind=VALIDITY)
        (low, high) = self.energy_ends(tau, dw)
        for (energy, beta), what in zip(low, ("first stance", "orbit of the lowest slopes")):
            # omega+^2 against rate (1 - cos(beta - alpha)) behind the vertical, 0 past it
            start2 = phys.speed_squared(energy, beta - self.alpha, self.rate)
            demand = phys.over_the_top_demand(beta, self.alpha, self.rate)
            add("over_the_top", f"{what}: vaults its spoke", start2 - demand, start2)
        self._force_rows(add, low + high, low_beta, high_beta)
        for beta, what in ((low_beta, "lowest"), (high_beta, "highest")):
            normal, tangential = phys.impact_impulses(self.eta, self.alpha, beta, self.ground)
            mu = self.scene.friction
            add("impact_friction", f"impact on the {what} chord", mu * normal - ca.fabs(tangential),
                mu * normal)
        if self.stairs:
            self._stairs_rows(add, tau, tread_tau, high_beta)

    def _force_rows(self, add, energies, low_beta, high_beta):
        phi0, phi1 = low_beta - self.alpha, high_beta + self.alpha
        g, mu = self.scene.gravity, self.scene.friction
        for energy, _ in energies:
            for _, (fc, fd), (sc, sd) in phys.stance_conditions(
                    energy, phi0, phi1, self.ground, self.leg, g, self.k2, self.rate, mu,
                    ARC_ROWS):
                add("no_flight", "stance, widest arc", fc - fd, fc)
                # mu N as the scale while N > 0; where N <= 0 the slack is negative already
                add("no_slip", "stance, widest arc", sc - sd, ca.fmax(sc, 0.0))

    def _stairs_rows(self, add, tau, tt, high_beta):
        """tau: the rise's half-width, tt: the tread's."""
        chord, tread, s0 = self.chord, self.tread, self.s0
        low_beta = self.chord_angle(-tau)
        add("spoke_reach", "every rise is below the spokes' chord", chord * (1 - 1e-6) - self.rise
            - tau, chord, kind=VALIDITY)
        add("step_down", "every step goes down", self.rise - tau, chord, kind=VALIDITY)
        self._tread_row(add)
        long_step = chord * ca.cos(low_beta) - tread + tt
        short_step = chord * ca.cos(high_beta) - tread - tt
        reach = phys.nose_reach(self.leg, self.alpha, high_beta)
        for k in sorted({1, max(self.stages, 1)}):
            longest = s0 + k * long_step - tt  # tread 0 is as designed
            shortest_before = s0 + (k - 1) * short_step + (tt if k > 1 else 0.0)
            add("landing", f"foothold {k}, furthest", tread - tt - longest, tread)
            nose = tread + (tt if k > 1 else 0.0) - shortest_before
            add("nose_clearance", f"step {k}, nearest foothold", reach - nose, reach)


def _sx(value):
    """value as a CasADi expression (a number or one already)."""
    return value if isinstance(value, ca.SX) else ca.SX(value)


def asin_sx(x, c):
    return ca.asin(ca.fmin(ca.fmax(x / c, -1.0 + 1e-12), 1.0 - 1e-12))
