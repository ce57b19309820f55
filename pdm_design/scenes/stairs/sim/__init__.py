"""Event simulator of a ball bouncing down stairs (paper sections 3.1-3.2).

Frame and conventions (as in ``pdm_design.scenes.stairs.physics``): x downhill, y up, spin omega
counter-clockwise positive (rolling in +x has vx = -r omega). The state logged in events is
x = the ball's centre (= its lowest point) along the stairs, y = the height of its lowest point,
vx, vy, omega. The ball is a circle of radius r (r = 0 is a point).

The staircase (built from the design, see `stairs_geometry`):
    * step k (k >= 1) has a tread of length ``tread + tread_error_k`` and a riser of height
      ``rise + rise_error_k`` at the back of its tread (the vertical face from the nose of step
      k-1 down to tread k). Every step is built on the one before, so a step's error shifts all
      later steps; the launcher fixes step 0.
    * step 0 is the top landing, one nominal rise above (nominal) tread 1, running back without
      end; its nose is the top of riser 1. The launch behaves like the apex of a bounce on it.
    * as built, each tread may have its own restitution and friction against the ball, and the
      launcher its own speed and place (`build_variation`, module `materials`); the staircase
      is still laid out from the design.
    * the stairs are placed so that, as designed (no errors), the ball's first landing is
      ``landing_offset`` from the back of tread 1. The ball is launched horizontally at x = 0
      with its lowest point drop_height above nominal tread 1.

Every flight is ballistic and solved in closed form; no ODE integrator is involved. Contacts:
    * a tread (the ball's lowest point reaches the tread's level while over it): the descending
      root of a quadratic, taken in the form without cancellation;
    * a nose corner: circle against point, a quartic in t, solved by the companion matrix and
      polished by Newton's method to the accuracy's event_tol; the first entering root counts;
    * a riser face (only reachable when moving backwards): linear in t.
Each flight is computed in a frame attached to the nose of the step it leaves, so positions
stay O(tread) however far down the stairs the ball is (10^6 bounces lose no digits to x ~ 10^6).
Time is summed with Kahan compensation.

Event kinds:
    impact          the ball lands on the next step (stage = that step); reset by the impact map
    slip            not a failure: an impact that ends with the contact point still sliding
                    (friction too small to reach rolling); logged right after its impact
A failure's stage is the bounce that fails (stages passed + 1, as on the manipulators: the
ball left step k = stages passed for step k + 1); its state's "step" and its detail name the
step where it happens.
    nose_hit        failure: the ball touches a step's nose corner
    riser_hit       failure: the ball touches a riser face
    skipped_step    failure: the ball lands on a step beyond the next one
    double_landing  failure: the ball lands again on the step it left (for the launch, on the
                    top landing, step 0)
    bounced_back    failure: the ball flies back up and lands on an earlier step
    no_rebound      failure: the ball leaves a tread with no vertical speed (restitution 0); it
                    would roll or slide along the tread, which the model does not cover
The staircase is built as far as the requested bounces need: the ball never runs off its end.

Long runs: full stage records and events are kept for the first ``record_limit`` bounces
(default 10 000) plus the last one; `StairsSimulationResult.summary` carries running statistics
over every bounce (extremes of landing position, speeds, spin, apex; counts), so a 10^6-bounce
run needs memory for record_limit records only. Trajectories (``record_trajectory=True``) are
sampled by the closed form, ``trajectory_samples`` points per flight, for the first
``trajectory_limit`` flights.

Vectorised closed forms for many samples at once: `impact_map` (one impact) and
`bounce_sequence` (many samples, many bounces on a uniform staircase, with failure detection).

Modules: this one holds the event-located run; `stairs_geometry` the staircase as built,
`flight` the closed-form next contact of a flight, `maps` the impact maps and the
vectorised bounces, `materials` each step's restitution and friction and the launch as built.
Their public names are importable from here. (Many builds at once, each with its own steps:
`pdm_design.scenes.stairs.tolerances`.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ....accuracy import Accuracy
from ....accuracy import accuracy as accuracy_preset
from ....sim.core import Event, Outcome, SimulationRefused, SimulationResult, check_scales
from ..model import StairsDesign, StairsScene
from .flight import Contact, next_contact, step_under
from .geometry import StairsGeometry, stairs_geometry
from .maps import (
    BOUNCE_FAILURES,
    BounceSequence,
    Impact,
    bounce_sequence,
    corner_hits,
    impact_map,
    impact_once,
)
from .materials import BuildVariation, build_variation

__all__ = [
    "BOUNCE_FAILURES", "DEFAULT_RECORD_LIMIT", "FAILURE_KINDS", "BounceSequence", "BuildVariation",
    "Impact", "StairsGeometry", "StairsSimulationResult", "bounce_sequence", "build_variation",
    "corner_hits", "impact_map", "impact_once", "simulate_stairs", "stairs_geometry",
]

FAILURE_KINDS = ("nose_hit", "riser_hit", "skipped_step", "double_landing", "bounced_back",
                 "no_rebound")
DEFAULT_RECORD_LIMIT = 10_000


@dataclass(frozen=True)
class StairsSimulationResult(SimulationResult):
    """A stairs run. summary: statistics over every bounce (also those beyond record_limit);
    staircase: the steps reached, as dicts (step, back, nose, level; global frame)."""

    summary: dict = field(default_factory=dict)
    staircase: list[dict] = field(default_factory=list)

    def to_json(self) -> dict:
        out = super().to_json()
        out["summary"] = self.summary
        return out


class _Summary:
    """Running extremes and counts over every bounce."""

    KEYS = ("landing_x", "impact_speed", "vx", "spin_after", "apex_height")

    def __init__(self):
        self.count = 0
        self.slips = 0
        self.lo = {k: math.inf for k in self.KEYS}
        self.hi = {k: -math.inf for k in self.KEYS}

    def add(self, values):
        self.count += 1
        lo, hi = self.lo, self.hi
        for key, v in zip(self.KEYS, values):
            if v < lo[key]:
                lo[key] = v
            if v > hi[key]:
                hi[key] = v

    def to_dict(self, record_limit, last):
        out = {"bounces": self.count, "slipping_impacts": self.slips,
               # the first record_limit bounces' records, and the last bounce's
               "records_kept": min(self.count, record_limit + 1), "record_limit": record_limit}
        if self.count:
            for key in self.KEYS:
                out[f"{key}_min"] = self.lo[key]
                out[f"{key}_max"] = self.hi[key]
            out["last"] = last
        return out


def simulate_stairs(scene: StairsScene, design: StairsDesign, *, stages: int,
                    accuracy: str | Accuracy = "default", step_errors=(),
                    variation: BuildVariation | None = None, record_trajectory: bool = False,
                    record_limit: int = DEFAULT_RECORD_LIMIT,
                    trajectory_samples: int = 48, trajectory_limit: int = 1000,
                    ) -> StairsSimulationResult:
    """Simulate the ball from its launch for `stages` bounces (impacts on successive steps).

    step_errors: objects (or dicts) with step (from 1), rise and tread: metres added to that
    step's rise and tread. variation (`build_variation`): each step's restitution and friction
    and the launch as built, where they differ from the design's and the scene's (the staircase
    is built from the design). The run stops at the first failure event. See the module
    docstring for the staircase, the event kinds and the memory policy of long runs.
    """
    acc = accuracy_preset(accuracy)
    stages = int(stages)
    if stages < 0:
        raise SimulationRefused(f"stages must be >= 0, not {stages}")
    check_stairs_scales(scene, design)
    geo = stairs_geometry(scene, design, step_errors)
    check_stairs_scales(scene, design, geo)
    g, eps, mu = scene.gravity, design.restitution, scene.friction
    r, m, inertia = scene.ball.radius, scene.ball.mass, scene.ball.inertia
    tol = acc.event_tol
    built = variation or BuildVariation()

    # launch, in the frame of step 0's nose (x_back_1, level of step 0)
    k = 0
    x0, y0 = built.launch_x - geo.x_back_1, geo.launch_height - geo.level(0)
    _check_start(geo, x0, y0, r)
    v0 = design.launch_speed if built.launch_speed is None else built.launch_speed
    vx, vy, omega = v0, 0.0, scene.initial.spin
    t_sum, t_comp = 0.0, 0.0

    stage_records: list[dict] = []
    events: list[Event] = []
    traj: dict[str, list[float]] = ({n: [] for n in ("time", "x", "y", "vx", "vy", "omega")}
                                    if record_trajectory else {})
    summary = _Summary()
    passed = 0
    failure: Event | None = None
    last_record: dict | None = None
    raw = None
    while passed < stages:
        if vy <= 0.0 and y0 <= geo.relative(k, step_under(geo, k, x0))[2]:
            failure = _failure(geo, k, t_sum, x0, y0, vx, vy, omega, "no_rebound", passed + 1,
                               f"the ball is on tread {k} with no vertical speed: it would "
                               "roll or slide along it (outside the model)", k)
            break
        c = next_contact(geo, k, x0, y0, vx, vy, r, g, tol)
        if record_trajectory and passed < trajectory_limit:
            _sample_flight(traj, geo, k, t_sum, x0, y0, vx, vy, omega, g, c.t, trajectory_samples)
        # Kahan-compensated time of the contact
        y_step = c.t - t_comp
        t_new = t_sum + y_step
        t_comp = (t_new - t_sum) - y_step
        t_sum = t_new
        kind = _classify(c, k)
        if kind != "impact":
            y_contact = y0 + vy * c.t - 0.5 * g * c.t * c.t
            failure = _failure(geo, k, t_sum, c.x, y_contact, vx, c.vy, omega, kind, passed + 1,
                               _failure_detail(kind, c, geo, k, r), c.step)
            break
        j = c.step
        back, nose, level = geo.relative(k, j)
        mu_j = built.friction_at(j, mu)
        vx_a, vy_a, om_a, slipped, demand = impact_once(vx, c.vy, omega,
                                                        built.restitution_at(j, eps), mu_j, r,
                                                        m, inertia)
        landing_x = c.x - back
        speed = math.hypot(vx, c.vy)
        apex = 0.5 * vy_a * vy_a / g
        passed += 1
        summary.add((landing_x, speed, vx_a, om_a, apex))
        if slipped:
            summary.slips += 1
        raw = (k, c.x, j, t_sum, landing_x, speed, vx, vx_a, c.vy, vy_a, omega, om_a, apex,
               slipped, demand, mu_j)
        if passed <= record_limit or passed == stages:
            last_record = _record(geo, raw, stage_records, events, r)
            raw = None
        # new frame: step j's nose
        k, x0, y0 = j, c.x - nose, 0.0
        vx, vy, omega = vx_a, vy_a, om_a
    if failure is not None:
        if passed and raw is not None:  # the impact before a failure beyond record_limit
            last_record = _record(geo, raw, stage_records, events, r)
        events.append(failure)
    outcome = Outcome(completed=failure is None and passed == stages, stages_passed=passed,
                      failure=failure)
    last_step = (failure.after["step"] if failure else k) + 1
    staircase = [{"step": s, "back": geo.back_x(s), "nose": geo.nose_x(s), "level": geo.level(s)}
                 for s in range(0, min(last_step, 10_000) + 1)]
    return StairsSimulationResult(
        scene="stairs", outcome=outcome, stages=stage_records, events=events, accuracy=acc,
        trajectory=traj, summary=summary.to_dict(record_limit, last_record),
        staircase=staircase,
    )


def check_stairs_scales(scene: StairsScene, design: StairsDesign,
                        geo: StairsGeometry | None = None) -> None:
    """Refuse (core.SimulationRefused) a staircase whose lengths and speeds are so far from the
    drop height and sqrt(g h0) that double precision cannot follow the ball. Without `geo`
    only the scene and the design as given are checked (before the staircase is derived)."""
    h0, g, ball = scene.initial.drop_height, scene.gravity, scene.ball
    check_scales(("the gravity", g), {})
    check_scales(("the ball's mass", ball.mass), {})
    if geo is None:
        given = {"rise": design.rise, "tread": design.tread,
                 "landing_offset": design.landing_offset}
        lengths = {k: v for k, v in given.items() if v is not None}
    else:
        lengths = {"rise": geo.rise, "tread": geo.tread, "landing_offset": geo.landing_offset}
        for step, err in geo.rise_errors.items():
            lengths[f"rise error of step {step}"] = err
        for step, err in geo.tread_errors.items():
            lengths[f"tread error of step {step}"] = err
    lengths["ball radius"] = ball.radius
    check_scales(("the drop height", h0), lengths)
    speed = math.sqrt(g) * math.sqrt(h0)
    check_scales(("sqrt(g h0)", speed), {"launch_speed": design.launch_speed,
                                         "spin x radius": scene.initial.spin * ball.radius})
    dimensionless = {"friction": scene.friction}
    if scene.friction > 0.0:  # a rolling ball: its spin is -vx / r, its inertia counts vs m r^2
        check_scales(("the ball radius", ball.radius), {"drop height": h0})
        dimensionless["inertia / (mass radius^2)"] = ball.inertia / ball.mass / ball.radius ** 2
    check_scales(("1", 1.0), dimensionless)


def _record(geo, raw, stage_records, events, r):
    """Append the stage record and the impact (and slip) events of one impact."""
    (k, x, j, t, landing_x, speed, vx, vx_a, vy, vy_a, omega, om_a, apex, slipped,
     demand, mu) = raw
    xg, yg = geo.nose_x(k) + x, geo.level(j)
    record = {
        "step": j, "impact_time": t, "landing_x": landing_x, "impact_speed": speed,
        "vx_before": vx, "vx": vx_a, "vy_before": vy, "vy_after": vy_a,
        "spin_before": omega, "spin_after": om_a, "apex_height": apex,
        "slipped": slipped, "friction_demand": demand, "x": xg, "y": yg,
    }
    stage_records.append(record)
    before = {"x": xg, "y": yg, "vx": vx, "vy": vy, "omega": omega}
    after = {"x": xg, "y": yg, "vx": vx_a, "vy": vy_a, "omega": om_a}
    events.append(Event(t, "impact", j, before, after,
                        f"landed {landing_x:.6g} m from the back of tread {j}"))
    if slipped:
        events.append(Event(t, "slip", j, before, after,
                            _slip_detail(vx_a + r * om_a, demand, mu)))
    return record


def _check_start(geo, x0, y0, r):
    """Refuse a launch that starts inside the stairs (SimulationRefused, a ValueError)."""
    j = step_under(geo, 0, x0)
    back, _, level = geo.relative(0, j)
    if y0 < level:
        raise SimulationRefused(f"the ball starts below the tread of step {j}: drop_height "
                         f"{geo.launch_height:g} m is too small for this staircase")
    if j > 0:
        upper = geo.relative(0, j - 1)[2]
        gap = math.hypot(x0 - back, max(0.0, y0 + r - upper))  # centre to the riser segment
        if gap < r:
            raise SimulationRefused(f"the ball starts overlapping the riser of step {j}: move the "
                             "landing_offset or lower the drop height")


def _classify(c: Contact, k: int) -> str:
    if c.kind == "corner":
        return "nose_hit"
    if c.kind == "face":
        return "riser_hit"
    if c.step == k + 1:
        return "impact"
    if c.step == k:
        return "double_landing"
    return "skipped_step" if c.step > k + 1 else "bounced_back"


def _failure_detail(kind, c, geo, k, r):
    if kind == "nose_hit":
        return f"the ball (radius {r:g} m) touches the nose of step {c.step}"
    if kind == "riser_hit":
        return f"the ball touches the riser at the back of tread {c.step}"
    back = geo.relative(k, c.step)[0]
    where = (f"{c.x - back:.6g} m from the back of tread {c.step}" if c.step > 0 else
             f"{-c.x:.6g} m before its nose (the top landing)")
    if kind == "double_landing":
        return f"the ball comes down again on step {c.step}, {where}"
    if kind == "skipped_step":
        return f"the ball passes step {k + 1} and lands on step {c.step}, {where}"
    return f"the ball flies back up the stairs and lands on step {c.step}, {where}"


def _slip_detail(slip_after, demand, mu):
    return (f"the contact point still slides at {slip_after:.6g} m/s after the impact: rolling "
            f"would need friction >= {demand:.4g}, the tread has {mu:g}")


def _failure(geo, k, t, x, y, vx, vy, omega, kind, stage, detail, step):
    """The failure event of bounce `stage` (stages passed + 1), at `step` (its state's
    "step": the step whose nose, riser or tread the ball meets)."""
    xg, yg = geo.nose_x(k) + x, geo.level(k) + y
    state = {"x": xg, "y": yg, "vx": vx, "vy": vy, "omega": omega, "step": step}
    return Event(t, kind, stage, state, dict(state), detail, failure=True)


def _sample_flight(traj, geo, k, t0, x0, y0, vx, vy, omega, g, duration, samples):
    """Closed-form samples of one flight (global frame; y is the lowest point)."""
    xn, yl = geo.nose_x(k), geo.level(k)
    for i in range(samples + 1):
        t = duration * i / samples
        traj["time"].append(t0 + t)
        traj["x"].append(xn + x0 + vx * t)
        traj["y"].append(yl + y0 + vy * t - 0.5 * g * t * t)
        traj["vx"].append(vx)
        traj["vy"].append(vy - g * t)
        traj["omega"].append(omega)
