"""Event simulator of a ball bouncing down stairs (paper sections 3.1-3.2).

Frame and conventions (as in ``pdm_design.physics.stairs``): x downhill, y up, spin omega
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
    nose_hit        failure: the ball touches a step's nose corner (stage = that step)
    riser_hit       failure: the ball touches a riser face (stage = the step whose riser it is)
    skipped_step    failure: the ball lands on a step beyond the next one (stage = where it lands)
    double_landing  failure: the ball lands again on the step it left (stage = that step; for the
                    launch, landing on the top landing, step 0)
    bounced_back    failure: the ball flies back up and lands on an earlier step
    no_rebound      failure: the ball leaves a tread with no vertical speed (restitution 0); it
                    would roll or slide along the tread, which the model does not cover
``left_stairs`` is never produced: the staircase is built as far as the requested bounces need.

Long runs: full stage records and events are kept for the first ``record_limit`` bounces
(default 10 000) plus the last one; `StairsSimulationResult.summary` carries running statistics
over every bounce (extremes of landing position, speeds, spin, apex; counts), so a 10^6-bounce
run needs memory for record_limit records only. Trajectories (``record_trajectory=True``) are
sampled by the closed form, ``trajectory_samples`` points per flight, for the first
``trajectory_limit`` flights.

Vectorised closed forms for many samples at once: `impact_map` (one impact) and
`bounce_sequence` (many samples, many bounces on a uniform staircase, with failure detection).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ..scenes import StairsDesign, StairsScene
from .core import Accuracy, Event, Outcome, SimulationResult
from .core import accuracy as accuracy_preset

FAILURE_KINDS = ("nose_hit", "riser_hit", "skipped_step", "double_landing", "bounced_back",
                 "no_rebound")
DEFAULT_RECORD_LIMIT = 10_000
_MAX_STEPS_PER_FLIGHT = 100_000


# --------------------------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class StairsGeometry:
    """The staircase as built, plus the launch. Global frame: nominal tread 1 at y = 0, launch
    at x = 0. rise, tread: nominal; landing_offset: where the first landing is designed to be
    (from the back of tread 1); x_back_1: the back of tread 1 (= nose of step 0)."""

    rise: float
    tread: float
    landing_offset: float
    x_back_1: float
    launch_height: float
    rise_errors: dict[int, float] = field(default_factory=dict)
    tread_errors: dict[int, float] = field(default_factory=dict)

    def tread_length(self, j: int) -> float:
        return math.inf if j == 0 else self.tread + self.tread_errors.get(j, 0.0)

    def rise_height(self, j: int) -> float:
        return self.rise + self.rise_errors.get(j, 0.0)

    def nose_x(self, j: int) -> float:
        """Global x of step j's nose (j >= 0)."""
        return self.x_back_1 + j * self.tread + _error_sum(self.tread_errors, 0, j)

    def back_x(self, j: int) -> float:
        return -math.inf if j == 0 else self.nose_x(j - 1)

    def level(self, j: int) -> float:
        """Global height of step j's tread surface."""
        return (1 - j) * self.rise - _error_sum(self.rise_errors, 0, j)

    def relative(self, k: int, j: int) -> tuple[float, float, float]:
        """(back, nose, level) of step j in the frame at step k's nose and level."""
        if not self.tread_errors and not self.rise_errors and j > 0:
            nose = (j - k) * self.tread
            return nose - self.tread, nose, -(j - k) * self.rise
        nose = (j - k) * self.tread + _error_diff(self.tread_errors, k, j)
        level = -(j - k) * self.rise - _error_diff(self.rise_errors, k, j)
        if j == 0:
            back = -math.inf
        else:
            back = nose - self.tread_length(j)
        return back, nose, level


def _error_sum(errors: dict[int, float], k: int, j: int) -> float:
    """Sum of errors of steps k < i <= j (k <= j)."""
    if not errors:
        return 0.0
    return math.fsum(v for i, v in errors.items() if k < i <= j)


def _error_diff(errors: dict[int, float], k: int, j: int) -> float:
    """sum_{i<=j} - sum_{i<=k} of the errors."""
    if not errors or j == k:
        return 0.0
    return _error_sum(errors, k, j) if j > k else -_error_sum(errors, j, k)


