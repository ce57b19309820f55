"""Many builds of a manipulators row at once: the closed-form stage map with every part's own
pivot, link length, back stop and palm mass, and the lot's friction, object and feed.

Build n, palm k (0-based) has pivot P_k (nominal pitch plus its deviations), link l_k, back stop
a_k (it rests at -a_k) and palm mass M_k; the lot has friction mu, object mass m and width w,
and the feed x and speed. Stage by stage, with physics.manipulators on numpy arrays (the
per-stage logic of formulation/manipulators/offsets.py, extended to every part's own values):

  first landing   palm 1's top at C = P_1 + l_1 (-sin a_1, cos a_1); fall H = y0 - C_y,
                  Q = sqrt(vy0^2 + 2 g H), offset o = x0 + vx0 (vy0 + Q) / g - C_x
  landing         u = m/(m+M_k) (V . t(-a_k)), impulse (px, py) = landing_impulse: sticks iff
                  |px| <= mu py, no tip iff -(h/2) px/py lies in the support
                  [max(-w/2, -W/2 - o), min(w/2, W/2 - o)]
  carry on palm k over the top iff u^2 >= 2 g l_k (1 - cos a_k); at both ends of the carry
                  (the guards are monotone or convex in the angle between them; on real links
                  over the whole carry, Builds.inside): no lift-off
                  (v^2 < g l cos th), no slip (|tan th| <= mu), no tip ((h/2) tan th in the
                  support); palms parked behind stay clear (physics.parked_palm_clearance)
  handover        palm k+1's top at C' = P_{k+1} + l_{k+1} (-sin a_{k+1}, cos a_{k+1}) is met
                  where the object's base comes down to it: cos th = (C'_y - P_k,y) / l_k,
                  speed v^2 = u^2 + 2 g l_k (cos a_k - cos th) along t(th), new offset
                  o' = P_k,x + o + l_k sin th - C'_x; it lands iff |o'| < (w + W)/2
  a slip first    on the paper's device, a carry that passes atan(mu) before the handover
                  (or beta) slides from there: integrated in the angle (slide_to_handover)
  the last palm   carries the object to the design's beta: the run is complete.
  other palms     the feed's flight and every carry's arc meet no palm but the one they end
                  on (exact for the next AHEAD palms beyond it: the path's heights over its
                  stretch within a box along x; bounds for the palms further on and for the
                  parked palms behind those parked_palms checks); else closed_form = False.

These are the simulator's own judgements in the regime it follows in closed form (plastic
landings that stick, stuck carries, and a slide on to the handover; with a palm restitution > 0
no build is in it). A build that leaves it (any other slip, a lift-off, a landing that drives
the palm into its stop, a miss, a palm in the way, a palm other than the next met) is marked
closed_form = False with the failure the closed forms expect; the event simulator has the last
word on it.
"""

from __future__ import annotations

import math

import numpy as np

from ...tolerances.outcome import BuildOutcome
from . import physics as phys

INVALID = "invalid_part"
# Parts no workshop can make, (build_values' key, test on its values, what it needs); friction
# coefficients and torques are taken at 0 instead (build_values): a part at that limit exists
UNBUILDABLE = (
    ("link_length", lambda x: x <= 0.0, "> 0"),
    ("palm_mass", lambda x: x <= 0.0, "> 0"),
    ("back_stop", lambda x: np.abs(x) >= 0.5 * math.pi, "within +-pi/2"),
    ("link_mass", lambda x: x < 0.0, ">= 0"),
    ("object_mass", lambda x: x <= 0.0, "> 0"),
    ("object_width", lambda x: x <= 0.0, "> 0"),
)
PARKED_CAP = 16  # palms parked behind the carrying one checked, at most
# cells of a carry on real links whose rows hold over the whole carry (its guards compared at
# their inner ends)
INSIDE_CELLS = 32
SLIDE_STEP = 0.01  # rad: the largest fourth-order Runge-Kutta step of a slide in the angle
AHEAD = 2  # palms beyond the one the object goes to checked one by one; the rest by a bound


def run_builds(scene, design, deviations: dict, stages: int) -> BuildOutcome:
    """Outcome of every build (deviations: tolerances.draw's arrays, SI, added to nominal)."""
    with np.errstate(all="ignore"):
        return _Builds(scene, design, deviations, stages).run()


