"""Event simulator of the compass gait: each step integrated (scipy's DOP853) to its heel strike,
the strike's reset, and the falls named.

A step runs in two phases: until the swing leg passes the stance leg (q1 - q2 rises through 0),
then until the heel strike, the guard's first fall through 0 (physics.strike_guard) after it.
The swing foot's scuffing as the legs pass is ignored, as the field does (straight legs of equal
length touch the ground there): the foot may go under the ground before the legs pass, and after
it until the guard rises back through 0; the deepest it goes is recorded (`scuff_depth`, per leg
length). Failures:
    fell_backward  the stance leg stops (w1 falls through 0) before the hip passes over the foot,
                   or the step ends with the walker moving back
    fell_forward   the hip reaches the ground (stance leg perpendicular to the ramp) first, or
                   the stance foot leaves the ground with the stance leg past the ramp's normal
                   and the swing leg still behind it
    scuffed        the swing leg, having passed the stance leg, swings back behind it, or the
                   walker falls with the swing foot still under the ground since the legs passed
    flight         the stance foot's normal force falls through 0, or a heel strike's normal
                   impulse is not positive
    slip           the friction the stance foot needs exceeds the scene's, in the stance phase or
                   at a heel strike (impulse ratio)
step_errors: per-step slope errors (rad) added to the design's slope for the ground from each
stance foot to the next (rough ground).
Each step's record gives its new stance foot's place (foot_x, foot_y; m, x downhill along the
horizontal, y up, the first stance foot at the origin); a recorded trajectory gives the state,
the hip's place (x, y) and the stance foot's (foot_x, foot_y) at every sample.
"""

from __future__ import annotations

import math

import numpy as np

from ...accuracy import Accuracy
from ...accuracy import accuracy as accuracy_preset
from ...sim.core import Event, Outcome, SimulationRefused, SimulationResult, check_scales
from . import physics as phys
from .ground import ground_of, params_for

FAILURE_KINDS = ("fell_forward", "fell_backward", "scuffed", "slip", "flight")
STATE_NAMES = ("stance", "swing", "stance_rate", "swing_rate")
PLACE_NAMES = ("x", "y", "foot_x", "foot_y")  # trajectory: the hip's place, the stance foot's (m)
MAX_STEP_TIME = 20.0  # x sqrt(l / g): a step that long is a fall
SAMPLES = 64  # dense-output samples per step for the margins


def _named(x) -> dict[str, float]:
    return {n: float(v) for n, v in zip(STATE_NAMES, x)}


class StepOutcome:
    """One step from a post-strike state: kind ("step" or a failure), time taken, the state at its
    end (before the reset), after the reset, and the step's margins."""

    def __init__(self, kind, time, end, after, detail="", margins=None, trajectory=None):
        self.kind, self.time, self.end, self.after = kind, time, end, after
        self.detail, self.margins, self.trajectory = detail, margins or {}, trajectory