def stairs_geometry(scene: StairsScene, design: StairsDesign, step_errors=()) -> StairsGeometry:
    """The staircase a design describes (rise, tread, landing offset derived where left out).

    rise = (1 - eps^2) h0 and tread = vx1 (1 + eps) v*/g, with vx1 the horizontal speed after
    the first impact (the impact map applied to the launch state) and v* the periodic vertical
    impact speed: sqrt(2 g h0) for a derived rise, sqrt(2 g rise / (1 - eps^2)) for a given one.
    landing_offset defaults to tread / 2. Raises ValueError when no tread can be derived or an
    error makes a step's tread non-positive or its rise negative.
    """
    g, h0 = scene.gravity, scene.initial.drop_height
    eps, v0 = design.restitution, design.launch_speed
    rise = (1.0 - eps**2) * h0 if design.rise is None else design.rise
    tread = design.tread
    if tread is None:
        if design.rise is None or (rise == 0.0 and eps == 1.0):
            v_star = math.sqrt(2.0 * g * h0)
        elif eps < 1.0:
            v_star = math.sqrt(2.0 * g * rise / (1.0 - eps**2))
        else:
            raise ValueError("restitution 1 with a rise > 0 has no periodic orbit: give the tread")
        ball = scene.ball
        vx1 = _impact(v0, -math.sqrt(2.0 * g * h0), scene.initial.spin, eps, scene.friction,
                      ball.radius, ball.mass, ball.inertia)[0]
        tread = vx1 * (1.0 + eps) * v_star / g
        if not tread > 0.0:
            raise ValueError(f"the derived tread is {tread:g} m (restitution {eps:g}, horizontal "
                             f"speed after the first impact {vx1:g} m/s): give the tread")
    landing = tread / 2.0 if design.landing_offset is None else design.landing_offset
    t1 = math.sqrt(2.0 * h0 / g)
    rise_errors: dict[int, float] = {}
    tread_errors: dict[int, float] = {}
    for e in step_errors:
        step, d_rise, d_tread = _step_error_fields(e)
        rise_errors[step] = rise_errors.get(step, 0.0) + d_rise
        tread_errors[step] = tread_errors.get(step, 0.0) + d_tread
    for step, d in tread_errors.items():
        if not tread + d > 0.0:
            raise ValueError(f"step {step}: tread error {d:g} m leaves no tread "
                             f"(nominal tread {tread:g} m)")
    for step, d in rise_errors.items():
        if rise + d < 0.0:
            raise ValueError(f"step {step}: rise error {d:g} m makes the step go up "
                             f"(nominal rise {rise:g} m)")
    return StairsGeometry(
        rise=float(rise), tread=float(tread), landing_offset=float(landing),
        x_back_1=v0 * t1 - landing, launch_height=float(h0),
        rise_errors={k: v for k, v in rise_errors.items() if v != 0.0},
        tread_errors={k: v for k, v in tread_errors.items() if v != 0.0},
    )


def _step_error_fields(e):
    if isinstance(e, dict):
        return int(e["step"]), float(e.get("rise", 0.0)), float(e.get("tread", 0.0))
    step = int(e.step)
    if step < 1:
        raise ValueError(f"step errors are numbered from 1, not {step}")
    return step, float(getattr(e, "rise", 0.0)), float(getattr(e, "tread", 0.0))


# --------------------------------------------------------------------------------------------
# Impact maps
# --------------------------------------------------------------------------------------------

def _impact(vx, vy, omega, eps, mu, r, m, inertia):
    """Scalar impact map: (vx+, vy+, omega+, slipped, friction demand |P_roll| / Pn)."""
    vy_after = -eps * vy
    if mu == 0.0:
        return vx, vy_after, omega, False, 0.0
    slip = vx + r * omega
    share = inertia / (inertia + m * r * r)        # (impulse that stops the slip) / (m c)
    need = abs(slip) * share                       # |P_roll| / m
    normal = (1.0 + eps) * abs(vy)                 # Pn / m
    demand = need / normal if normal > 0.0 else (0.0 if need == 0.0 else math.inf)
    if need <= mu * normal:
        vx_after = vx - slip * share               # = (m r^2 vx - J r omega) / (m r^2 + J)
        return vx_after, vy_after, -vx_after / r, False, demand
    dv = -math.copysign(mu * normal, slip)
    return vx + dv, vy_after, omega + m * r * dv / inertia, True, demand