def build_values(scene, design, deviations: dict, stages: int, count: int) -> dict:
    """Every part's and the lot's values of `count` builds: pivot_x, pivot_y, link_length,
    back_stop, palm_mass, link_mass (each link), pivot_friction (torque, a manipulator's joints
    together) as (count, stages) arrays; friction, object_mass, object_width, feed_x, feed_vx,
    feed_vy as (count,) arrays."""
    def each(name, nominal):
        dev = deviations.get(name)
        dev = 0.0 if dev is None else (dev if np.ndim(dev) == 2 else np.asarray(dev)[:, None])
        return np.broadcast_to(np.asarray(nominal + dev, dtype=float), (count, stages))

    def lot(name, nominal):
        return np.broadcast_to(np.asarray(nominal + deviations.get(name, 0.0), dtype=float),
                               (count,))

    l, a = design.link_length, design.alpha
    pitch_x, pitch_y = (float(p) for p in phys.pitch(a, design.beta, l))
    k = np.arange(stages)
    (x0, _), (vx, vy) = scene.initial.position, scene.initial.velocity
    speed = math.hypot(vx, vy)
    direction = (vx / speed, vy / speed) if speed > 0.0 else (1.0, 0.0)
    feed_speed = lot("feed_speed", speed)
    return {
        "pivot_x": each("pivot_x", design.first_pivot_x + k * pitch_x),
        "pivot_y": each("pivot_y", design.first_pivot_y - k * pitch_y),
        "link_length": each("link_length", l),
        "back_stop": each("back_stop", a),
        "palm_mass": each("palm_mass", scene.body.mass / design.mass_ratio),
        "link_mass": each("link_mass", scene.links.mass),
        # a dissipation below its physical limit is taken at it (docs/tolerances.md, 1.)
        "pivot_friction": np.maximum(each("pivot_friction", scene.pivots.friction_torque), 0.0),
        "friction": np.maximum(lot("friction", scene.palm.friction), 0.0),
        "object_mass": lot("object_mass", scene.body.mass),
        "object_width": lot("object_width", scene.body.width),
        "feed_x": lot("feed_x", x0),
        "feed_vx": feed_speed * direction[0],
        "feed_vy": feed_speed * direction[1],
    }


def _margin(capacity, demand):
    """analysis.result.margin on arrays: (capacity - demand) / max(capacity, demand)."""
    scale = np.maximum(capacity, demand)
    return np.where(scale > 0.0, (capacity - demand) / np.where(scale > 0.0, scale, 1.0),
                    np.where(capacity == demand, 0.0, -1.0))