def one_step(params: phys.Params, ground, x0, friction: float, acc: Accuracy,
             keep_trajectory: bool = False) -> StepOutcome:
    """Integrate one step from the post-strike state x0 on `ground` (stepmap.Ground)."""
    from scipy.integrate import solve_ivp  # 0.4 s to import: only when a run needs it

    slope, rise = ground.slope, ground.rise_per_length
    t_max = MAX_STEP_TIME * math.sqrt(params.l / params.g)

    def rhs(_, x):
        a1, a2 = phys.accelerations(x[0], x[1], x[2], x[3], params)
        return [x[2], x[3], a1, a2]

    def normal(_, x):
        return phys.ground_reaction(*x, slope, params)[0]

    def slip_ahead(_, x):
        n, t = phys.ground_reaction(*x, slope, params)
        return friction * n - t

    def slip_back(_, x):
        n, t = phys.ground_reaction(*x, slope, params)
        return friction * n + t

    def passes(_, x):
        return x[0] - x[1]

    def backward(_, x):
        return x[2]

    def forward(_, x):
        return math.pi / 2 - (x[0] - slope)

    def strike(_, x):
        return phys.strike_guard(x[0], x[1], slope, rise)

    kinds = {normal: "flight", slip_ahead: "slip", slip_back: "slip", backward: "fell_backward",
             forward: "fell_forward"}
    for f in (normal, slip_ahead, slip_back, backward, forward, passes, strike):
        f.terminal, f.direction = True, -1.0
    passes.direction = 1.0
    tol = dict(method="DOP853", rtol=acc.rtol, atol=acc.atol, dense_output=True)
    stats = {"scuff_depth": 0.0, "normal_min": math.inf, "friction_max": 0.0}
    pieces = []

    def run(t0, x, events):
        sol = solve_ivp(rhs, (t0, t_max), x, events=events, **tol)
        _sample(sol, params, slope, stats, pieces)
        for f, times in zip(events, sol.t_events):
            if len(times):
                return f, float(times[0]), np.asarray(sol.y_events[events.index(f)][0])
        return None, float(sol.t[-1]), sol.y[:, -1]

    base = [normal, slip_ahead, slip_back, backward, forward]
    x0 = np.asarray(x0, dtype=float)
    for f in (normal, slip_ahead, slip_back):  # a condition that fails from the start
        if not f(0.0, x0) > 0.0:
            return StepOutcome(kinds[f], 0.0, x0, x0, _detail(kinds[f], x0, slope), stats)
    which, t, x = run(0.0, np.asarray(x0, dtype=float), base + [passes])
    if which is passes:
        scuffed = _swings_back()
        which, t, x = run(t, x, base + [scuffed, strike])
        if which is scuffed:
            return StepOutcome("scuffed", t, x, x, "the swing leg swings back behind the stance "
                               "leg before its heel strikes: its foot scuffs the ground",
                               stats, pieces)
    if which is None:
        kind = "fell_forward" if x[0] > 0 else "fell_backward"
        return StepOutcome(kind, t, x, x, f"no heel strike within {t_max:.3g} s", stats, pieces)
    if which is not strike and which is not passes:
        kind = kinds[which]
        if kind == "flight" and x[0] > slope and x[0] < x[1]:
            kind = "fell_forward"
        if x[0] > x[1] and phys.strike_guard(x[0], x[1], slope, rise) < 0.0:
            kind = "scuffed"  # the swing foot has been under the ground since the legs passed
        return StepOutcome(kind, t, x, x, _detail(kind, x, slope), stats, pieces)
    after = np.array(phys.heel_strike(*x, params), dtype=float)
    pn, pt = phys.strike_impulse(*x, params, slope)
    stats["strike_friction"] = abs(pt) / pn if pn > 0 else math.inf
    stats["strike_normal"] = pn
    if not pn > 0.0:
        return StepOutcome("flight", t, x, after, f"the heel strike's normal impulse is {pn:.4g} "
                           "N s/kg: the foot does not stay down", stats, pieces)
    if abs(pt) > friction * pn:
        return StepOutcome("slip", t, x, after, f"the heel strike needs friction "
                           f"{abs(pt) / pn:.4g}, the ground has {friction:g}", stats, pieces)
    return StepOutcome("step", t, x, after, "", stats, pieces)


def _swings_back():
    def scuffed(_, x):
        return x[0] - x[1]

    scuffed.terminal, scuffed.direction = True, -1.0
    return scuffed


def _detail(kind, x, slope):
    q1 = x[0]
    return {
        "flight": "the stance foot's normal force falls to zero: it leaves the ground",
        "slip": "the stance foot needs more friction than the ground has",
        "fell_backward": f"the stance leg stops at {q1:.4g} rad, before the hip passes over the "
                         "foot: the walker falls back",
        "scuffed": "the swing foot went under the ground as the legs passed and never came "
                   "up before the walker fell: it scuffs",
        "fell_forward": "the walker falls forward (the hip to the ground, or the stance foot "
                        "leaving it) before the swing leg passes the stance leg",
    }[kind]


def _sample(sol, params, slope, stats, pieces):
    """Margins over the dense output: the smallest normal force per weight, the largest friction
    demand, the swing foot's deepest scuff before it passes (per leg length)."""
    t = np.linspace(sol.t[0], sol.t[-1], SAMPLES)
    x = sol.sol(t)
    n, tang = phys.ground_reaction(x[0], x[1], x[2], x[3], slope, params)
    weight = (1 + 2 * params.beta) * params.g
    stats["normal_min"] = min(stats["normal_min"], float(np.min(n)) / weight)
    with np.errstate(divide="ignore", invalid="ignore"):
        demand = np.where(n > 0, np.abs(tang) / n, np.inf)
    stats["friction_max"] = max(stats["friction_max"], float(np.max(demand)))
    spread = float(np.max(np.abs(x[0] - x[1])))  # the angle between the legs
    stats["leg_angle_max"] = max(stats.get("leg_angle_max", 0.0), spread)
    depth = phys.foot_height(x[0], x[1], slope, params) / params.l
    stats["scuff_depth"] = min(stats["scuff_depth"], float(np.min(depth)))
    pieces.append((t, x))