class Impact(NamedTuple):
    """Velocities just after an impact with a tread (arrays), and where the contact slid."""

    vx: np.ndarray
    vy: np.ndarray
    omega: np.ndarray
    slipped: np.ndarray


def impact_map(vx, vy, omega, eps, mu, r, m, J) -> Impact:
    """The stairs impact map on numpy arrays (broadcast; any argument may be a scalar).

    vy is the vertical velocity before the impact (< 0). Newton restitution vy+ = -eps vy;
    frictionless (mu = 0): vx and omega unchanged. With Coulomb friction mu the contact slip
    c = vx + r omega needs |P| = |c| m J / (J + m r^2) to stop; if |P| <= mu m (1 + eps)|vy| the
    impact ends rolling (vx+ = vx - c J / (J + m r^2), omega+ = -vx+ / r), otherwise it slides
    throughout (P = -sign(c) mu Pn). J = 0 with friction: the spin follows at once (rolling).
    Friction needs r > 0 (mu > 0 with r = 0 gives NaN spin).
    """
    vx = np.asarray(vx, dtype=float)
    vy = np.asarray(vy, dtype=float)
    omega = np.asarray(omega, dtype=float)
    vy_after = -eps * vy
    if np.ndim(mu) == 0 and mu == 0.0:
        shape = np.broadcast_shapes(vx.shape, vy.shape, omega.shape)
        return Impact(np.broadcast_to(vx, shape).copy(), np.broadcast_to(vy_after, shape).copy(),
                      np.broadcast_to(omega, shape).copy(), np.zeros(shape, dtype=bool))
    with np.errstate(divide="ignore", invalid="ignore"):
        vx_after, omega_after, slipped = _impact_arrays(vx, vy, omega, eps, mu, r, m, J)
    return Impact(vx_after, np.broadcast_to(vy_after, vx_after.shape).copy(), omega_after,
                  slipped)


def _impact_arrays(vx, vy, omega, eps, mu, r, m, J):
    """Tangential part of impact_map on arrays: (vx+, omega+, slipped)."""
    slip = vx + r * omega
    share = J / (J + m * (r * r))
    stick = slip * share                                # -(impulse to stop the slip) / m
    limit = mu * (1.0 + eps) * np.abs(vy)              # mu Pn / m
    rolls = np.abs(stick) <= limit
    dv = np.where(rolls, -stick, -np.copysign(limit, slip))
    vx_after = vx + dv
    omega_after = np.where(rolls, -vx_after / r, omega + m * r * dv / J)
    if np.ndim(mu) or mu == 0.0:
        frictionless = np.asarray(mu) == 0.0
        if np.any(frictionless):
            vx_after = np.where(frictionless, vx, vx_after)
            omega_after = np.where(frictionless, omega, omega_after)
            rolls = rolls | frictionless
    return vx_after, omega_after, ~rolls


# --------------------------------------------------------------------------------------------
# Flight: the next contact, in closed form
# --------------------------------------------------------------------------------------------

def _descend(vy, height, g):
    """(t, vy(t)) when a body at height 0 moving up at vy, falling under g, passes `height`
    going down; None if it never gets that high. The root is taken without cancellation."""
    disc = vy * vy - 2.0 * g * height
    if disc < 0.0:
        return None
    s = math.sqrt(disc)
    t = (vy + s) / g if vy >= 0.0 else -2.0 * height / (s - vy)
    return t, -s


class _Contact(NamedTuple):
    kind: str       # "tread", "corner", "face"
    step: int
    t: float
    x: float        # ball centre x at contact, frame of the step left
    vy: float       # vertical velocity at contact