class _Builds:
    """The map's bookkeeping: one array entry per build, a build stops at its first failure."""

    def __init__(self, scene, design, deviations, stages):
        self.n = n = _count(deviations)
        self.stages, self.g = stages, scene.gravity
        # every part's values by stage (stages, builds): a stage's values contiguous
        # (a part nobody varies stays a broadcast view: no copy of a constant)
        self.v = {key: (x.T if x.ndim == 2 and x.strides == (0, 0)
                        else np.ascontiguousarray(x.T) if x.ndim == 2 else x)
                  for key, x in build_values(scene, design, deviations, stages, n).items()}
        self.beta, self.fs = design.beta, scene.palm.front_stop
        self.W, self.h, self.T = scene.palm.width, scene.body.height, scene.palm.thickness
        self.y0 = scene.initial.position[1]
        self.restitution = scene.palm.restitution
        self.alive = np.ones(n, bool)
        self.passed = np.zeros(n, int)
        self.code = np.zeros(n, np.int16)  # index in self.names of the failure
        self.names = [""]
        self.closed = np.ones(n, bool)
        self.worst = np.full(n, np.inf)
        self.parked = _parked_rows(scene, design, stages)
        # links and pivots (docs/physics.md, section 2.1): every palm its own carry terms
        self.scene, self.l = scene, design.link_length
        self.real = not (scene.plain_mechanism and not self.v["link_mass"].any()
                         and not self.v["pivot_friction"].any())

    def run(self) -> BuildOutcome:
        v = self.v
        m, w, mu = v["object_mass"], v["object_width"], v["friction"]
        self.half_w = 0.5 * w
        self.invalid(v)
        # a palm whose back stop is past the vertical swings forward from rest at the build
        # (docs/manipulators_model.md, section 2.5): no closed form here, the simulator's
        past = v["back_stop"] < 0.0
        self.closed &= ~(past.any(axis=0) if past.ndim == 2 else past)
        self.row_boxes(w)
        cx, cy = self.rest_top(0)
        fall = self.y0 - cy
        vx, vy0 = v["feed_vx"], v["feed_vy"]
        self.group(0, [("blocked", fall / v["link_length"][0], False)])
        q_fall = np.sqrt(vy0**2 + 2.0 * self.g * np.maximum(fall, 0.0))
        self.flight_meets_others(v["feed_x"], vx, vy0, (vy0 + q_fall) / self.g)
        offset = v["feed_x"] + vx * (vy0 + q_fall) / self.g - cx
        self.meets(0, offset, w)
        u = self.land(0, vx, -q_fall, offset, m, w, mu, passed=0)
        for k in range(self.stages):
            u, offset = self.carry(k, u, offset, w, mu)
            if not self.alive.any():
                break
        self.passed[self.alive] = self.stages
        # the closed forms' landings are plastic, and viscous pivot damping has no closed form:
        # with either, none applies
        if self.restitution > 0.0 or self.scene.pivots.damping > 0.0:
            self.closed[self.code != self.names.index(INVALID)
                        if INVALID in self.names else slice(None)] = False
        failure = np.array(self.names, dtype=object)[self.code]
        return BuildOutcome(self.passed, failure, np.where(np.isinf(self.worst), 1.0,
                                                           self.worst), self.closed)

    # -- bookkeeping ------------------------------------------------------------------------
    def group(self, passed, checks):
        """Conditions judged at one moment: [(failure name, margin, closed form?)]. A build
        alive where one margin is < 0 (or not a number) fails with the first such name; it
        stays in the closed-form regime only if every failing condition is closed form."""
        failing_any = None
        for kind, value, closed in checks:
            np.fmin(self.worst, value, out=self.worst, where=self.alive)
            bad = self.alive & ~(value >= 0.0)
            if not bad.any():
                continue
            if failing_any is None:
                failing_any, code = np.zeros(self.n, bool), np.zeros(self.n, np.int16)
                open_any = np.zeros(self.n, bool)
            code[bad & ~failing_any] = self._code(kind)
            failing_any |= bad
            open_any |= bad & (np.isnan(value) if closed else True)
        if failing_any is None:
            return
        self.code[failing_any] = code[failing_any]
        self.passed[failing_any] = passed
        self.closed[failing_any] &= ~open_any[failing_any]
        self.alive &= ~failing_any

    def _code(self, kind: str) -> int:
        if kind not in self.names:
            self.names.append(kind)
        return self.names.index(kind)

    def invalid(self, v):
        """Parts no workshop can make (a link of length <= 0, a palm of no mass, ...): the
        build fails before it starts (invalid_part), as the simulator reports it."""
        bad = np.zeros(self.n, bool)
        for key, test, _ in UNBUILDABLE:
            value = test(v[key])
            bad |= value.any(axis=0) if value.ndim == 2 else value
        self.group(0, [(INVALID, np.where(bad, -1.0, 1.0), True)])

    def rest_top(self, k):
        """Top-surface centre of palm k resting on its back stop."""
        v = self.v
        return phys.palm_centre(v["pivot_x"][k], v["pivot_y"][k], -v["back_stop"][k],
                                v["link_length"][k])

    def support(self, offset, w):
        return np.maximum(-0.5 * w, -0.5 * self.W - offset), np.minimum(0.5 * w,
                                                                      0.5 * self.W - offset)

    def tips(self, point, offset, w):
        """The tip onset: the force line reaches an end of the supported base. The object then
        rocks (sim/rocking.py): it may settle, be caught or tip over, which the event simulator
        judges (closed form False; with restitution > 0 no build is closed form anyway)."""
        lo, hi = self.support(offset, w)
        return [("tip", (hi - point) / self.half_w, False), ("tip", (point - lo) / self.half_w,
                                                              False)]

    def meets(self, passed, offset, w):
        """The object comes down on a palm's top (else it passes it or hits its side)."""
        self.group(passed, [("fell_clear", _margin(0.5 * (w + self.W), np.abs(offset)), False)])

    # -- the phases -------------------------------------------------------------------------
    def terms(self, k):
        """(q_e, g_e, f) of palm k's carry (physics.carry_terms): q, g, 0 on the paper's
        device; with links and pivots its own link length, palm mass, link mass and friction."""
        v = self.v
        m, l = v["object_mass"], v["link_length"][k]
        q = m / v["palm_mass"][k]
        if not self.real:
            return q, self.g, 0.0
        mech = self.scene.mechanism(link_mass=v["link_mass"][k],
                                    friction_torque=v["pivot_friction"][k],
                                    length_scale=l / self.l)
        return phys.carry_terms(q, object_mass=m, gravity=self.g, link_length=l, **mech)

    def land(self, k, vx, vy, offset, m, w, mu, passed):
        """Plastic landing on palm k resting at -a_k: the speed the palm moves off with."""
        a = self.v["back_stop"][k]
        q = self.terms(k)[0]
        u = phys.landing_speed(vx, vy, a, q)
        px, py = phys.landing_impulse(vx, vy, a, q)
        self.group(passed, [("stall", u / np.hypot(vx, vy), False),
                            ("slip", _margin(mu * py, np.abs(px)), False),
                            *self.tips(-0.5 * self.h * px / py, offset, w)])
        return u

    def guards(self, k, theta, v2, offset, w, mu, terms):
        """The stuck carry's guards at angle theta, speed v2 (physics.manipulators): lift-off,
        tip (both edges) and slip, as (failure, margin, closed form?)."""
        g, l = self.g, self.v["link_length"][k]
        along = ratio = None
        if self.real:
            along = phys.carry_along(theta, gravity=g, carry_gravity=terms[1], friction=terms[2],
                                     link_length=l)
            ratio = phys.carry_force_ratio(theta, v2, gravity=g, link_length=l, along=along)
        return [("lift_off", _margin(phys.lift_off_capacity(theta, gravity=g, link_length=l,
                                                            along=along), v2), False),
                *self.tips(phys.carry_force_point(theta, self.h, ratio), offset, w),
                ("slip", _margin(mu, phys.friction_demand(theta, ratio)), False)]

    def need(self, a, theta, terms, l):
        """Squared speed a carry from -a must start with to reach theta: over the top on the
        paper's device; with pivot friction v^2 falls until the balance angle th* (sin th* =
        f / (g_e l)) and rises after it, so the slowest point is th* clipped to [-a, theta]."""
        if not self.real:
            return np.where(a > 0.0, phys.top_speed_squared_needed(a, gravity=self.g,
                                                                   link_length=l), 0.0)
        _, g_e, f = terms
        star = phys.friction_balance_angle(f, gravity=g_e, link_length=l)
        slowest = np.clip(star, -a, theta)
        return -phys.carry_speed_squared(0.0, a, slowest, gravity=g_e, link_length=l,
                                         friction=f)

    def carry(self, k, u, offset, w, mu):
        """Stuck carry on palm k from -a_k at speed u; then the handover (k + 1 < stages)."""
        v = self.v
        px, py = v["pivot_x"][k], v["pivot_y"][k]
        l, a = v["link_length"][k], v["back_stop"][k]
        terms = self.terms(k)
        last = k + 1 == self.stages
        if last:
            theta = np.full(self.n, self.beta)
        else:
            nx, ny = self.rest_top(k + 1)
            theta = np.arccos(np.clip((ny - py) / l, -1.0, 1.0))
        self.arc_meets_others(k, theta, offset)
        self.group(k, self.guards(k, -a, u * u, offset, w, mu, terms))
        self.group(k, [("stall", _margin(u * u, self.need(a, theta, terms, l)), True)])
        if not last:
            self.group(k, [("blocked", (py + l * np.cos(a) - ny) / l, False)])
        self.group(k, [("stranded", _margin(self.fs, theta), False)])
        v2 = phys.carry_speed_squared(u, a, theta, gravity=terms[1], link_length=l,
                                      friction=terms[2])
        if self.real:
            self.inside(k, u, a, theta, offset, w, mu, terms)
            if not last:
                self.held_short(k, theta)
        slips = self.slips_before_handover(k, a, theta, mu)
        stuck_end = np.where(slips, np.arctan(mu), theta)  # the stuck part's end
        v2_stuck = np.where(slips, phys.carry_speed_squared(u, a, stuck_end, gravity=terms[1],
                                                            link_length=l), v2)
        guards = self.guards(k, stuck_end, v2_stuck, offset, w, mu, terms)
        # a slip that slides on to the handover is no failure, nor its margin the build's least
        guards = [(kind, np.where(slips, np.inf, value), closed)
                  if kind == "slip" else (kind, value, closed) for kind, value, closed in guards]
        self.group(k, guards)
        speed = np.sqrt(np.maximum(v2, 0.0))
        vx, vy = speed * np.cos(theta), -speed * np.sin(theta)
        slid, slips = offset, slips & self.alive
        if slips.any():  # the slide to the handover, or to beta (slide_to_handover)
            vx, vy, slid = self.slide_to_handover(k, slips, stuck_end, v2_stuck, theta, offset,
                                                  vx, vy, w, mu)
        # the palms parked behind, the object anywhere between its place and where it slid to
        self.group(k, self.parked_palms(k, theta, np.maximum(offset, slid), w,
                                        np.minimum(offset, slid)))
        offset = slid
        if last:
            return u, offset
        offset = px + offset + l * np.sin(theta) - nx
        self.meets(k, offset, w)
        u = self.land(k + 1, vx, vy, offset, v["object_mass"], w, mu, passed=k + 1)
        return u, offset

    # -- a slip before the handover ---------------------------------------------------------
    def slips_before_handover(self, k, a, theta, mu):
        """Builds (alive) whose stuck carry on palm k reaches the slip onset |tan th| = mu
        forward, at th_s = atan(mu), before the handover at theta: on the paper's device
        (plastic landings, no links' mass or pivot friction: the friction demand is tan th).
        The object then slides to the handover, or on the last palm to beta
        (slide_to_handover)."""
        if self.real or self.restitution > 0.0 or self.scene.pivots.damping > 0.0:
            return np.zeros(self.n, bool)
        onset = np.arctan(mu)
        return self.alive & (onset < theta) & (onset > -a) & (onset > 0.0)

    def slide_to_handover(self, k, slips, start, v2, theta, offset, vx, vy, w, mu):
        """The sliding carry of the `slips` builds on palm k from the slip onset `start` (speed
        squared v2, s' = 0) to the handover angle theta (the height at which palm k + 1's top
        is met does not depend on the slide), integrated in th (physics.slide_accelerations,
        the simulator's sliding carry) in fourth-order Runge-Kutta steps of at most SLIDE_STEP.
        The slide stays in the map where it goes on to theta: sgn s' > 0, N > 0, D > 0 and
        th' > 0 at every node, the force point (h/2) mu sgn inside the support at the end (the
        support only shrinks as the object slides on), and the arc shifted by the slide meets
        no other palm (arc_meets_others: with the unshifted one it brackets the path). Returns
        (vx, vy, offset) at the handover, the slipping builds' the slide's."""
        v, g = self.v, self.g
        i = np.flatnonzero(slips)
        l, M = v["link_length"][k][i], v["palm_mass"][k][i]
        m, f = np.broadcast_to(v["object_mass"], (self.n,))[i], np.broadcast_to(mu, (self.n,))[i]
        th0, th1 = start[i], theta[i]
        y = np.array([v2[i] / l**2, offset[i], np.zeros(len(i))])
        steps = max(2, math.ceil(float(np.max(th1 - th0)) / SLIDE_STEP))
        h = (th1 - th0) / steps
        # the direction just past the onset: at the onset s'' (s' = 0) is 0, to rounding
        sgn, ok = self._slide_direction(th0 + 1e-3 * h, np.sqrt(y[0]), m, M, f, l)

        def rates(th, y):
            omega = np.sqrt(np.maximum(y[0], 0.0))
            thdd, normal, sdd, d = phys.slide_accelerations(
                th, omega, object_mass=m, palm_mass=M, friction=f, sgn=sgn, gravity=g,
                link_length=l)
            inv = 1.0 / np.where(omega > 0.0, omega, np.nan)
            return np.array([2.0 * thdd, y[2] * inv, sdd * inv]), normal, d

        for n in range(steps + 1):
            k1, normal, d = rates(th0 + n * h, y)
            ok &= (normal > 0.0) & (d > 0.0) & ((sgn * y[2] > 0.0) | (n == 0)) & (y[0] > 0.0)
            if n == steps:
                break
            k2 = rates(th0 + (n + 0.5) * h, y + 0.5 * h * k1)[0]
            k3 = rates(th0 + (n + 0.5) * h, y + 0.5 * h * k2)[0]
            k4 = rates(th0 + (n + 1) * h, y + h * k3)[0]
            y = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        point = phys.slide_force_point(sgn, f, self.h)
        lo, hi = self.support(y[1], w if np.ndim(w) == 0 else w[i])
        ok &= (point < hi) & (point > lo)
        self.closed[i[~ok]] = False  # the simulator follows what the map does not
        slid = np.array(offset, float)
        slid[i] = y[1]
        self.arc_meets_others(k, theta, slid)
        omega = np.sqrt(np.maximum(y[0], 0.0))
        vx, vy = np.array(vx, float), np.array(vy, float)
        vx[i] = l * omega * np.cos(th1) + y[2]
        vy[i] = -l * omega * np.sin(th1)
        return vx, vy, slid

    def _slide_direction(self, theta, omega, m, M, mu, l):
        """(sgn, known) of slips from relative rest at (theta, omega): the sgn whose s'' agrees
        with it (phases.slide_direction); unknown (the simulator's) where neither does."""
        sdd = [phys.slide_accelerations(theta, omega, object_mass=m, palm_mass=M, friction=mu,
                                        sgn=sgn, gravity=self.g, link_length=l)[2]
               for sgn in (1.0, -1.0)]
        forward, back = sdd[0] > 0.0, sdd[1] < 0.0
        return np.where(forward, 1.0, -1.0), forward | back

    # -- other palms in the way -------------------------------------------------------------
    def row_boxes(self, w):
        """Every palm's contact box at rest on its back stop (docs/manipulators_model.md 1.:
        the object's reference point inside |x - cx| < R, cy - T - h < y < cy meets it), and
        the bounds that stand for many palms at once: the highest top cy and the smallest rear
        edge cx - R of the palms from each one on, and the largest x any part of the palms up
        to each one reaches at any angle (pivot x + l + R)."""
        v = self.v
        self.reach = np.broadcast_to(0.5 * (w + self.W), (self.n,))
        self.box_x, self.box_y = phys.palm_centre(v["pivot_x"], v["pivot_y"], -v["back_stop"],
                                                  v["link_length"])
        self.top_from = np.maximum.accumulate(self.box_y[::-1], axis=0)[::-1]
        self.rear_from = np.minimum.accumulate((self.box_x - self.reach)[::-1], axis=0)[::-1]
        self.front_upto = np.maximum.accumulate(v["pivot_x"] + v["link_length"] + self.reach,
                                                axis=0)
        self.hair = 1e-9 * v["link_length"].max(axis=0)  # boxes taken closed, and a hair wider

    def _others_ahead(self, first, lowest, x_end, window):
        """Builds (alive) whose path meets a resting palm from `first` on. Where every such
        palm's top lies below the path's lowest point (`lowest`), none; elsewhere palms first ..
        first + AHEAD - 1 exactly (window(j, idx) gives the path's lowest and highest points
        over the stretch where it is within palm j's box along x, lowest > highest: no such
        stretch) and the rest by a bound: their rear edges lie beyond the path's largest x,
        x_end(idx)."""
        hit = np.zeros(self.n, bool)
        if first >= self.stages:
            return hit
        idx = np.flatnonzero(self.alive & ~(self.top_from[first] < lowest - self.hair))
        if not len(idx):
            return hit
        near = np.zeros(len(idx), bool)
        for j in range(first, min(first + AHEAD, self.stages)):
            low, high = window(j, idx)
            top, hair = self.box_y[j][idx], self.hair[idx]
            near |= (low <= high) & (high > top - self.T - self.h - hair) & (low < top + hair)
        if first + AHEAD < self.stages:
            near |= ~(self.rear_from[first + AHEAD][idx] > x_end(idx))
        hit[idx] = near
        return hit

    def flight_meets_others(self, x0, vx, vy0, t_end):
        """The feed's flight (x0 + vx t, y0 + vy0 t - g t^2 / 2, 0 <= t <= t_end) comes down on
        palm 1's top; a build whose flight enters the box of another palm first is left to the
        simulator (it lands on that palm or hits its side: closed_form False). Exact for the
        palms checked one by one: x is linear in t, and y, concave, ranges over [its smaller
        end, its value at the vertex clipped to the stretch]."""
        g, y0 = self.g, self.y0
        x0, vx, vy0, t_end = (np.broadcast_to(q, (self.n,)) for q in (x0, vx, vy0, t_end))

        def window(j, i):
            moving, start, speed, end = vx[i] != 0.0, x0[i], vx[i], t_end[i]
            step = np.where(moving, speed, 1.0)
            ta, tb = ((self.box_x[j][i] + side * self.reach[i] - start) / step
                      for side in (-1.0, 1.0))
            inside = np.abs(start - self.box_x[j][i]) <= self.reach[i]
            lo = np.maximum(np.where(moving, np.minimum(ta, tb), np.where(inside, 0.0, np.inf)),
                            0.0)
            hi = np.minimum(np.where(moving, np.maximum(ta, tb), np.where(inside, end, -np.inf)),
                            end)
            y = lambda t: y0 + t * (vy0[i] - 0.5 * g * t)  # noqa: E731
            peak = y(np.clip(vy0[i] / g, lo, np.maximum(lo, hi)))
            return np.where(lo <= hi, np.minimum(y(lo), y(hi)), np.inf), peak

        lowest = np.minimum(y0, self.box_y[0])  # the parabola's lowest point is an end
        hit = self._others_ahead(1, lowest,
                                 lambda i: np.maximum(x0[i], x0[i] + vx[i] * t_end[i]), window)
        self.closed &= ~hit

    def arc_meets_others(self, k, theta, offset):
        """The carry on palm k takes the object along (P_k,x + o + l sin th, P_k,y + l cos th)
        from -a_k to the handover angle theta, where it comes down on palm k + 1's top (the
        first time it is below that top: it starts above it, else `blocked`). A build whose arc
        enters the box of a palm further on first, or reaches a palm parked behind beyond those
        parked_palms checks, is left to the simulator. Exact for the palms checked one by one
        (x grows with th, y = l cos th is unimodal); a bound for the others."""
        v = self.v
        px, py = v["pivot_x"][k], v["pivot_y"][k]
        l, a = v["link_length"][k], v["back_stop"][k]

        def end(i):  # the carry's last angle (beyond pi/2 a build is `stranded`)
            return np.clip(theta[i], -a[i], 0.5 * math.pi)

        def window(j, i):
            lo, hi = ((self.box_x[j][i] + side * self.reach[i] - px[i] - offset[i]) / l[i]
                      for side in (-1, 1))
            th_lo = np.maximum(-a[i], np.arcsin(np.clip(lo, -1.0, 1.0)))
            th_hi = np.minimum(end(i), np.arcsin(np.clip(hi, -1.0, 1.0)))
            th_hi = np.where((lo <= 1.0) & (hi >= -1.0), th_hi, -np.inf)
            low = py[i] + l[i] * np.minimum(np.cos(th_lo), np.cos(th_hi))
            peak = py[i] + l[i] * np.cos(np.clip(0.0, th_lo, np.maximum(th_lo, th_hi)))
            return np.where(th_lo <= th_hi, low, np.inf), peak

        hit = np.zeros(self.n, bool)
        if k + 2 < self.stages:  # the arc's lowest point is an end (cos is unimodal): the
            # start on palm k's top, or the handover at palm k + 1's (theta in [-a, pi/2])
            lowest = np.minimum(self.box_y[k], self.box_y[k + 1])
            hit = self._others_ahead(k + 2, lowest,
                                     lambda i: px[i] + offset[i] + l[i] * np.sin(end(i)), window)
        behind = k - min(k, self.parked) - 1
        if behind >= 0:  # the arc's smallest x is at its start
            hit |= self.alive & ~(self.front_upto[behind] < self.box_x[k] + offset)
        self.closed &= ~hit

    def held_short(self, k, theta):
        """Palm k, empty after the handover at theta, may stop short of its front stop where
        its pivot friction holds it (tau >= (M + n m_l / 2) g l sin th somewhere on [theta,
        pi/2], i.e. at theta): the palms parked behind are then not where the map takes them
        (at their front stops), and the build is left to the simulator."""
        v = self.v
        weight = (v["palm_mass"][k] + 0.5 * self.scene.links.count * v["link_mass"][k]) * (
            self.g * v["link_length"][k])
        self.closed &= ~(self.alive & (v["pivot_friction"][k] >= weight * np.sin(theta)))

    def inside(self, k, u, a, theta, offset, w, mu, terms):
        """With links and pivots the carry's guards are judged at its ends (docs/physics.md,
        section 2.1), where on the paper's device they are monotone or convex in between. Here
        a build is left to the simulator (closed_form False) unless its whole-carry rows hold:
        lift-off, slip and tip over INSIDE_CELLS cells with the curvature bound (the NLP's,
        physics.carry_contact_nodes), lower bounds of each row over the carry (a row below 0
        fails the build on the map: that lift-off, slip or tip, closed form False); and where
        the guards at the cells' inner ends are lower than at both ends (its smallest margin
        is inside the carry)."""
        l = self.v["link_length"][k]
        kw = dict(gravity=terms[1], friction=terms[2], link_length=l)  # the carry's speed
        nodes, bend = phys.carry_contact_nodes(u, a, start=a, end=theta, fastest_u2=u * u,
                                               gravity=self.g, carry_gravity=terms[1],
                                               friction=terms[2], link_length=l,
                                               cells=INSIDE_CELLS)
        lo, hi = self.support(offset, w)
        half_h, g = 0.5 * self.h, self.g
        rows = []  # (failure, the row's least over the carry in g (object half widths for tip))
        for kind, c1, c2, unit in (("lift_off", 1.0, 0.0, g), ("slip", mu, -1.0, g),
                                   ("slip", mu, 1.0, g), ("tip", hi, half_h, g * self.half_w),
                                   ("tip", -lo, -half_h, g * self.half_w)):
            rows.append((kind, phys.carry_row_least(nodes, c1, c2, bend) / unit))
        held = np.logical_and.reduce([value >= 0.0 for _, value in rows])
        # a row not proven: the map's account is that failure, the simulator's the verdict
        self.group(k, [(kind, np.where(value >= 0.0, np.inf, value), False)
                       for kind, value in rows])
        ends = [self.guards(k, th, v2, offset, w, mu, terms) for th, v2 in (
            (-a, u * u), (theta, phys.carry_speed_squared(u, a, theta, **kw)))]
        low = np.minimum.reduce([c[1] for c in ends[0] + ends[1]])
        inner = np.full(self.n, np.inf)
        for i in range(1, INSIDE_CELLS):
            th = -a + i * (theta + a) / INSIDE_CELLS
            v2 = phys.carry_speed_squared(u, a, th, **kw)
            for _, value, _ in self.guards(k, th, v2, offset, w, mu, terms):
                np.fmin(inner, value, out=inner)
        self.closed &= ~(self.alive & ~(held & (inner >= low)))

    def parked_palms(self, k, theta, offset, w, low=None):
        """Clearance, in link lengths, to the palms 1 .. parked places behind palm k, each at
        its front stop (taken as there from the handover on: conservative, so a failure here
        is left to the simulator, which follows the timing), the object anywhere on the palm
        from `low` (default: offset; a slide along the palm) to `offset`. The clearance
        is at least the distance the palm stays behind the object from the start of the carry
        (physics.parked_palm_clearance's `behind`), so it is computed in full only where that
        bound, in link lengths, is under the build's smallest margin so far: elsewhere the
        clearance cannot be the build's smallest margin, and the bound stands for it."""
        v = self.v
        l, a = v["link_length"][k], v["back_stop"][k]
        sf, cf = math.sin(self.fs), math.cos(self.fs)
        reach = 0.5 * (w + self.W)
        low = offset if low is None else low
        back = -l * np.sin(a)
        out = []
        for n in range(1, min(k, self.parked) + 1):
            j = k - n
            lj = v["link_length"][j]
            # palm j's pivot and link as palm k's link and an effective pitch (exact)
            pitch_x = v["pivot_x"][k] - v["pivot_x"][j] + (l - lj) * sf
            behind = back - (l * sf - pitch_x + reach - low)
            near = np.flatnonzero(self.alive & (behind < l * self.worst))
            gap = behind
            if len(near):
                pitch_y = v["pivot_y"][j] - v["pivot_y"][k] + (lj - l) * cf
                gap = behind.copy()
                gap[near] = phys.parked_palm_clearance(
                    1, alpha=a[near], theta_end=theta[near], link_length=l[near],
                    front_stop=self.fs, pitch_x=pitch_x[near], pitch_y=pitch_y[near],
                    offset_lo=low[near], offset_hi=offset[near],
                    reach=np.broadcast_to(reach, (self.n,))[near], depth=self.T + self.h)
            out.append(("blocked", gap / l, False))
        return out


