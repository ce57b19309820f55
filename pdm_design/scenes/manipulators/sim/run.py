"""One run of the manipulators event simulator: bookkeeping, flights, impacts and stuck carries.

The numerically integrated phases (sliding carry, bouncing) are in ode.py; the pure phase
functions in phases.py; the geometry in geometry.py. Each phase method returns the
next phase as a callable, or None when the run has ended (the driver loops until then).
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from ....sim.core import Event, Outcome, SimulationResult
from ....sim.numerics import brentq
from .. import physics as phys
from . import phases as ph
from .bridge import BridgePhases
from .edgeslide import EdgeSlidingPhases
from .geometry import Arc, Ballistic, build_row, first_contact, support_words
from .liftoff import LiftOffPhases
from .ode import OdePhases
from .pushing import PushingPhases
from .pushslide import SlidingPushPhases
from .rocking import RockingPhases
from .stepped import SteppedPhases
from .swinging import SwingingPhases
from .tumbling import TumblingPhases
from .twocontact import TwoContactPhases

FALL_DEPTH = 3.0  # link lengths below the lowest pivot where a falling object is given up
ZENO_FRACTION = 1e-4  # bounces separating slower than this times sqrt(g l) end in contact
PHASE_TIME = 200.0  # longest integrated phase, in units of sqrt(l / g)
EVENTS_PER_STAGE = 2000  # event budget per manipulator (guards against chattering)
CHATTER_EVENTS, CHATTER_SPAN = 50, 1e-6  # so many events within so many s: chattering


class Run(OdePhases, LiftOffPhases, RockingPhases, SwingingPhases, TumblingPhases,
          EdgeSlidingPhases, PushingPhases, SlidingPushPhases, TwoContactPhases,
          BridgePhases, SteppedPhases):
    """Mutable bookkeeping of one run around the pure phase functions."""

    def __init__(self, scene, design, stages, offsets, acc, record, parts=None,
                 allow_skips=False):
        self.row = build_row(scene, design, stages, offsets, parts)
        self.acc, self.record = acc, record
        self.g, self.l = scene.gravity, design.link_length
        self.m = scene.body.mass
        self.M = scene.body.mass / design.mass_ratio
        self.mu, self.eps = scene.palm.friction, scene.palm.restitution
        self.alpha, self.beta, self.fs = design.alpha, design.beta, scene.palm.front_stop
        self.h = scene.body.height
        self.n = stages
        self.initial = scene.initial
        # every manipulator's own link, back stop and palm mass (geometry.Parts; nominal: all
        # the design's); self.l and self.alpha stay the design's, for the run's scales
        self.ls, self.alphas = self.row.link_lengths, self.row.back_stops
        self.Ms = self.row.palm_masses or (self.M,) * stages
        self.plain = (scene.plain_mechanism and not any(self.row.link_masses)
                      and not any(self.row.pivot_frictions))
        if not self.plain:  # links and pivots (docs/physics.md, section 2.1), palm by palm
            self._mechanism(scene, design)
        else:  # the paper's device as phases.Swing (l th'' = g sin th), for integrated phases
            self.swings_alone = [ph.Swing(M, M, 0.0, 0.0, self.g, l)
                                 for M, l in zip(self.Ms, self.ls)]
            self.swings_loaded = [ph.Swing(M + self.m, M + self.m, 0.0, 0.0, self.g, l)
                                  for M, l in zip(self.Ms, self.ls)]
        self.qs = tuple(self.m / M for M in self.Ms)
        self.rest_angle = [-a for a in self.alphas]
        self.rest_since = [-math.inf] * stages
        self.swinging: list[int] = []  # released palms, some perhaps at rest by now
        self.y_floor = min(p[1] for p in self.row.pivots) - FALL_DEPTH * self.l
        self._pivot_order = sorted(range(stages), key=lambda j: self.row.pivots[j][0])
        self._pivot_x = [self.row.pivots[j][0] for j in self._pivot_order]
        self._boxes: dict = {}
        # (the object's larger side: it may come to lie on either, tumbling.TumblingPhases)
        self._reach = (2.0 * max(self.ls) + 1.5 * self.row.palm_width
                       + max(self.row.body_width, self.h))
        self.face = 0  # quarter turns clockwise from its base to the face it lies on
        self._left_angle = None  # the angle of the palm the object last left tumbling
        self.events: list[Event] = []
        self.palm_events: list[Event] = []
        self.stages: list[dict] = []
        self.passed = 0  # palms that carried the object forward in order (handed it on)
        self.at = -1  # the palm the object last came onto (-1: the feed)
        self.allow_skips = allow_skips
        self.failure: Event | None = None
        self.completed = False
        self.traj = {k: [] for k in ("time", "x", "y", "vx", "vy", "theta", "manipulator")}
        self.zeno_speed = ZENO_FRACTION * math.sqrt(self.g * self.l)
        self.phase_time = PHASE_TIME * math.sqrt(self.l / self.g)
        self._planned: dict = {}  # a palm swinging from rest: its planned stop (palm event)
        self._launched: dict = {}  # a palm swinging alone: (t, th, th') it was released at
        self.from_rest = self._release_past_vertical()
        # followed while they swing (swinging.py) until the object meets one
        self.unmet = set(self.from_rest)
        self.pushed: set[int] = set()  # palms the carried object pushed off their back stops
        self._free = {k: (0.0, -self.alphas[k], 0.0) for k in self.from_rest}

    def _release_past_vertical(self):
        """Palms whose back stop is past the vertical (alpha_k < 0: gravity pulls them forward,
        l th'' = g sin th > 0 at -alpha_k) swing forward from rest as soon as the row is built,
        to their front stop (or, on real links, to where pivot friction holds them; a palm
        that friction holds at its back stop stays there). A back stop exactly vertical is taken
        as a rest (the equilibrium, unstable: a landing pushes the palm forward). Returns the
        palms released so."""
        out = []
        for k, a in enumerate(self.alphas):
            if a >= 0.0 or (not self.plain and ph.held_by_friction(-a, self.swings_alone[k])):
                continue
            events = len(self.palm_events)
            self._release(k, 0.0, -a, 0.0)
            if len(self.palm_events) > events:
                self._planned[k] = self.palm_events[-1]
            out.append(k)
        return tuple(out)

    def _swinging_from_rest(self, t, j):
        """The object reaches palm j at time t at the end of a phase that does not follow the
        palms swinging from rest (swinging.py; a rocking object): a palm up to j released from
        rest at the build (_release_past_vertical), not yet met and still swinging then is one
        the object may have met or passed unseen: the run fails (`swinging_palm`). Returns the
        1-based palm or None."""
        for k in self.unmet:
            if k <= j and self.rest_since[k] > t:
                return k + 1
        return None

    def _mechanism(self, scene, design):
        """Links and pivots, every palm its own (its link length, palm mass, link mass and
        pivot friction): the impacts see the palm-plus-links mass felt along the swing (mass
        ratio m / (M + J): self.Ms becomes M + J), the swings their inertia, weight and pivot
        torques (self.swings_alone, self.swings_loaded: phases.Swing)."""
        row, damping = self.row, scene.pivots.damping
        self.swings_alone, self.swings_loaded, felt_masses = [], [], []
        for k in range(self.n):
            l = self.ls[k]
            mech = scene.mechanism(
                link_mass=row.link_masses[k] if row.link_masses else None,
                friction_torque=row.pivot_frictions[k] if row.pivot_frictions else None,
                length_scale=l / self.l if l != self.l else None)
            ratio = self.m / self.Ms[k] if row.palm_masses else design.mass_ratio
            felt, g_p, _ = phys.palm_terms(ratio, object_mass=self.m, gravity=self.g,
                                           link_length=l, **mech)
            weight, torque = felt * g_p / self.g, mech["friction_torque"]
            self.swings_alone.append(ph.Swing(felt, weight, torque, damping, self.g, l))
            self.swings_loaded.append(ph.Swing(felt + self.m, weight + self.m, torque, damping,
                                               self.g, l))
            felt_masses.append(felt)
        self.Ms = tuple(felt_masses)

    def _slide_params(self, sgn, k):
        """The sliding carry's parameters (phases.SlideParams) on palm k, slip direction sgn."""
        if self.plain:
            return ph.SlideParams(self.m, self.Ms[k], self.mu, self.g, self.ls[k], sgn)
        sw = self.swings_alone[k]
        return ph.SlideParams(self.m, self.Ms[k], self.mu, self.g, self.ls[k], sgn, sw.weight,
                              sw.torque, sw.damping)

    # ------------------------------------------------------------ driver and bookkeeping
    def run(self) -> SimulationResult:
        (x, y), (vx, vy) = self.initial.position, self.initial.velocity
        step = lambda: self._flight(0.0, x, y, vx, vy, stage=0)  # noqa: E731
        budget = EVENTS_PER_STAGE * (self.n + 1)
        while step is not None:
            budget -= 1
            if budget < 0 or self._chattering():
                t = self.events[-1].time if self.events else 0.0
                self._fail(t, "too_many_events", 0, {},
                           "event budget exhausted (chattering?)" if budget < 0 else
                           f"{CHATTER_EVENTS} events within {CHATTER_SPAN:g} s (chattering)")
                break
            step = step()
        t_end = self.events[-1].time if self.events else 0.0
        log = sorted(self.events + [e for e in self.palm_events if e.time <= t_end],
                     key=lambda e: e.time)
        passed = self.passed if self.completed else min(self.passed, self.n - 1)
        outcome = Outcome(completed=self.completed, stages_passed=passed,
                          failure=self.failure)
        traj = {k: list(v) for k, v in self.traj.items()} if self.record else {}
        stages = [rec if all(type(v) in _PLAIN for v in rec.values())
                  else {k: _plain(v) for k, v in rec.items()} for rec in self.stages]
        return SimulationResult("manipulators", outcome, stages, log, self.acc, traj)

    def _chattering(self) -> bool:
        """The last CHATTER_EVENTS events all within CHATTER_SPAN: impacts without end (a
        rocking object caught again and again 7e-9 s apart ran to the event budget, minutes
        of a yield)."""
        events = self.events
        return (len(events) >= CHATTER_EVENTS
                and events[-1].time - events[-CHATTER_EVENTS].time < CHATTER_SPAN)

    def _log(self, time, kind, stage, before, after, detail="", failure=False):
        if self.face and "x" in before and "face" not in before:  # it lies on another face
            before = dict(before, face=self.face)
        ev = Event(float(time), kind, int(stage), _floats(before), _floats(after), detail, failure)
        self.events.append(ev)
        if failure:
            self.failure = ev
        return ev

    def _fail(self, time, kind, stage, before, detail):
        self._log(time, kind, stage, before, {}, detail, failure=True)
        return None

    def _rec(self, t, x, y, vx, vy, theta, manip):
        if not self.record:
            return
        t = np.atleast_1d(np.asarray(t, dtype=float))
        for key, val in (("time", t), ("x", x), ("y", y), ("vx", vx), ("vy", vy),
                         ("theta", theta), ("manipulator", manip)):
            self.traj[key].extend(np.broadcast_to(np.asarray(val, dtype=float), t.shape).tolist())

    def _obstacles(self, t, carrier=None, near=None):
        """Contact boxes of palms at rest by time t (not the carrier), optionally only those
        within reach of an object carried by a palm whose pivot is at x = near (the object is
        within l + W/2 of that pivot, a palm's box within l + (W + w)/2 of its own pivot)."""
        candidates = range(self.n) if near is None else self._near(near)
        out = []
        cache, rest_since, rest_angle = self._boxes, self.rest_since, self.rest_angle
        for j in candidates:  # (inline: this runs every phase, at every palm within reach)
            if j == carrier or rest_since[j] > t:
                continue
            box = cache.get((j, rest_angle[j]))
            out.append(self._rest_box(j) if box is None else box)
        return out

    def _near(self, x):
        """Palms whose pivot is within the run's reach of x (in pivot order along x)."""
        lo = bisect.bisect_left(self._pivot_x, x - self._reach)
        hi = bisect.bisect_right(self._pivot_x, x + self._reach)
        return self._pivot_order[lo:hi]

    def _rest_box(self, j):
        """Contact box of palm j at its rest angle (a palm at rest keeps its box until it moves
        again, so boxes are cached by palm and angle)."""
        key = (j, self.rest_angle[j])
        box = self._boxes.get(key)
        if box is None:
            box = self._boxes[key] = self.row.box(j, self.rest_angle[j])
        return box

    def _release(self, k, t, theta, w):
        """Palm k, now empty, swings on alone from (theta, w) to one of its stops; it is an
        obstacle again once it is there."""
        if self.plain:
            dt, stop, speed = ph.free_palm_arrival(theta, w, gravity=self.g,
                                                   link_length=self.ls[k],
                                                   back_stop=-self.alphas[k],
                                                   front_stop=self.fs)
        else:
            dt, stop, speed = self._free_swing_arrival(k, theta, w)
        self._launched[k] = (t, theta, w / self.ls[k])
        self.rest_angle[k], self.rest_since[k] = stop, t + dt
        if len(self.swinging) > 2:  # palms at rest by now are dropped now and then
            self.swinging = [j for j in self.swinging if self.rest_since[j] > t]
        self.swinging.append(k)
        if math.isfinite(dt):
            kind = ("front_stop" if stop == self.fs else "back_stop" if stop == -self.alphas[k]
                    else "pivot_friction_stop")
            self.palm_events.append(Event(
                float(t + dt), kind, k + 1, {"theta": float(stop), "omega": speed / self.ls[k]},
                {"theta": float(stop), "omega": 0.0}, f"empty palm {k + 1} stopped"))

    def _arrivals(self, t0, t1, carrier):
        """Palms (not the carrier) that come to rest at a time in (t0, t1): a phase that does
        not end before the first of them is split there, so that it is an obstacle from then
        on (the swinging palm itself is not one)."""
        rest = self.rest_since
        return [j for j in self.swinging if t0 < rest[j] < t1 and j != carrier]

    def _next_arrival(self, t0, carrier):
        """Time the first palm still swinging at t0 comes to rest (None: none does)."""
        return min((self.rest_since[j] for j in self._arrivals(t0, math.inf, carrier)),
                   default=None)

    def _on_palm(self, k, theta, omega, s, sd=0.0):
        x, y, vx, vy = ph.object_state_on_palm(self.row.pivots[k], theta, omega, s, sd, self.ls[k])
        return {"x": x, "y": y, "vx": vx, "vy": vy, "theta": theta, "omega": omega, "offset": s}

    def _stage(self, k):
        return self.stages[-1] if self.stages and self.stages[-1]["manipulator"] == k + 1 else None

    # ------------------------------------------------------------ flight among resting palms
    def _flight(self, t0, x, y, vx, vy, stage):
        tracked = self._tracked(t0)
        if tracked:  # palms swing from rest: integrated with them (swinging.py)
            return self._flight_swinging(t0, x, y, vx, vy, stage, tracked)
        path = Ballistic(t0, x, y, vx, vy, self.g)
        roots = path.roots_y(self.y_floor, t0, math.inf)
        t_floor = roots[-1] if y > self.y_floor and roots else t0
        entry = first_contact(path, self._obstacles(t0), t0, t_floor)
        t_hit = entry.tau if entry else t_floor
        arriving = [self.rest_since[j] for j in self._arrivals(t0, t_hit, None)]
        if arriving:  # a swinging palm comes to rest during the flight: it becomes an obstacle
            t1 = min(arriving)
            self._rec_flight(path, t0, t1)
            return lambda: self._flight(t1, *path.at(t1), stage=stage)
        self._rec_flight(path, t0, t_hit)
        xe, ye, vxe, vye = path.at(t_hit)
        state = {"x": xe, "y": ye, "vx": vxe, "vy": vye}
        if entry is None:  # (after a lift-off with no landing since: the object missed)
            kind = "missed" if self.events and self.events[-1].kind == "lift_off" else "fell_clear"
            return self._fail(t_hit, kind, self.passed + 1, state,  # the stage that fails
                              f"fell {FALL_DEPTH:g} link lengths below the lowest pivot")
        j = entry.palm
        if entry.kind != "top":
            where = "side" if entry.kind == "side" else "inside"
            why = f"hit the {where} of palm {j + 1} in flight"
            return (self._stepped(t_hit, (xe, ye + 0.5 * self.h, vxe, vye, 0.0, 0.0), {},
                                  state, why)
                    or self._fail(t_hit, "blocked", self.passed + 1, state, why))
        return self._impact(t_hit, j, self.rest_angle[j], 0.0, xe, ye, vxe, vye,
                            log_as="landing", stage=stage, before=state, at_rest=True)

    def _rec_flight(self, path, t0, t1):
        if self.record and t1 > t0:
            ts = np.linspace(t0, t1, 60)
            x, y, vx, vy = path.at(ts)
            self._rec(ts, x, y, vx, vy, np.nan, 0)

    # ------------------------------------------------------------ impacts
    def _resolve(self, j, vx, vy, w, theta, eps, at_rest):
        """Impact on palm at theta; a palm at rest on a stop that the impulse pushes into the stop
        is held there (the stop takes the impulse: infinite effective mass)."""
        imp = ph.impact(vx, vy, w, theta, m=self.m, mass_ratio=self.qs[j], mu=self.mu, eps=eps)
        if imp.jam or not at_rest:
            return imp, False
        if (theta <= -self.alphas[j] and imp.w < 0.0) or (theta >= self.fs and imp.w > 0.0):
            return ph.impact(vx, vy, 0.0, theta, m=self.m, inv_M=0.0, mu=self.mu, eps=eps), True
        return imp, imp.w == 0.0

    def _impact(self, t, j, theta, w, x, y, vx, vy, *, log_as, stage, before, at_rest):
        """The object meets palm j (angle theta, speed w) from above: impact, then what follows.

        log_as: "landing" (from a flight), "handover" (from the previous palm), "rebound" (onto
        the palm it bounced off), "stop" (its palm has just been stopped by the front stop)."""
        if log_as in ("landing", "handover") and self._comes_onto(j):
            return self._fail(t, "skipped_palm", self.at + 2, before,
                              f"the object flew over palm {self.at + 2} and came onto palm "
                              f"{j + 1}")
        imp, held = self._resolve(j, vx, vy, w, theta, self.eps, at_rest)
        gn = imp.vy + imp.w * math.sin(theta)
        bounce = self.eps > 0.0 and not imp.jam and gn > self.zeno_speed
        if self.eps > 0.0 and not imp.jam and not bounce:  # too slow a bounce: contact persists
            imp, held = self._resolve(j, vx, vy, w, theta, 0.0, at_rest)
        if imp.jam:
            return self._fail(t, "impact_jam", j + 1, before,
                              f"landing on palm {j + 1}: no consistent sliding impact")
        cx, y = self.row.palm_top(j, theta)  # the contact is on the palm's top by definition
        offset = x - cx
        after = {"x": x, "y": y, "vx": imp.vx, "vy": imp.vy, "theta": theta,
                 "omega": imp.w / self.ls[j], "offset": offset, "palm": j + 1}
        rec = self._stage(j)
        if log_as == "handover" or (log_as == "landing" and rec is None):
            rec = self._new_stage(j, t, offset, vx, vy, imp)
        elif log_as in ("landing", "rebound"):
            rec["bounces"] += 1
        if log_as == "handover":
            self._log(t, "handover", stage, before, after, f"palm {stage} -> palm {j + 1}")
        elif log_as == "stop":
            self._log(t, "front_stop", j + 1, before, after,
                      f"palm {j + 1} stopped carrying the object")
        else:
            self._log(t, "landing", j + 1, before, after,
                      f"on palm {j + 1} at {offset:+.4g} m from its centre, "
                      f"{'sticking' if imp.stick else 'sliding'}")
        if rec is not None and not imp.stick:
            rec["slipped"] = True
        lo, hi = self.row.support(offset)
        xb = ph.impact_force_point(imp.pt, imp.pn, self.h) if imp.pn > 0.0 else 0.0
        if not lo <= xb <= hi:
            if self.eps == 0.0:  # the object turns about the support's end (rocking.py)
                hold = None
                if at_rest or held:
                    hold = "back" if theta <= -self.alphas[j] else "front"
                step = self._rock_landing(t, j, theta, w, vx, vy, offset, xb, after, hold, rec)
                if step is not None:
                    return step
            return self._fail(t, "tip", j + 1, after,
                              f"the impulse {support_words(xb, (lo, hi))}")
        if bounce:
            self._log(t, "bounce", j + 1, before, after, f"separating at {gn:.4g} m/s")
            if held:
                self.rest_angle[j], self.rest_since[j] = theta, t
                if self._bouncing_in_place(j, x, y, imp.vx, t):
                    hops = self._hops_left(imp.vy)
                    if hops > EVENTS_PER_STAGE // 2:  # fewer are followed event by event
                        return self._settle_in_place(t, j, theta, imp.vy, hops, after)
                return lambda: self._flight(t, x, y, imp.vx, imp.vy, stage=j + 1)
            self.rest_since[j] = math.inf
            return lambda: self._bouncing(t, j, x, y, imp.vx, imp.vy, theta, imp.w / self.ls[j])
        if held:
            self.rest_angle[j], self.rest_since[j] = theta, t
            # a sticking impact leaves the object at rest on the held palm: exactly 0, not the
            # rounding residue of vx + p_t (1e-17 m/s would be read as a slide)
            return self._held_slide(t, j, theta, offset, 0.0 if imp.stick else imp.vx, after)
        if imp.w < 0.0:
            return self._fail(t, "stall", j + 1, after,
                              f"the impact drives palm {j + 1} backwards with the object")
        self.rest_since[j] = math.inf
        if imp.stick:
            return lambda: self._stuck(t, j, theta, imp.w, offset)
        sd = imp.vx - imp.w * math.cos(theta)
        return lambda: self._sliding(t, j, theta, imp.w / self.ls[j], offset, sd)

    def _comes_onto(self, j):
        """Bookkeeping of the object coming onto palm j (a landing or a handover) from palm
        self.at. The next palm in order: the one it came from has carried it forward
        (stages_passed). Back onto the same palm (after a lift-off or a bounce), or onto one
        behind: nothing passed. Further on: the palms between were flown over; True (the run
        fails, skipped_palm, the palm it came from counted as passed) unless skips are
        allowed, where they count as passed too."""
        if j > self.at + 1 and not self.allow_skips:
            self.passed = max(self.passed, self.at + 1)
            return True
        if j > self.at:
            self.passed = max(self.passed, j)
        self.at = j
        return False

    def _bouncing_in_place(self, j, x, y, vx, t):
        """True when the object has just bounced straight up off palm j, held by a stop, at the
        point where its previous bounce (also straight up, off the same held palm) left it, and
        no palm is still swinging: every later flight is then the same vertical hop, lower by
        the restitution, and nothing can change that (the free palms are all at rest)."""
        here = (j, x, y) if vx == 0.0 else None
        again = here is not None and here == getattr(self, "_hop", None)
        self._hop = here
        return again and all(r <= t or r == math.inf for r in self.rest_since)

    def _hops_left(self, vy):
        """Hops in place still to come, this one included: those leaving faster than the Zeno
        speed (vy eps^k > zeno_speed); inf with restitution 1."""
        if self.eps >= 1.0:
            return math.inf
        return math.floor(math.log(self.zeno_speed / vy) / math.log(self.eps)) + 1

    def _settle_in_place(self, t, j, theta, vy, hops, state):
        """Closed form of an object hopping in place on a held palm: the same vertical hop at
        vy, eps vy, eps^2 vy, ... until a hop would leave slower than the Zeno speed (as the
        event loop would do hop by hop, in 2 vy (1 - eps^n) / (g (1 - eps)) for n hops); then
        the object rests on the held palm. With restitution 1 it hops forever: refused."""
        where = "back" if theta <= -self.alphas[j] else "front"
        kind = "stall" if where == "back" else "stranded"
        if math.isinf(hops):
            return self._fail(t, kind, j + 1, state,
                              f"restitution 1: the object hops in place on palm {j + 1}, held by "
                              f"its {where} stop, at {vy:.4g} m/s forever")
        # 1 - eps^n without cancellation for eps near 1
        rest = -math.expm1(hops * math.log1p(self.eps - 1.0))
        t_rest = t + 2.0 * vy * rest / (self.g * (1.0 - self.eps))
        rec = self._stage(j)
        if rec is not None:
            rec["bounces"] = int(rec["bounces"]) + hops
        return self._fail(t_rest, kind, j + 1, state,
                          f"the object hops in place on palm {j + 1}, held by its {where} stop: "
                          f"{hops} hops from {vy:.4g} m/s (restitution {self.eps:.12g}), then it "
                          "rests on the palm")

    def _new_stage(self, j, t, offset, vx, vy, imp):
        loss = (0.5 * self.m * (vx * vx + vy * vy - imp.vx ** 2 - imp.vy ** 2)
                - 0.5 * self.Ms[j] * imp.w ** 2)
        rec = {"manipulator": j + 1, "landing_time": t, "landing_offset": offset,
               "landing_vx": vx, "landing_vy": vy, "landing_speed": imp.w,
               "landing_stick": bool(imp.stick), "impact_loss": loss,
               "handover_time": None, "handover_speed": None, "handover_angle": None,
               "handover_vx": None, "handover_vy": None, "release_speed": None,
               "slipped": not imp.stick, "bounces": 0}
        self.stages.append(rec)
        return rec

    def _held_slide(self, t, j, theta, s, sd, state):
        """The object on palm j held by a stop (static, horizontal top), sliding at sd.

        At the back stop friction may drag the palm off its stop (then a sliding carry starts);
        otherwise the object decelerates at mu g and stops on the palm (stall at the back stop,
        stranded at the front stop), or reaches the palm's end first (tip over the edge when
        mu > 0, slid_off when frictionless)."""
        at_back = theta <= -self.alphas[j]
        stuck_kind = "stall" if at_back else "stranded"
        where = f"palm {j + 1} held by its {'back' if at_back else 'front'} stop"
        if sd == 0.0:
            return self._fail(t, stuck_kind, j + 1, state, f"the object rests on {where}")
        sgn = math.copysign(1.0, sd)
        if at_back:
            p = self._slide_params(sgn, j)
            if ph.slide_accelerations(theta, 0.0, p)[0] > 0.0:  # friction drags the palm along
                self.rest_since[j] = math.inf
                return lambda: self._sliding(t, j, theta, 0.0, s, sd)
        xb = ph.slide_force_point(sgn, self.mu, self.h)
        lo, hi = self.row.support(s)
        if not lo <= xb <= hi:
            return self._fail(t, "tip", j + 1, state, f"sliding on {where}: friction tips it")
        dist = abs(sgn * 0.5 * self.row.palm_width - xb - s)
        decel = self.mu * self.g
        if decel > 0.0 and sd * sd < 2.0 * decel * dist:
            return self._fail(t + abs(sd) / decel, stuck_kind, j + 1, state,
                              f"slides {sd * sd / (2 * decel):.4g} m and stops on {where}")
        tau = dist / abs(sd) if decel == 0.0 else (
            (abs(sd) - math.sqrt(sd * sd - 2.0 * decel * dist)) / decel)
        kind = "tip" if self.mu > 0.0 else "slid_off"
        return self._fail(t + tau, kind, j + 1, state,
                          f"slides to the end of {where} and goes over its edge")

    def _handover(self, t, k, theta, omega, s, sd, j, palm=None):
        """The object on palm k meets palm j's top: record, release palm k, land on palm j
        (at rest, or swinging at palm = (angle, speed along t))."""
        before = self._on_palm(k, theta, omega, s, sd)
        rec = self._stage(k)
        vx, vy = before["vx"], before["vy"]
        if rec is not None:
            rec.update(handover_time=t, handover_speed=math.hypot(vx, vy), handover_angle=theta,
                       handover_vx=vx, handover_vy=vy, release_speed=self.ls[k] * omega)
        self._release(k, t, theta, self.ls[k] * omega)
        theta_j, w_j = (self.rest_angle[j], 0.0) if palm is None else palm
        return self._impact(t, j, theta_j, w_j, before["x"], before["y"], vx, vy,
                            log_as="handover", stage=k + 1, before=before,
                            at_rest=palm is None)

    def _stop_with_object(self, t, k, omega, s, sd):
        """Palm k reaches its front stop carrying the object: the palm stops (plastic); the
        object, moving down along t(front_stop), then meets the stopped palm."""
        st = self._on_palm(k, self.fs, omega, s, sd)
        self.rest_angle[k], self.rest_since[k] = self.fs, t
        return self._impact(t, k, self.fs, 0.0, st["x"], st["y"], st["vx"], st["vy"],
                            log_as="stop", stage=k + 1, before=st, at_rest=True)

    def _complete(self, t, k, theta, omega, s, sd=0.0):
        state = self._on_palm(k, theta, omega, s, sd)
        rec = self._stage(k)
        if rec is not None:
            rec.update(handover_angle=theta)
        self.passed, self.completed = self.n, True
        self._log(t, "complete", k + 1, state, state,
                  f"the last manipulator ({k + 1}) carried the object to beta")
        return None

    # ------------------------------------------------------------ stuck carry (closed form)
    def _stuck(self, t0, k, theta0, v0, s):
        """Object stuck on palm k from (theta0, speed v0): every guard is a function of theta
        whose crossing is closed form (phases.stuck_crossings), contacts are closed-form
        roots of the arc (geometry), and the time of an angle is the closed-form
        integral of l dth / v(th) (phases.swing_time)."""
        g, l, tol = self.g, self.ls[k], self.acc.event_tol
        if v0 <= 0.0:
            return self._fail(t0, "stall", k + 1, self._on_palm(k, theta0, v0 / l, s),
                              "the palm is not moving forward")
        if not self.plain or self._tracked(t0, k):  # links and pivots, or palms swinging from
            return self._stuck_integrated(t0, k, theta0, v0 / l, s)  # rest: integrated (ode.py)
        turn = ph.turning_angle(theta0, v0, gravity=g, link_length=l)
        ends = [(self.fs, "stranded")]
        if turn is not None:
            ends.append((turn, "stall"))
        if k == self.n - 1 and theta0 < self.beta:
            ends.append((self.beta, "complete"))
        theta_end, end_kind = min(ends)
        px, py = self.row.pivots[k]
        arc = Arc(px + s, py, l)
        entry = first_contact(arc, self._obstacles(t0, k, near=px), theta0, theta_end)
        candidates = [(theta_end, 5, end_kind)]
        if entry is not None:
            candidates.append((entry.tau, 4, "handover" if entry.kind == "top" else "blocked"))
        # slip and lift-off always come before pi/2; a guard crossing after the handover or the
        # end cannot end the carry (ties go to the guard: it has the lower priority number)
        cap = min(theta_end, 0.5 * math.pi - 1e-9, entry.tau if entry is not None else math.inf)
        lo, hi = self.row.support(s)
        candidates += ph.stuck_crossings(theta0, v0, cap, gravity=g, link_length=l,
                                         height=self.h, support=(lo, hi), mu=self.mu)
        theta_e, _, kind = min(candidates)
        turn = turn if kind == "stall" else None
        te = t0 + ph.swing_time(theta0, theta_e, theta0, v0, gravity=g, link_length=l, turn=turn)
        # A palm released earlier (palm k-1, say) may reach its stop during this carry, where
        # the arc meets it: the carry is split at its arrival and goes on with it as an obstacle.
        t1 = math.inf  # (a loop, not _arrivals: this runs at every carry)
        for j in self.swinging:
            if t0 < self.rest_since[j] < min(te, t1) and j != k:
                box = self._rest_box(j)
                lowest = py + l * min(math.cos(theta0), math.cos(theta_e))  # |th| < pi/2
                if box.y_high > lowest and first_contact(arc, [box], theta0, theta_e):
                    t1 = self.rest_since[j]
        if t1 < te:
            theta1 = brentq(lambda th: ph.swing_time(theta0, th, theta0, v0, gravity=g,
                                                     link_length=l, turn=turn) - (t1 - t0),
                            theta0, theta_e, xtol=tol)
            v1 = math.sqrt(max(ph.speed_squared(theta1, theta0, v0, gravity=g, link_length=l),
                               0.0))
            self._rec_stuck(t0, k, theta0, v0, s, theta1, None)
            return lambda: self._stuck(t1, k, theta1, v1, s)
        omega_e = math.sqrt(max(ph.speed_squared(theta_e, theta0, v0, gravity=g,
                                                 link_length=l), 0.0)) / l
        self._rec_stuck(t0, k, theta0, v0, s, theta_e, turn)
        state = self._on_palm(k, theta_e, omega_e, s)
        if kind == "handover":
            return self._handover(te, k, theta_e, omega_e, s, 0.0, entry.palm)
        if kind == "complete":
            return self._complete(te, k, theta_e, omega_e, s)
        if kind == "stranded":
            return self._stop_with_object(te, k, omega_e, s, 0.0)
        if kind == "blocked":  # the next palm's rear end, on its back stop: pushed (pushing.py)
            hc = self._push_contact(te, k, theta_e, s, entry.palm)
            if hc is not None:
                return self._push(te, k, theta_e, omega_e, s, entry.palm, hc)
            stepped = self._stepped_carry(te, k, (theta_e, omega_e, s, 0.0), (), 0, [], state,
                                          f"the carried object hits the side of palm "
                                          f"{entry.palm + 1}")
            if stepped is not None:
                return stepped
        if kind == "slip":
            self._log(te, "slip", k + 1, state, state,
                      f"|tan th| = {abs(math.tan(theta_e)):.6g} reaches mu = {self.mu:g}")
            return lambda: self._sliding(te, k, theta_e, omega_e, s, 0.0)
        if kind == "lift_off":  # the object flies on (liftoff.py)
            return self._lift_off(te, k, theta_e, omega_e, s, 0.0,
                                  f"v^2 = g l cos th at th = {theta_e:.6g} rad")
        if kind == "tip" and self.eps == 0.0:  # the object turns about its edge (rocking.py)
            return self._rock_onset(te, k, theta_e, omega_e, s,
                                    ph.stuck_force_point(theta_e, self.h), (lo, hi), state)
        details = {
            "tip": f"the contact force "
                   f"{support_words(ph.stuck_force_point(theta_e, self.h), (lo, hi))}, "
                   f"th = {theta_e:.6g} rad",
            "stall": f"the palm stops at th = {theta_e:.6g} rad before the top and swings back",
            "blocked": f"the carried object hits the side of palm "
                       f"{entry.palm + 1 if entry else '?'}",
        }
        return self._fail(te, kind, k + 1, state, details[kind])

    def _rec_stuck(self, t0, k, theta0, v0, s, theta_e, turn):
        if not self.record or theta_e <= theta0:
            return
        g, l = self.g, self.ls[k]
        ths = np.linspace(theta0, theta_e, 40)
        t = t0
        for i, th in enumerate(ths):
            if i:
                t += ph.swing_time(ths[i - 1], th, theta0, v0, gravity=g, link_length=l,
                                   turn=turn if i == len(ths) - 1 else None)
            v = math.sqrt(max(ph.speed_squared(th, theta0, v0, gravity=g, link_length=l), 0.0))
            st = self._on_palm(k, th, v / l, s)
            self._rec(t, st["x"], st["y"], st["vx"], st["vy"], th, k + 1)


_PLAIN = frozenset({bool, int, str, float, type(None)})


def _plain(value):
    """Stage-record values as plain Python values (JSON-ready)."""
    return value if type(value) in _PLAIN else float(value)


def _floats(state: dict) -> dict:
    return {k: v if type(v) is float else float(v) for k, v in state.items() if v is not None}