def _corner_time(px, py, vx, vy, r, g, t_max, tol):
    """First time the centre, starting at the origin with (vx, vy) under gravity, comes within
    r of the corner (px, py), entering; None if not before t_max.

    Distance^2 - r^2 is the quartic (g^2/4) t^4 - g vy t^3 + (vx^2 + vy^2 + g py) t^2
    - 2 (vx px + vy py) t + px^2 + py^2 - r^2. It is only solved when a cheap window test
    (the centre within r of the corner horizontally and vertically) says contact is possible.
    """
    if vx > 0.0:
        ta, tb = (px - r) / vx, (px + r) / vx
    elif vx < 0.0:
        ta, tb = (px + r) / vx, (px - r) / vx
    else:
        if abs(px) > r:
            return None
        ta, tb = 0.0, t_max
    ta, tb = max(ta, 0.0), min(tb, t_max)
    if not ta <= tb:
        return None
    ea = vy * ta - 0.5 * g * ta * ta - py
    eb = vy * tb - 0.5 * g * tb * tb - py
    if min(ea, eb) >= r:
        return None
    tv = vy / g
    emax = vy * tv - 0.5 * g * tv * tv - py if ta < tv < tb else max(ea, eb)
    if emax <= -r:
        return None
    tau = tb if tb > 0.0 else 1.0          # time scale: roots of interest in [0, 1]
    c = (0.25 * g * g * tau**4, -g * vy * tau**3, (vx * vx + vy * vy + g * py) * tau**2,
         -2.0 * (vx * px + vy * py) * tau, px * px + py * py - r * r)

    def f(t):
        return (((c[0] * t + c[1]) * t + c[2]) * t + c[3]) * t + c[4]

    def df(t):
        return ((4.0 * c[0] * t + 3.0 * c[1]) * t + 2.0 * c[2]) * t + c[3]

    scale = px * px + py * py + r * r
    lo, hi = ta / tau, tb / tau
    best = None
    for z in np.roots(c):
        if abs(z.imag) > 1e-4 * max(1.0, abs(z.real)):
            continue
        s = float(z.real)
        for _ in range(30):                # Newton polish (linear near a graze's double root)
            d = df(s)
            if d == 0.0:
                break
            step = f(s) / d
            s -= step
            if abs(step) * tau <= tol:
                break
        if abs(f(s)) > 1e-9 * scale or not (lo - 1e-9 <= s <= hi + 1e-9) or s * tau <= tol:
            continue
        if df(s) > 1e-7 * scale:
            continue                       # leaving: it touched at the start (landed on the nose)
        if best is None or s < best:
            best = s
    return None if best is None else best * tau


def _next_contact(geo: StairsGeometry, k, x0, y0, vx, vy, r, g, tol):
    """First contact of a flight starting over step(s) near step k, in the frame of step k's
    nose: lowest point at (x0, y0), velocity (vx, vy)."""
    j0 = k if k > 0 else _step_under(geo, k, x0)   # after an impact the ball is over step k
    if vx >= 0.0:
        return _forward(geo, k, j0, x0, y0, vx, vy, r, g, tol)
    return _backward(geo, k, j0, x0, y0, vx, vy, r, g, tol)


def _step_under(geo, k, x):
    j = k
    back, nose, _ = geo.relative(k, j)
    while x > nose:
        j += 1
        back, nose, _ = geo.relative(k, j)
    while x < back:
        j -= 1
        back, nose, _ = geo.relative(k, j)
    return j


def _forward(geo, k, j, x0, y0, vx, vy, r, g, tol):
    passed = []
    for _ in range(_MAX_STEPS_PER_FLIGHT):
        _, nose, level = geo.relative(k, j)
        t, vy_hit = _descend(vy, level - y0, g)
        x = x0 + vx * t
        if x <= nose:
            landing = _Contact("tread", j, t, x, vy_hit)
            break
        passed.append((j, nose, level))
        j += 1
    else:  # pragma: no cover - treads of positive length always stop the loop
        raise RuntimeError("flight passes more steps than the simulator searches")
    if r > 0.0:
        first = None
        for step, nose, level in passed:
            tc = _corner_time(nose - x0, level - y0 - r, vx, vy, r, g, landing.t, tol)
            if tc is not None and tc < landing.t - tol and (first is None or tc < first.t):
                first = _Contact("corner", step, tc, x0 + vx * tc, vy - g * tc)
        if first is not None:
            return first
    return landing