def _count(deviations: dict) -> int:
    sizes = {np.shape(d)[0] for d in deviations.values()}
    if len(sizes) != 1:
        raise ValueError("run_builds needs deviations of one number of builds (and at least "
                         "one quantity)")
    return sizes.pop()


def _parked_rows(scene, design, stages) -> int:
    """Palms behind the carrying one that can reach the carried object: those within
    2 l + W + w of its pivot along the row (nominal pitch), at most PARKED_CAP."""
    pitch_x = float(phys.pitch(design.alpha, design.beta, design.link_length)[0])
    far = 2.0 * design.link_length + scene.palm.width + scene.body.width
    reach = math.ceil(far / pitch_x) if pitch_x > 0.0 else PARKED_CAP
    return max(0, min(stages - 1, reach, PARKED_CAP))


def meets_another_palm(run) -> bool:
    """A simulated run (sim.manipulators' result) whose object met a palm other than the next
    one before any lift-off: the feed came down on (or hit) a palm other than the first, a palm
    handed it past the next palm, or a carry hit the side of a palm other than the next. The
    map leaves every such build to the simulator (tests/test_tolerances.py checks it)."""
    import re

    current = 0  # the palm carrying the object (1-based); 0 in the feed's flight
    for event in run.events:
        if event.kind == "lift_off":
            return False
        palms = [int(p) for p in re.findall(r"palm (\d+)", event.detail or "")]
        if event.kind == "landing" and current == 0:
            if event.after.get("palm") != 1:
                return True
            current = 1
        elif event.kind == "handover":
            if palms[-1] != current + 1:
                return True
            current = palms[-1]
        elif event.kind == "blocked" and palms and palms[-1] != current + 1:
            return True
        elif event.kind == "skipped_palm":  # it came onto a palm beyond the next
            return True
    return False


