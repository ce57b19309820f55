"""Event simulator of the rimless wheel, and its vectorised step map for long runs.

The logged run (`simulate_rimless_wheel`) integrates each stance's equation of motion phi'' =
(rate / 2) sin phi numerically (the Dormand-Prince 5(4) pair of stance_rk.py, in the time unit
sqrt(2 / rate)), with events located by the integrator: the next spoke's tip reaching the next
foothold (impact), the wheel stopping (stalled: it rolls back), the normal force reaching zero
(flight) and friction reaching its limit (slip); the contact force is Newton's on the centre of
mass. Each impact is solved as a general rigid-body impact (a linear system for the impulse and
the velocities after it, the new tip stopped), not by the closed form eta; its impulse must
push (else flight) inside the friction cone (else slip), and the wheel must go on forward (else
stalled). On stairs the landing spoke's swing is checked against the nose it passes (nose_hit)
and the tread it lands on (missed_tread). So the closed forms of `physics` are checked against
it (tests).

Frame: x downhill, y up; foothold 0 at the origin. Step k (k >= 1) is the chord from foothold
k - 1 to foothold k: on a ramp its slope is the design's plus the step's slope error; on stairs
tread k lies rise + rise_error_k below tread k - 1 and is tread + tread_error_k long (tread 0,
where the wheel starts, as designed). The wheel starts just after an impact on the ground as
designed (the stance spoke at beta - alpha) at the scene's start speed.

Failure kinds: stalled, flight, slip, nose_hit, missed_tread (also: the next spoke reaching the
ground before the stance spoke leaves it, a slope change of more than 2 alpha between steps).
A failure in stance k has stage k (k - 1 steps passed), as on the other scenes.

`step_map` runs many wheels for many steps at once on the closed forms (the stance energy's
affine map by a linear filter), checking each stance at its start, its top and its end, and
each impact: 10^6 steps take a fraction of a second.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...accuracy import Accuracy
from ...accuracy import accuracy as accuracy_preset
from ...sim.core import Event, Outcome, SimulationRefused, SimulationResult, check_scales
from . import physics as phys
from .analysis import resolve
from .model import RimlessWheelDesign, RimlessWheelScene, check_ground

FAILURE_KINDS = ("stalled", "flight", "slip", "nose_hit", "missed_tread")
DEFAULT_RECORD_LIMIT = 10_000
SWING_SAMPLES = 128  # angles of a swing at which the landing spoke is checked against a nose


@dataclass(frozen=True)
class RimlessWheelSimulationResult(SimulationResult):
    """A rimless wheel run; summary: counts and extremes over every step."""

    summary: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        out = super().to_json()
        out["summary"] = self.summary
        return out


def _errors(step_errors, stages, stairs=None):
    """Per-step (slope, rise, tread) errors, arrays indexed by step 1..stages (index 0 unused).
    stairs: the ground (True, False), whose errors alone are taken (the other ground's refused);
    None takes any."""
    out = {name: np.zeros(stages + 2) for name in ("slope", "rise", "tread")}
    _refuse_other_ground(step_errors, stairs)
    for err in step_errors:
        get = err.get if isinstance(err, dict) else (lambda k, d=0.0, e=err: getattr(e, k, d))
        step = int(get("step"))
        if step < 1:
            raise SimulationRefused(f"step_errors: step must be >= 1, not {step}")
        if step <= stages + 1:
            for name in out:
                out[name][step] += float(get(name, 0.0) or 0.0)
    return out


def _refuse_other_ground(step_errors, stairs) -> None:
    """SimulationRefused for a step error of the other ground (a slope error on stairs, a rise
    or tread error on a ramp), which the run would otherwise leave out unsaid."""
    if stairs is None:
        return
    other = ("slope",) if stairs else ("rise", "tread")
    for err in step_errors:
        get = err.get if isinstance(err, dict) else (lambda k, d=0.0, e=err: getattr(e, k, d))
        found = [name for name in other if get(name, 0.0)]
        if found:
            ground, takes = ("stairs", "rise and tread") if stairs else ("a ramp", "slope")
            raise SimulationRefused(
                f"step_errors: step {get('step')} gives a {' and '.join(found)} error, but the "
                f"wheel rolls on {ground}, whose steps take {takes} errors only")


def check_wheel_scales(scene: RimlessWheelScene, design: RimlessWheelDesign) -> None:
    """Refuse (SimulationRefused) a wheel whose numbers double precision cannot follow."""
    leg = design.leg_length
    check_scales(("the gravity", scene.gravity), {})
    check_scales(("the hub's mass", scene.wheel.mass), {"spoke_mass": scene.wheel.spoke_mass})
    lengths = {"gyration": scene.wheel.gyration}
    for name in ("rise", "tread", "landing_offset"):
        if getattr(design, name) is not None:
            lengths[name] = getattr(design, name)
    check_scales(("the leg length", leg), lengths)
    check_scales(("sqrt(g / leg_length)", math.sqrt(scene.gravity / leg)),
                 {"speed": scene.initial.speed})


class _Ground:
    """Footholds and chords of the ground as built."""

    def __init__(self, scene, design, wh, geo, errors):
        self.stairs = scene.ground == "stairs"
        self.wh, self.errors = wh, errors
        if self.stairs:
            self.rise, self.tread = geo["rise"], geo["tread"]
            self.s0 = geo["landing_offset"]
        else:
            self.slope = design.slope

    def chord_angle(self, k, chord=None):
        """beta_k of step k (0: the ground as designed, where the wheel starts); chord: the
        distance between the step's two tips (the design's when left out)."""
        chord = self.wh.chord if chord is None else chord
        if not self.stairs:
            return self.slope + (self.errors["slope"][k] if k else 0.0)
        rise = self.rise + (self.errors["rise"][k] if k else 0.0)
        if not 0.0 <= rise < chord:
            return None
        return math.asin(rise / chord)

    def tread_length(self, k):
        return self.tread + (self.errors["tread"][k] if k else 0.0)

    def normal_angle(self):
        return 0.0 if self.stairs else self.slope


def simulate_rimless_wheel(scene: RimlessWheelScene, design: RimlessWheelDesign, *, stages: int,
                           accuracy: str | Accuracy = "default", step_errors=(),
                           record_trajectory: bool = False,
                           record_limit: int = DEFAULT_RECORD_LIMIT,
                           trajectory_samples: int = 48, trajectory_limit: int = 1000,
                           spoke_lengths=None) -> RimlessWheelSimulationResult:
    """Roll the wheel from its start for `stages` steps (impacts). step_errors: objects or dicts
    with step (from 1) and slope (rad; a ramp) or rise and tread (m; stairs). spoke_lengths:
    each spoke's own length (n of them, m; step k stands on spoke (k - 1) mod n and lands
    spoke k mod n; the mass distribution as designed), the design's leg length when left
    out."""
    acc = accuracy_preset(accuracy)
    stages = int(stages)
    if stages < 0:
        raise SimulationRefused(f"stages must be >= 0, not {stages}")
    check_wheel_scales(scene, design)
    missing = check_ground(scene, design)
    if missing:
        raise SimulationRefused("; ".join(missing))
    wh, geo, _ = resolve(scene, design)
    ground = _Ground(scene, design, wh, geo, _errors(step_errors, stages, scene.ground == "stairs"))
    run = _Run(scene, wh, ground, acc, record_trajectory, trajectory_samples, trajectory_limit)
    if spoke_lengths is not None:
        run.lengths = [float(v) for v in spoke_lengths]
        if len(run.lengths) != wh.n or min(run.lengths) <= 0.0:
            raise SimulationRefused(f"spoke_lengths: {wh.n} lengths > 0 (one a spoke)")
    failure = None
    beta_prev = ground.chord_angle(0)
    if beta_prev is None:
        raise SimulationRefused("the rise is not below the distance between two spoke tips")
    omega = scene.initial.speed
    s_prev = ground.s0 if ground.stairs else 0.0
    for k in range(1, stages + 1):
        failure, omega, beta_prev, s_prev = run.step(k, omega, beta_prev, s_prev,
                                                     keep=k <= record_limit or k == stages)
        if failure is not None:
            break
    if failure is not None:
        run.events.append(failure)
    passed = run.passed
    outcome = Outcome(completed=failure is None and passed == stages, stages_passed=passed,
                      failure=failure)
    return RimlessWheelSimulationResult(
        scene="rimless_wheel", outcome=outcome, stages=run.records, events=run.events,
        accuracy=acc, trajectory=run.trajectory, summary=run.summary(record_limit))


class _Run:
    """The state of one logged run: the foothold, the time, the records and the events."""

    def __init__(self, scene, wh, ground, acc, record_trajectory, samples, limit):
        self.scene, self.wh, self.ground, self.acc = scene, wh, ground, acc
        self.mass = phys.total_mass(scene.wheel.mass, scene.wheel.spoke_mass, wh.n)
        self.foot = np.zeros(2)
        self.time, self.passed = 0.0, 0
        self.records: list[dict] = []
        self.events: list[Event] = []
        self.trajectory = ({n: [] for n in ("time", "x", "y", "phi", "omega")}
                           if record_trajectory else {})
        self.samples, self.limit = samples, limit
        self.speeds = [math.inf, -math.inf]
        th = ground.normal_angle()
        self.normal_dir = (math.sin(th), math.cos(th))
        self.stances: dict[tuple, tuple] = {}  # stance outcomes by their exact inputs
        self.base, self.lengths, self.phi_start = wh, None, None

    # --- the stance -------------------------------------------------------------------
    def forces(self, phi, omega):
        """(normal, tangential) ground reaction on the stance tip, per unit mass, from Newton:
        R = a_G - g with a_G = l phi'' e_t - l omega^2 e_r (e_r = (sin phi, cos phi) tip to
        hub, e_t = (cos phi, -sin phi) the hub's direction of motion), on the ground's normal
        (sin th, cos th) and tangent (cos th, -sin th)."""
        wh = self.wh
        s, c = math.sin(phi), math.cos(phi)
        along, radial = wh.leg * 0.5 * wh.rate * s, wh.leg * omega * omega
        rx = along * c - radial * s
        ry = -along * s - radial * c + wh.gravity
        sn, cn = self.normal_dir
        return rx * sn + ry * cn, rx * cn - ry * sn

    def stance(self, phi0, phi1, omega0):
        """Integrate from phi0 at omega0 to the first event: (kind, t, phi, omega, solution).
        A stance whose inputs are bit for bit those of one integrated before has its outcome:
        the integration is deterministic (a run on even ground settles on its orbit to the last
        bit after some tens of steps, and repeats it)."""
        key = (phi0, phi1, omega0, self.wh.leg)
        if key not in self.stances:
            if len(self.stances) > 4096:
                self.stances.clear()
            self.stances[key] = self.integrate(phi0, phi1, omega0)
        return self.stances[key]

    def integrate(self, phi0, phi1, omega0):
        """The stance from phi0 at omega0, integrated to its first event (stance_rk: the
        Dormand-Prince pair, events located to rounding)."""
        from .stance_rk import integrate

        wh, mu = self.wh, self.scene.friction
        unit = math.sqrt(2.0 / wh.rate)  # time unit: phi'' = sin phi in it

        def flight(y):
            return self.forces(y[0], y[1] / unit)[0]

        def slip(y):
            normal, tangential = self.forces(y[0], y[1] / unit)
            return mu * normal - abs(tangential)

        events = [(lambda y: y[0] - phi1, 1), (lambda y: y[1], -1), (flight, -1), (slip, -1)]
        normal, tangential = self.forces(phi0, omega0)
        if normal <= 0.0:
            return "flight", 0.0, phi0, omega0, None
        if abs(tangential) > mu * normal:
            return "slip", 0.0, phi0, omega0, None
        span = 50.0 + 10.0 * (phi1 - phi0) / max(omega0 * unit, 1e-3)
        t, y, index, dense = integrate((phi0, omega0 * unit), span, events, self.acc.rtol,
                                       self.acc.atol, dense=bool(self.trajectory))
        names = ("impact", "stalled", "flight", "slip")
        kind = "stalled" if index is None else names[index]
        return kind, t * unit, float(y[0]), float(y[1] / unit), dense

    # --- the impact ---------------------------------------------------------------------
    def impact(self, phi, omega, landing=None):
        """The rigid-body impact at the new foothold: (omega+, normal impulse, tangential
        impulse) per unit mass. Unknowns v+ (2), Omega+ (counter-clockwise), P (2):
        v+ - v- = P, k^2 (Omega+ - Omega-) = r x P, v+ + Omega+ x r = 0 (r: hub to new tip)."""
        wh = self.wh
        b = wh.leg if landing is None else landing  # the landing spoke's length
        hub = wh.leg * np.array([math.sin(phi), math.cos(phi)])
        tip = hub - b * np.array([math.sin(phi - 2 * wh.alpha), math.cos(phi - 2 * wh.alpha)])
        r = tip - hub
        spin = -omega  # counter-clockwise
        v = spin * np.array([-hub[1], hub[0]])  # Omega x (hub - old tip)
        a = np.zeros((5, 5))
        b = np.zeros(5)
        a[0, 0] = a[1, 1] = 1.0
        a[0, 3] = a[1, 4] = -1.0
        b[0:2] = v
        a[2, 2] = wh.k2
        a[2, 3], a[2, 4] = r[1], -r[0]  # - (r x P) = -(r_x P_y - r_y P_x)
        b[2] = wh.k2 * spin
        a[3, 0], a[3, 2] = 1.0, -r[1]  # v+ + Omega+ (-r_y, r_x) = 0
        a[4, 1], a[4, 2] = 1.0, r[0]
        x = np.linalg.solve(a, b)
        th = self.ground.normal_angle()
        impulse = x[3:5]
        return (-float(x[2]), float(impulse @ [math.sin(th), math.cos(th)]),
                float(impulse @ [math.cos(th), -math.sin(th)]), tip)

    # --- one step -----------------------------------------------------------------------
    def spokes(self, k):
        """(stance spoke's length, landing spoke's length, chord between their tips) of step k;
        the run's wheel set to the stance spoke (its length and stance rate)."""
        import dataclasses

        if self.lengths is None:
            return None, None, None
        n = len(self.lengths)
        a, b = self.lengths[(k - 1) % n], self.lengths[k % n]
        base = self.base
        self.wh = dataclasses.replace(base, leg=a, rate=float(
            phys.stance_rate(base.gravity, base.k2, a)))
        return a, b, float(phys.chord_between(a, b, base.alpha))

    def step(self, k, omega, beta_prev, s_prev, keep):
        a, b, chord = self.spokes(k)
        wh, ground = self.wh, self.ground
        beta = ground.chord_angle(k, chord)
        phi0 = beta_prev - wh.alpha if self.phi_start is None else self.phi_start
        if beta is None:
            return self.fail(k, "missed_tread", phi0, omega,
                             f"step {k}'s rise is not below the spokes' chord: no spoke reaches "
                             "its tread"), omega, beta_prev, s_prev
        phi1 = (beta + wh.alpha if b is None
                else float(phys.chord_offset(a, b, wh.alpha)) + beta)
        if b is not None:
            self.phi_start = phi1 - 2 * wh.alpha
        if phi1 <= phi0:
            return self.fail(k, "missed_tread", phi0, omega,
                             f"the ground of step {k} rises into the next spoke: it meets the "
                             "ground before the stance spoke leaves it"), omega, beta, s_prev
        kind, dt, phi, w, sol = self.stance(phi0, phi1, omega)
        self.sample(sol, dt, phi0, phi1, k)
        self.time += float(dt)
        if kind != "impact":
            return self.fail(k, kind, phi, w, _stance_detail(kind, k, phi)), w, beta, s_prev
        if ground.stairs:
            miss = self.stairs_check(k, phi0, phi1, s_prev, b)
            if miss is not None:
                return self.fail(k, miss[0], phi, w, miss[1]), w, beta, s_prev
        w_after, p_n, p_t, tip = self.impact(phi, w, b)
        mu = self.scene.friction
        if p_n <= 0.0:
            return self.fail(k, "flight", phi, w, f"impact {k}'s impulse would pull the new "
                             "spoke into the ground"), w, beta, s_prev
        if abs(p_t) > mu * p_n:
            return self.fail(k, "slip", phi, w, f"impact {k} needs friction {abs(p_t) / p_n:.4g}"
                             f", the ground has {mu:g}: the new spoke slides"), w, beta, s_prev
        if w_after <= 0.0:
            detail = (f"impact {k} stops the wheel (speed after it {w_after:.4g} rad/s): it "
                      "rolls back")
            return self.fail(k, "stalled", phi, w, detail), w, beta, s_prev
        s_new = tip[0] - (ground.tread_length(k - 1) - s_prev) if ground.stairs else 0.0
        self.passed = k
        self.record(k, phi, w, w_after, beta, tip, s_new, keep, p_t / p_n)
        self.foot = self.foot + tip
        return None, w_after, beta, s_new

    def stairs_check(self, k, phi0, phi1, s_prev, landing=None):
        """The landing spoke's swing against the nose of tread k - 1 (sampled) and its landing
        on tread k: (kind, detail) of a failure, or None. landing: that spoke's length (the
        stance spoke's when left out)."""
        wh, ground = self.wh, self.ground
        b = wh.leg if landing is None else landing
        nose = ground.tread_length(k - 1) - s_prev  # ahead of the foothold, at its level
        phi = np.linspace(phi0, phi1, SWING_SAMPLES + 1)
        hub_x, hub_y = wh.leg * np.sin(phi), wh.leg * np.cos(phi)
        tip_x = hub_x - b * np.sin(phi - 2 * wh.alpha)
        tip_y = hub_y - b * np.cos(phi - 2 * wh.alpha)
        down = (tip_y <= 0.0) & (tip_x < nose)  # the tip on tread k - 1, before its nose
        low, high = np.minimum(hub_x, tip_x), np.maximum(hub_x, tip_x)
        across = (low <= nose) & (nose <= high) & (tip_x != hub_x)
        with np.errstate(divide="ignore", invalid="ignore"):
            height = hub_y + (tip_y - hub_y) * (nose - hub_x) / (tip_x - hub_x)
        struck = across & (height < 0.0)
        first = np.flatnonzero(down | struck)  # the first sampled angle that fails
        if first.size:
            i = first[0]
            if down[i]:
                return "missed_tread", (f"step {k}: the spoke comes down on tread {k - 1}, "
                                        f"{nose - tip_x[i]:.4g} m before its nose")
            return "nose_hit", f"step {k}: the landing spoke strikes the nose of tread {k - 1}"
        tip_x = (2 * wh.leg * math.sin(wh.alpha) * math.cos(phi1 - wh.alpha) if landing is None
                 else wh.leg * math.sin(phi1) - b * math.sin(phi1 - 2 * wh.alpha))
        landing = tip_x - nose
        if landing >= ground.tread_length(k):
            return "missed_tread", (f"step {k}: the spoke lands {landing:.4g} m from the back "
                                    f"of tread {k}, beyond its nose (tread "
                                    f"{ground.tread_length(k):.4g} m)")
        if landing <= 0.0:
            return "nose_hit", f"step {k}: the spoke meets the riser of tread {k}"
        return None

    # --- the log ------------------------------------------------------------------------
    def state(self, phi, omega):
        hub = self.foot + self.wh.leg * np.array([math.sin(phi), math.cos(phi)])
        return {"x": float(hub[0]), "y": float(hub[1]), "phi": float(phi), "omega": float(omega),
                "foot_x": float(self.foot[0]), "foot_y": float(self.foot[1])}

    def record(self, k, phi, w_before, w_after, beta, tip, s_new, keep, ratio):
        self.speeds = [min(self.speeds[0], w_after), max(self.speeds[1], w_after)]
        if not keep:
            return
        before = self.state(phi, w_before)
        start, rate = beta - self.wh.alpha, self.wh.rate
        if self.lengths is not None:  # the next stance: on the landing spoke, from phi1 - 2 alpha
            landing = self.lengths[k % len(self.lengths)]
            start = self.phi_start
            rate = float(phys.stance_rate(self.base.gravity, self.base.k2, landing))
        rec = {"step": k, "impact_time": self.time, "speed_before": w_before,
               "speed_after": w_after, "friction_demand": abs(ratio),
               "energy_after": float(phys.stance_energy(w_after, start, rate)),
               "chord_angle": float(beta), "foot_x": float(self.foot[0] + tip[0]),
               "foot_y": float(self.foot[1] + tip[1])}
        if self.ground.stairs:
            rec["landing_x"] = float(s_new)
        self.records.append(rec)
        foot = self.foot + tip
        after = {"x": before["x"], "y": before["y"], "phi": float(phi - 2 * self.wh.alpha),
                 "omega": float(w_after), "foot_x": float(foot[0]), "foot_y": float(foot[1])}
        self.events.append(Event(self.time, "impact", k, before, after,
                                 f"spoke {k} lands; speed {w_before:.6g} -> {w_after:.6g} rad/s"))

    def fail(self, k, kind, phi, omega, detail):
        state = self.state(phi, omega)
        return Event(self.time, kind, k, state, dict(state), detail, failure=True)

    def sample(self, sol, dt, phi0, phi1, k):
        if not self.trajectory or sol is None or k > self.limit:
            return
        unit = math.sqrt(2.0 / self.wh.rate)
        for t in np.linspace(0.0, dt / unit, self.samples + 1):
            phi, w = sol.sol(t)
            st = self.state(phi, w / unit)
            self.trajectory["time"].append(self.time + t * unit)
            for name in ("x", "y", "phi", "omega"):
                self.trajectory[name].append(st[name])

    def summary(self, record_limit):
        out = {"steps": self.passed, "record_limit": record_limit,
               "records_kept": len(self.records)}
        if self.passed:
            out.update(speed_after_min=self.speeds[0], speed_after_max=self.speeds[1])
        return out


def _stance_detail(kind, k, phi):
    return {
        "stalled": f"stance {k}: the wheel stops at {phi:.4g} rad before vaulting its spoke and "
                   "rolls back",
        "flight": f"stance {k}: the ground's normal force reaches 0 at {phi:.4g} rad: the wheel "
                  "leaves the ground",
        "slip": f"stance {k}: the stance tip slides at {phi:.4g} rad (friction at its limit)",
    }[kind]