def _backward(geo, k, j, x0, y0, vx, vy, r, g, tol):
    apex = y0 + 0.5 * max(vy, 0.0) ** 2 / g
    found: list[_Contact] = []
    while True:
        back, nose, level = geo.relative(k, j)
        landed = False
        hit = _descend(vy, level - y0, g) if apex >= level else None
        if hit is not None:
            x = x0 + vx * hit[0]
            if back <= x <= nose:
                found.append(_Contact("tread", j, hit[0], x, hit[1]))
                landed = True
        if j == 0:
            break
        upper = geo.relative(k, j - 1)[2]
        if x0 > back + r:  # the riser face at the back of tread j, from `level` up to `upper`
            tf = (back + r - x0) / vx
            yc = y0 + r + vy * tf - 0.5 * g * tf * tf
            if level <= yc <= upper:
                found.append(_Contact("face", j, tf, back + r, vy - g * tf))
        if r > 0.0:
            tc = _corner_time(back - x0, upper - y0 - r, vx, vy, r, g, math.inf, tol)
            if tc is not None:
                found.append(_Contact("corner", j - 1, tc, x0 + vx * tc, vy - g * tc))
        if landed or apex < upper:
            break
        j -= 1
    if not found:  # pragma: no cover - a backward flight always meets a face, corner or tread
        raise RuntimeError(f"no contact found for a backward flight from step {k}")
    # earliest contact; a tread landing wins a tie with a corner or face it meets at its edge
    return min(found, key=lambda c: (c.t - (tol if c.kind == "tread" else 0.0)))


# --------------------------------------------------------------------------------------------
# The event-located run
# --------------------------------------------------------------------------------------------

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
               "records_kept": min(self.count, record_limit), "record_limit": record_limit}
        if self.count:
            for key in self.KEYS:
                out[f"{key}_min"] = self.lo[key]
                out[f"{key}_max"] = self.hi[key]
            out["last"] = last
        return out


def simulate_stairs(scene: StairsScene, design: StairsDesign, *, stages: int,
                    accuracy: str | Accuracy = "default", step_errors=(),
                    record_trajectory: bool = False, record_limit: int = DEFAULT_RECORD_LIMIT,
                    trajectory_samples: int = 48, trajectory_limit: int = 1000,
                    ) -> StairsSimulationResult:
    """Simulate the ball from its launch for `stages` bounces (impacts on successive steps).

    step_errors: objects (or dicts) with step (from 1), rise and tread: metres added to that
    step's rise and tread. The run stops at the first failure event. See the module docstring
    for the staircase, the event kinds and the memory policy of long runs.
    """
    acc = accuracy_preset(accuracy)
    stages = int(stages)
    if stages < 0:
        raise ValueError(f"stages must be >= 0, not {stages}")
    geo = stairs_geometry(scene, design, step_errors)
    g, eps, mu = scene.gravity, design.restitution, scene.friction
    r, m, inertia = scene.ball.radius, scene.ball.mass, scene.ball.inertia
    tol = acc.event_tol

    # launch, in the frame of step 0's nose (x_back_1, level of step 0)
    k = 0
    x0, y0 = -geo.x_back_1, geo.launch_height - geo.level(0)
    _check_start(geo, x0, y0, r)
    vx, vy, omega = design.launch_speed, 0.0, scene.initial.spin
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
        if vy <= 0.0 and y0 <= geo.relative(k, _step_under(geo, k, x0))[2]:
            failure = _failure(geo, k, t_sum, x0, y0, vx, vy, omega, "no_rebound", k,
                               "the ball is on a tread with no vertical speed: it would roll "
                               "or slide along it (outside the model)")
            break
        c = _next_contact(geo, k, x0, y0, vx, vy, r, g, tol)
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
            failure = _failure(geo, k, t_sum, c.x, y_contact, vx, c.vy, omega, kind, c.step,
                               _failure_detail(kind, c, geo, k, r))
            break
        j = c.step
        back, nose, level = geo.relative(k, j)
        vx_a, vy_a, om_a, slipped, demand = _impact(vx, c.vy, omega, eps, mu, r, m, inertia)
        landing_x = c.x - back
        speed = math.hypot(vx, c.vy)
        apex = 0.5 * vy_a * vy_a / g
        passed += 1
        summary.add((landing_x, speed, vx_a, om_a, apex))
        if slipped:
            summary.slips += 1
        raw = (k, c.x, j, t_sum, landing_x, speed, vx, vx_a, c.vy, vy_a, omega, om_a, apex,
               slipped, demand)
        if passed <= record_limit or passed == stages:
            last_record = _record(geo, raw, stage_records, events, r, mu)
            raw = None
        # new frame: step j's nose
        k, x0, y0 = j, c.x - nose, 0.0
        vx, vy, omega = vx_a, vy_a, om_a
    if failure is not None:
        if passed and raw is not None:  # the impact before a failure beyond record_limit
            last_record = _record(geo, raw, stage_records, events, r, mu)
        events.append(failure)
    outcome = Outcome(completed=failure is None and passed == stages, stages_passed=passed,
                      failure=failure)
    last_step = (failure.stage if failure else k) + 1
    staircase = [{"step": s, "back": geo.back_x(s), "nose": geo.nose_x(s), "level": geo.level(s)}
                 for s in range(0, min(last_step, 10_000) + 1)]
    return StairsSimulationResult(
        scene="stairs", outcome=outcome, stages=stage_records, events=events, accuracy=acc,
        trajectory=traj, summary=summary.to_dict(record_limit, last_record),
        staircase=staircase,
    )