def unbuildable_part(values: dict):
    """(stage, what) of one build's first part no workshop can make (UNBUILDABLE; stage 0 for
    a lot's), or None. values: build_values of that build alone."""
    from .quantities import QUANTITIES

    for key, test, needs in UNBUILDABLE:
        row = np.ravel(values[key])
        bad = np.flatnonzero(test(row))
        if len(bad):
            k, unit = int(bad[0]), QUANTITIES[key].unit
            whose = f"manipulator {k + 1}'s " if np.ndim(values[key]) == 2 else "the lot's "
            return (k + 1 if np.ndim(values[key]) == 2 else 0,
                    f"{whose}{key} = {row[k]:.6g} {unit} cannot be built (needs {needs})")
    return None


def invalid_result(unbuilt, accuracy):
    """The run of a build with a part no workshop can make: it fails before it starts, 0 stages
    passed, as the map counts it (invalid_part)."""
    from ...accuracy import accuracy as resolve
    from ...sim.core import Event, Outcome, SimulationResult

    stage, detail = unbuilt
    event = Event(0.0, INVALID, stage, {}, {}, detail, failure=True)
    return SimulationResult(scene="manipulators", outcome=Outcome(False, 0, event), stages=[],
                            events=[event], accuracy=resolve(accuracy))