def simulate_compass_gait(scene, design, *, stages: int, accuracy: str | Accuracy = "default",
                          step_errors=(), record_trajectory: bool = False,
                          start=None, rise_errors=()) -> SimulationResult:
    """Simulate the walker from the scene's initial state (or `start`, a post-strike state) for
    `stages` steps (heel strikes). step_errors: per-step slope errors (rad), the k-th for the
    ground under step k + 1 (missing ones 0); rise_errors: on stairs, per-step rise errors (m).
    Stops at the first failure."""
    acc = accuracy_preset(accuracy)
    stages = int(stages)
    if stages < 0:
        raise SimulationRefused(f"stages must be >= 0, not {stages}")
    params = params_for(scene, design)
    check_scales(("the leg length", params.l), {"leg_com": params.b})
    check_scales(("the gravity", params.g), {})
    x = np.array(scene.initial.state() if start is None else start, dtype=float)
    errors, rises = list(step_errors), list(rise_errors)
    records, events, traj = [], [], {}
    if record_trajectory:
        traj = {n: [] for n in ("time", *STATE_NAMES, *PLACE_NAMES)}
    foot = (0.0, 0.0)  # the stance foot's place (m): x downhill, y up, the first at the origin
    t_sum, failure, passed = 0.0, None, 0
    while passed < stages:
        error = float(errors[passed]) if passed < len(errors) else 0.0
        rise = float(rises[passed]) if passed < len(rises) else 0.0
        ground = ground_of(design, params, error, rise)
        out = one_step(params, ground, x, scene.friction, acc)
        if record_trajectory:
            _append(traj, out.trajectory, t_sum, foot, params.l)
        t_sum += out.time
        if out.kind != "step":
            failure = Event(t_sum, out.kind, passed + 1, _named(out.end), _named(out.after),
                            out.detail, failure=True)
            break
        passed += 1
        foot = next_foot(foot, out.end, params.l)
        lost = phys.kinetic_energy(*out.end, params) - phys.kinetic_energy(*out.after, params)
        record = {"step": passed, "time": t_sum, "step_period": out.time,
                  "step_length": float(phys.step_length(out.end[0], out.end[1], params)),
                  "foot_x": foot[0], "foot_y": foot[1], "slope": ground.slope,
                  "energy_lost": float(lost), **out.margins,
                  **_named(out.after)}
        records.append(record)
        events.append(Event(t_sum, "heel_strike", passed, _named(out.end), _named(out.after),
                            f"step {passed}: {record['step_length']:.6g} m"))
        x = out.after
    if failure is not None:
        events.append(failure)
    outcome = Outcome(completed=failure is None, stages_passed=passed, failure=failure)
    return SimulationResult(scene="compass_gait", outcome=outcome, stages=records,
                            events=events, accuracy=acc, trajectory=traj)


def next_foot(foot, end, leg_length):
    """The new stance foot's place (m) after a heel strike from the pre-strike state `end`: the
    swing foot's, foot + l (sin q1 - sin q2, cos q1 - cos q2)."""
    q1, q2 = float(end[0]), float(end[1])
    return (foot[0] + leg_length * (math.sin(q1) - math.sin(q2)),
            foot[1] + leg_length * (math.cos(q1) - math.cos(q2)))


def _append(traj, pieces, t0, foot, leg_length):
    """The step's samples: time, state, the hip's place (x, y) and the stance foot's (m)."""
    for t, x in pieces or ():
        traj["time"].extend((t + t0).tolist())
        for name, row in zip(STATE_NAMES, x):
            traj[name].extend(row.tolist())
        traj["x"].extend((foot[0] + leg_length * np.sin(x[0])).tolist())
        traj["y"].extend((foot[1] + leg_length * np.cos(x[0])).tolist())
        traj["foot_x"].extend([foot[0]] * len(t))
        traj["foot_y"].extend([foot[1]] * len(t))