def _record(geo, raw, stage_records, events, r, mu):
    """Append the stage record and the impact (and slip) events of one impact."""
    (k, x, j, t, landing_x, speed, vx, vx_a, vy, vy_a, omega, om_a, apex, slipped,
     demand) = raw
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
    """Refuse a launch that starts inside the stairs (ValueError)."""
    j = _step_under(geo, 0, x0)
    back, _, level = geo.relative(0, j)
    if y0 < level:
        raise ValueError(f"the ball starts below the tread of step {j}: drop_height "
                         f"{geo.launch_height:g} m is too small for this staircase")
    if j > 0:
        upper = geo.relative(0, j - 1)[2]
        gap = math.hypot(x0 - back, max(0.0, y0 + r - upper))  # centre to the riser segment
        if gap < r:
            raise ValueError(f"the ball starts overlapping the riser of step {j}: move the "
                             "landing_offset or lower the drop height")


def _classify(c: _Contact, k: int) -> str:
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
            f"would need friction >= {demand:.4g}, the scene has {mu:g}")


def _failure(geo, k, t, x, y, vx, vy, omega, kind, stage, detail):
    xg, yg = geo.nose_x(k) + x, geo.level(k) + y
    state = {"x": xg, "y": yg, "vx": vx, "vy": vy, "omega": omega}
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


# --------------------------------------------------------------------------------------------
# Vectorised bounces on a uniform staircase
# --------------------------------------------------------------------------------------------

BOUNCE_FAILURES = ("", "double_landing", "skipped_step", "nose_hit", "riser_hit")


@dataclass(frozen=True)
class BounceSequence:
    """State of many samples after bounce_sequence: the state just before the last impact
    reached (landing offset from the back of the tread, velocities), time since the first impact,
    bounces completed, and a failure code (index into BOUNCE_FAILURES; 0 = none), plus the
    extremes of the landing offset seen."""

    landing: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    omega: np.ndarray
    time: np.ndarray
    bounces: np.ndarray
    failure: np.ndarray
    landing_min: np.ndarray
    landing_max: np.ndarray

    def failure_kinds(self) -> list[str]:
        return [BOUNCE_FAILURES[i] for i in self.failure]


def bounce_sequence(landing, vx, vy, omega, *, bounces: int, rise: float, tread: float,
                    eps: float, mu: float = 0.0, r: float = 0.0, m: float = 1.0, J: float = 0.0,
                    g: float = 9.81, check_nose: bool = True) -> BounceSequence:
    """Advance many samples `bounces` bounces down a uniform staircase with plain numpy.

    Each sample starts just before an impact on a tread: landing offset from the tread's back,
    vx, vy (< 0), omega. A bounce = impact_map + the closed-form flight to the next tread:
        same-level return x = s + vx 2 vy+/g  (<= tread: double_landing; < 0: riser_hit, the
        ball went back), time to the next tread t = (vy+ + sqrt(vy+^2 + 2 g rise)) / g,
        s' = s + vx t - tread (> tread: skipped_step; it passes the next nose).
    check_nose (r > 0): the nose between the treads can only be touched when the same-level
    return is less than r beyond it; for those samples the centre path's distance to the nose
    is minimised by safeguarded Newton steps, exact when vx^2 + vy+^2 > g r (distance^2 convex
    there; any ball small against the flight's curvature radius). A failed sample is frozen
    with its failure code. Memory is O(samples) whatever `bounces` is.
    """
    s, vx, vy, om = (np.array(np.broadcast_arrays(landing, vx, vy, omega), dtype=float))
    frictionless = mu == 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return _bounce_loop(s, vx, vy, om, int(bounces), rise, tread, eps, mu, r, m, J, g,
                            check_nose, frictionless)