def simulate_build(scene, design, deviations: dict, stages: int, *, accuracy="default",
                   record_trajectory: bool = False, allow_skips: bool = False):
    """The event simulator on one build (deviations of one build: arrays of 1 row), every
    part as drawn: pivots as offsets, link lengths, back stops, palm masses, link masses and
    pivot friction torques as
    sim.manipulators.geometry.Parts, the lot's values in the scene. A build whose values no
    scene can hold (a negative mass, say) is refused (sim.core.SimulationRefused)."""
    import dataclasses

    import pydantic

    from ...sim.core import SimulationRefused
    from .model import ManipulatorOffset
    from .sim import simulate_manipulators
    from .sim.geometry import Parts

    v = build_values(scene, design, deviations, stages, 1)
    unbuilt = unbuildable_part(v)
    if unbuilt is not None:
        return invalid_result(unbuilt, accuracy)
    dx = deviations.get("pivot_x", np.zeros((1, stages)))
    dy = deviations.get("pivot_y", np.zeros((1, stages)))
    dx, dy = (np.broadcast_to(np.reshape(d, (1, -1)), (1, stages))[0] for d in (dx, dy))
    offsets = tuple(ManipulatorOffset(manipulator=k + 1, dx=float(dx[k]), dy=float(dy[k]))
                    for k in range(stages) if dx[k] or dy[k])
    parts = Parts(link_length=tuple(v["link_length"][0]), back_stop=tuple(v["back_stop"][0]),
                  palm_mass=tuple(v["palm_mass"][0]),
                  link_mass=tuple(v["link_mass"][0]) if "link_mass" in deviations else (),
                  pivot_friction=(tuple(v["pivot_friction"][0])
                                  if "pivot_friction" in deviations else ()))
    try:
        built = dataclasses.replace(
            scene,
            body=dataclasses.replace(scene.body, mass=float(v["object_mass"][0]),
                                     width=float(v["object_width"][0])),
            palm=dataclasses.replace(scene.palm, friction=float(v["friction"][0])),
            initial=dataclasses.replace(
                scene.initial, position=(float(v["feed_x"][0]), scene.initial.position[1]),
                velocity=(float(v["feed_vx"][0]), float(v["feed_vy"][0]))))
    except pydantic.ValidationError as error:
        raise SimulationRefused(f"this build cannot be made: {error.errors()[0]['msg']}") \
            from None
    return simulate_manipulators(built, design, stages=stages, offsets=offsets,
                                 accuracy=accuracy, record_trajectory=record_trajectory,
                                 parts=parts, allow_skips=allow_skips)