def _bounce_loop(s, vx, vy, om, bounces, rise, tread, eps, mu, r, m, J, g, check_nose,
                 frictionless):
    n = s.shape
    time, comp = np.zeros(n), np.zeros(n)
    done = np.zeros(n, dtype=np.int64)
    code = np.zeros(n, dtype=np.int8)
    lo, hi = s.copy(), s.copy()
    alive = np.ones(n, dtype=bool)
    all_alive = True
    two_g_rise = 2.0 * g * rise
    for _ in range(bounces):
        up = -eps * vy
        if frictionless:
            vx_a, om_a = vx, om
        else:
            vx_a, om_a, _ = _impact_arrays(vx, vy, om, eps, mu, r, m, J)
        x_same = s + vx_a * (2.0 / g) * up
        root = np.sqrt(up * up + two_g_rise)
        t = (up + root) / g
        s_next = s + vx_a * t - tread
        bad = (x_same <= tread) | (s_next > tread)
        if check_nose and r > 0.0:
            near = (x_same - tread < r) & ~bad
            if near.any():
                idx = np.flatnonzero(near)
                hit = _nose_hits(tread - s[idx], vx_a[idx], up[idx], r, g, t[idx])
                nose = np.zeros(n, dtype=bool)
                nose[idx[hit]] = True
                bad |= nose
            else:
                nose = None
        else:
            nose = None
        if all_alive and not bad.any():
            s, vx, om, vy = s_next, vx_a, om_a, -root
            y = t - comp                               # Kahan summation of the flight times
        else:
            fail = np.where(x_same <= tread, np.where(x_same < 0.0, 4, 1),
                            np.where(s_next > tread, 2, 0)).astype(np.int8)
            if nose is not None:
                fail[nose] = 3
            newly = alive & (fail != 0)
            code[newly] = fail[newly]
            alive &= fail == 0
            all_alive = False
            if not alive.any():
                break
            s = np.where(alive, s_next, s)
            vx = np.where(alive, vx_a, vx)
            om = np.where(alive, om_a, om)
            vy = np.where(alive, -root, vy)
            y = np.where(alive, t, 0.0) - comp
        tt = time + y
        comp = (tt - time) - y
        time = tt
        done += alive
        np.minimum(lo, s, out=lo)
        np.maximum(hi, s, out=hi)
    return BounceSequence(s, vx, vy, om, time, done, code, lo, hi)


def _nose_hits(d, vx, up, r, g, t_land):
    """True where the ball (leaving a tread at speed (vx, up), nose a distance d ahead) touches
    the nose before landing at t_land. Only called for samples that pass the nose."""
    t0 = 2.0 * up / g                                       # back at take-off height, past the nose
    t1 = np.minimum((up + np.sqrt(up * up + 2.0 * g * r)) / g, t_land)  # centre at nose level

    def grad(t):  # f(t) = (vx t - d)^2 + (r + up t - g t^2/2)^2 - r^2; returns f, f', f''
        dx = vx * t - d
        dy = r + up * t - 0.5 * g * t * t
        vyc = up - g * t
        f = dx * dx + dy * dy - r * r
        return f, 2.0 * (vx * dx + dy * vyc), 2.0 * (vx * vx + vyc * vyc - g * dy)

    lo, hi = t0.copy(), t1.copy()
    t = t1.copy()
    best = np.minimum(grad(t0)[0], grad(t1)[0])
    for _ in range(8):                                      # safeguarded Newton on f'
        f, d1, d2 = grad(t)
        best = np.minimum(best, f)
        lo = np.where(d1 < 0.0, t, lo)
        hi = np.where(d1 >= 0.0, t, hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = t - d1 / d2
        inside = (d2 > 0.0) & (newton > lo) & (newton < hi)
        t = np.where(inside, newton, 0.5 * (lo + hi))
    best = np.minimum(best, grad(t)[0])
    return best < 0.0
