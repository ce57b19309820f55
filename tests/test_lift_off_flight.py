"""After a lift-off the object flies on: against independent numbers.

Expected values come from closed forms written out here (the lift-off angle from
v^2 = g l cos th with the energy equation, elliptic-integral times, ballistic quadratics) and from
a separate integration of the empty palm's pendulum (scipy solve_ivp at rtol 1e-13) intersected
with the ballistic path by root finding; never from the simulator's output. The "before" runs
come from the simulator as it was before lift-offs were followed (the repository at
BEFORE_COMMIT, extracted with git archive), run in a separate interpreter.
Frame: origin at pivot 1, x along the row, y up; theta clockwise from the vertical.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import ellipkinc

from pdm_design.api import evaluate
from pdm_design.scenes.manipulators.model import (
    Body,
    ManipulatorsDesign,
    ManipulatorsInitial,
    ManipulatorsScene,
    Palm,
)
from pdm_design.scenes.manipulators.sim import EVENT_KINDS, FAILURE_KINDS, simulate_manipulators
from pdm_design.spec.loader import load_spec

ROOT = Path(__file__).resolve().parents[1]
BEFORE_COMMIT = "a6ce8ef"  # the simulator that ended every run at its first lift-off
G, L, Q = 9.81, 2.0, 10.0
ALPHA = 0.2
X0, Y0, VX0 = -1.25, 3.05, 3.0  # the paper's feed (problems/paper_manipulators.toml)
W_BODY, H_BODY, W_PALM, T_PALM = 0.4, 0.2, 1.6, 0.05
HALF = 0.5 * (W_BODY + W_PALM)  # half width of a palm's contact box
TIGHT = dict(method="DOP853", rtol=1e-13, atol=1e-14, dense_output=True)


def make(*, alpha=ALPHA, beta=1.0, mu=2.0, front_stop=math.pi / 2, position=(X0, Y0),
         velocity=(VX0, 0.0), height=H_BODY):
    scene = ManipulatorsScene(
        body=Body(mass=1.0, width=W_BODY, height=height),
        palm=Palm(width=W_PALM, thickness=T_PALM, friction=mu, restitution=0.0,
                  front_stop=front_stop),
        initial=ManipulatorsInitial(position=position, velocity=velocity), gravity=G)
    return scene, ManipulatorsDesign(alpha=alpha, beta=beta, link_length=L, mass_ratio=Q)


def offset(k, dx, dy):
    return SimpleNamespace(manipulator=k, dx=dx, dy=dy)


def landing_speed(vx, vy, alpha=ALPHA):
    """Eq. 21: u = m/(m+M) V.t(-alpha), t(-alpha) = (cos a, sin a)."""
    return Q / (1 + Q) * (vx * math.cos(alpha) + vy * math.sin(alpha))


def paper_lift_off():
    """The paper's feed onto palm 1 (beta 1, friction 2: nothing slips): the first landing,
    then the stuck carry's lift-off in closed form. Returns (t*, th*, v*, s): time, angle and
    speed of the lift-off (v*^2 = g l cos th*) and the object's offset on the palm."""
    drop = Y0 - L * math.cos(ALPHA)
    t1 = math.sqrt(2 * drop / G)
    vy = -G * t1
    u = landing_speed(VX0, vy)
    # v^2 = u^2 + 2 g l (cos a - cos th) = g l cos th
    theta = math.acos((u * u + 2 * G * L * math.cos(ALPHA)) / (3 * G * L))
    # carry time over the top: psi = pi - th, (psi/2)'^2 = g (C+1)/(2l) (1 - k^2 sin^2(psi/2))
    c = math.cos(ALPHA) + u * u / (2 * G * L)
    k2, rate = 2 / (c + 1), math.sqrt(G * (c + 1) / (2 * L))
    carry = (ellipkinc((math.pi + ALPHA) / 2, k2) - ellipkinc((math.pi - theta) / 2, k2)) / rate
    s = X0 + VX0 * t1 + L * math.sin(ALPHA)
    return t1 + carry, theta, math.sqrt(G * L * math.cos(theta)), s


def free_palm(theta0, w0, t_end, stop=None):
    """The empty palm l th'' = g sin th from (th0, th0') by solve_ivp, optionally to `stop`."""
    events = None
    if stop is not None:
        def events(t, y):
            return y[0] - stop
        events.terminal, events.direction = True, math.copysign(1.0, stop - theta0)
    return solve_ivp(lambda t, y: [y[1], G / L * math.sin(y[0])], (0.0, t_end),
                     [theta0, w0], events=events, **TIGHT)


def ballistic(x, y, vx, vy, tau):
    return x + vx * tau, y + vy * tau - 0.5 * G * tau * tau


def descending_root(y0, vy, level):
    """tau > 0 where y0 + vy tau - g tau^2 / 2 falls through `level`."""
    return (vy + math.sqrt(vy * vy + 2 * G * (y0 - level))) / G


def events_of(result, kind):
    return [e for e in result.events if e.kind == kind]


# ---------------------------------------------------------------- where the object goes

def test_lift_off_after_the_top_flies_onto_the_next_palm():
    t_star, theta, v, s = paper_lift_off()
    scene, design = make()
    result = simulate_manipulators(scene, design, stages=6)
    (lift, *_) = events_of(result, "lift_off")
    assert lift.stage == 1 and not lift.failure
    assert lift.before["theta"] == pytest.approx(theta, abs=1e-11)
    assert lift.time == pytest.approx(t_star, abs=1e-11)
    # the object leaves with the palm's velocity v* t(th*) from its place on the palm
    x, y = L * math.sin(theta) + s, L * math.cos(theta)
    vx, vy = v * math.cos(theta), -v * math.sin(theta)
    # palm 2 rests at -alpha: pivot at (pitch_x, -pitch_y), pitch = l (sin a + sin b, cos a - cos b)
    px2, py2 = L * (math.sin(ALPHA) + math.sin(1.0)), -L * (math.cos(ALPHA) - math.cos(1.0))
    top2, cx2 = py2 + L * math.cos(ALPHA), px2 - L * math.sin(ALPHA)
    tau = descending_root(y, vy, top2)
    x_land, _ = ballistic(x, y, vx, vy, tau)
    assert abs(x_land - cx2) < HALF
    # palm 1 swings on alone to its front stop (pi/2), independently integrated; it is not met
    palm = free_palm(theta, v / L, 5.0, stop=math.pi / 2)
    t_stop = palm.t_events[0][0]
    assert t_stop > tau  # the object is on palm 2 before palm 1 parks at its front stop
    for t in np.linspace(0.0, tau, 2001):
        th = palm.sol(t)[0]
        ox, oy = ballistic(x, y, vx, vy, t)
        assert not (abs(ox - L * math.sin(th)) < HALF
                    and L * math.cos(th) - T_PALM - H_BODY < oy < L * math.cos(th))
    landing = next(e for e in result.events if e.time > lift.time and e.kind == "landing")
    assert landing.after["palm"] == 2 and landing.stage == 2
    assert landing.time == pytest.approx(t_star + tau, abs=1e-10)
    assert landing.before["x"] == pytest.approx(x_land, abs=1e-10)
    assert landing.after["offset"] == pytest.approx(x_land - cx2, abs=1e-10)
    (stop,) = [e for e in events_of(result, "front_stop") if e.stage == 1]
    assert stop.time == pytest.approx(t_star + t_stop, abs=1e-9)
    assert result.stages[1]["landing_time"] == landing.time


def moving_palm_scene(ratio, alpha=0.5, beta=0.9, drop=0.2):
    """The object lands on palm 1's centre so fast that the palm's push vanishes at once:
    u^2 = ratio g l cos(alpha) (eq. 21), with ratio a little above 1."""
    vy = -math.sqrt(2 * G * drop)
    u = math.sqrt(ratio * G * L * math.cos(alpha))
    vx = (u * (1 + Q) / Q - vy * math.sin(alpha)) / math.cos(alpha)
    t1 = math.sqrt(2 * drop / G)
    x_land = -L * math.sin(alpha)
    scene = ManipulatorsScene(
        body=Body(mass=1.0, width=0.2, height=0.05),
        palm=Palm(width=1.0, thickness=0.05, friction=5.0, restitution=0.0),
        initial=ManipulatorsInitial(position=(x_land - vx * t1, L * math.cos(alpha) + drop),
                                    velocity=(vx, 0.0)), gravity=G)
    design = ManipulatorsDesign(alpha=alpha, beta=beta, link_length=L, mass_ratio=Q)
    return scene, design, t1, u


@pytest.mark.parametrize("ratio", [1.01, 1.05])
def test_lift_off_at_the_landing_comes_back_down_on_the_moving_palm(ratio):
    alpha = 0.5
    scene, design, t1, u = moving_palm_scene(ratio, alpha=alpha)
    result = simulate_manipulators(scene, design, stages=3)
    # The landing sticks with u along t(-alpha); u^2 > g l cos(alpha): lift-off at once. Before
    # the top lambda = v^2/l - g cos th falls (cos th grows) and turns negative at
    # cos th = (u^2 + 2 g l cos a) / (3 g l): the object comes down again on its own palm.
    assert u * u > G * L * math.cos(alpha)
    assert (u * u + 2 * G * L * math.cos(alpha)) / (3 * G * L) < 1.0
    lift = events_of(result, "lift_off")[0]
    assert lift.time == pytest.approx(t1, abs=1e-12)
    assert lift.before["theta"] == -alpha
    # independently: the empty palm from (-alpha, u/l) by solve_ivp; the object on its ballistic
    # path from the palm's centre with velocity u t(-alpha); gap = object height - palm top
    x0, y0 = -L * math.sin(alpha), L * math.cos(alpha)
    vx, vy = u * math.cos(alpha), u * math.sin(alpha)
    palm = free_palm(-alpha, u / L, 1.0)

    def gap(t):
        return ballistic(x0, y0, vx, vy, t)[1] - L * math.cos(palm.sol(t)[0])

    grid = np.linspace(1e-3, 1.0, 4000)
    values = [gap(t) for t in grid]
    i = next(i for i in range(len(grid) - 1) if values[i] > 0.0 >= values[i + 1])
    t_c = brentq(gap, grid[i], grid[i + 1], xtol=1e-15)
    th_c, w_c = palm.sol(t_c)
    x_c, _ = ballistic(x0, y0, vx, vy, t_c)
    assert abs(x_c - L * math.sin(th_c)) < 0.5 * (0.2 + 1.0)  # over the palm's top
    landing = next(e for e in result.events if e.time > lift.time)
    assert landing.kind == "landing" and landing.after["palm"] == 1
    assert landing.time == pytest.approx(t1 + t_c, abs=1e-10)
    assert landing.before["theta"] == pytest.approx(th_c, abs=1e-9)
    assert landing.before["omega"] == pytest.approx(w_c, abs=1e-9)
    assert landing.before["x"] == pytest.approx(x_c, abs=1e-9)
    assert landing.after["offset"] == pytest.approx(x_c - L * math.sin(th_c), abs=1e-9)
    # a plastic sticking impact on the moving palm keeps m V.t + M w (the links take the radial
    # part): u' = (q V.t + w) / (1 + q), V the object's velocity just before, t = t(th_c)
    v_t = vx * math.cos(th_c) - (vy - G * t_c) * math.sin(th_c)
    assert landing.after["omega"] * L == pytest.approx((Q * v_t + L * w_c) / (1 + Q), abs=1e-9)
    # palm 1 did not reach a stop: no palm event for it was kept in the log before the landing
    assert not [e for e in result.events
                if e.kind in ("front_stop", "back_stop") and e.stage == 1 and e.time < lift.time
                + 0.5]


def test_lift_off_that_misses_every_palm_is_a_named_failure():
    # one manipulator, front stop 1.8 rad: the palm swings on below the object, which flies
    # past its far end and falls: `missed`, 3 link lengths below the pivot
    t_star, theta, v, s = paper_lift_off()
    scene, design = make(front_stop=1.8)
    result = simulate_manipulators(scene, design, stages=1)
    failure = result.outcome.failure
    assert failure.kind == "missed" and failure.stage == 1 and failure.kind in FAILURE_KINDS
    x, y = L * math.sin(theta) + s, L * math.cos(theta)
    vx, vy = v * math.cos(theta), -v * math.sin(theta)
    tau = descending_root(y, vy, -3 * L)
    assert failure.time == pytest.approx(t_star + tau, abs=1e-10)
    # independently, the palm never meets the object: swinging (solve_ivp) and then at rest
    palm = free_palm(theta, v / L, 5.0, stop=1.8)
    t_stop = palm.t_events[0][0]
    for t in np.linspace(0.0, tau, 4001):
        th = palm.sol(min(t, t_stop))[0]
        ox, oy = ballistic(x, y, vx, vy, t)
        assert not (abs(ox - L * math.sin(th)) < HALF
                    and L * math.cos(th) - T_PALM - H_BODY < oy < L * math.cos(th))
    (stop,) = events_of(result, "front_stop")
    assert stop.time == pytest.approx(t_star + t_stop, abs=1e-9)
    assert result.outcome.stages_passed == 0


def test_sliding_lift_off_flies_over_the_low_palm_onto_palm_3():
    # eq. 43: palm 2 is 0.4 m low; the object slips on palm 1 and its normal force vanishes
    scene, design = make(beta=0.6, mu=0.8)
    result = simulate_manipulators(scene, design, stages=6, offsets=[offset(2, 0.0, -0.4)],
                                   allow_skips=True)
    lift = events_of(result, "lift_off")[0]
    b = lift.before
    # N = 0 on a sliding carry: the free palm's l th'' = g sin th gives N = m cos th (g cos th -
    # l th'^2): lift-off where l th'^2 = g cos th, as on the stuck carry
    assert L * b["omega"] ** 2 == pytest.approx(G * math.cos(b["theta"]), rel=1e-8)
    # from there the flight is ballistic onto palm 3 at rest (pivot 2 pitch down the row)
    beta = 0.6
    px3, py3 = 2 * L * (math.sin(ALPHA) + math.sin(beta)), -2 * L * (math.cos(ALPHA) -
                                                                      math.cos(beta))
    top3, cx3 = py3 + L * math.cos(ALPHA), px3 - L * math.sin(ALPHA)
    tau = descending_root(b["y"], b["vy"], top3)
    x_land, _ = ballistic(b["x"], b["y"], b["vx"], b["vy"], tau)
    landing = next(e for e in result.events if e.time > lift.time and e.kind == "landing")
    assert landing.after["palm"] == 3
    assert landing.time == pytest.approx(lift.time + tau, abs=1e-10)
    assert landing.after["offset"] == pytest.approx(x_land - cx3, abs=1e-10)
    assert result.outcome.completed  # palm 2 flown over, allowed
    # by default palm 2 flown over ends the run there, named
    failure = simulate_manipulators(scene, design, stages=6,
                                    offsets=[offset(2, 0.0, -0.4)]).outcome.failure
    assert failure.kind == "skipped_palm" and failure.stage == 2
    assert failure.time == pytest.approx(lift.time + tau, abs=1e-10)


def test_a_required_lift_off_margin_is_still_reported_when_the_run_completes(tmp_path):
    # The paper's design fed fast (0.05 m above palm 1, 5.5 m/s): u^2 = 1.16 g l cos(alpha) at
    # the first landing, so the first_lift_off margin is 1 - u^2 / (g l cos a) < 0. The object
    # hops, lands on palm 2 and the run completes; the requirement is still violated.
    drop, vx = 0.05, 5.5
    t1 = math.sqrt(2 * drop / G)
    u = landing_speed(vx, -G * t1)
    x0 = -L * math.sin(ALPHA) - vx * t1
    text = (ROOT / "problems" / "paper_manipulators.toml").read_text()
    text = text.replace("position = [-1.25, 3.05]", f"position = [{x0!r}, "
                        f"{L * math.cos(ALPHA) + drop!r}]")
    text = text.replace("velocity = [3.0, 0.0]", "velocity = [5.5, 0.0]")
    path = tmp_path / "fast_feed.toml"
    path.write_text(text + "\n[requirements]\nlift_off = 0.0\n")
    outcome = evaluate(load_spec(path))
    # margins are (capacity - demand) / max(capacity, demand), at the landing and at beta
    held_a, held_b = G * L * math.cos(ALPHA), G * L * math.cos(0.6)
    v_beta2 = u * u + 2 * G * L * (math.cos(ALPHA) - math.cos(0.6))
    expected = min((held_a - u * u) / u ** 2, (held_b - v_beta2) / v_beta2)
    margin = outcome.analysis.margins["first_lift_off"]
    assert margin == pytest.approx(expected, rel=1e-9)
    assert u * u > held_a and margin < -0.1
    assert any("first_lift_off" in v for v in outcome.violations)
    assert outcome.verification["passed"] and outcome.verification["outcome"]["completed"], \
        outcome.verification
    assert "lifted off palm 1" in outcome.verification["summary"]
    assert outcome.exit_code == 1  # the requirement is the spec's: not met


# ---------------------------------------------------------------- before and after

CASE_RUNNER = """
import inspect, json, sys
from types import SimpleNamespace
try:  # this code's layout, or the one of the commit before the flight was modelled
    from pdm_design.scenes.manipulators.model import (Body, ManipulatorsDesign,
                                                      ManipulatorsInitial, ManipulatorsScene, Palm)
    from pdm_design.scenes.manipulators.sim import simulate_manipulators
except ImportError:
    from pdm_design.scenes import (Body, ManipulatorsDesign, ManipulatorsInitial,
                                   ManipulatorsScene, Palm)
    from pdm_design.sim.manipulators import simulate_manipulators
out = []
for c in json.load(sys.stdin):
    scene = ManipulatorsScene(
        body=Body(mass=1.0, width=0.4, height=0.2),
        palm=Palm(width=1.6, thickness=0.05, friction=c["mu"], restitution=c["eps"],
                  front_stop=1.5707963),
        initial=ManipulatorsInitial(position=(-1.25, 3.05), velocity=(3.0, 0.0)), gravity=9.81)
    design = ManipulatorsDesign(alpha=0.2, beta=0.6, link_length=2.0, mass_ratio=10.0)
    offsets = [SimpleNamespace(manipulator=k + 1, dx=dx, dy=dy)
               for k, (dx, dy) in enumerate(c["offsets"])]
    # the lift-off's comparison: palms flown over allowed (the code before had no such failure)
    skips = ({"allow_skips": True} if "allow_skips" in
             inspect.signature(simulate_manipulators).parameters else {})
    r = simulate_manipulators(scene, design, stages=len(c["offsets"]), offsets=offsets, **skips)
    out.append({"completed": r.outcome.completed, "passed": r.outcome.stages_passed,
                "events": [e.to_json() for e in r.events], "stages": r.stages})
json.dump(out, sys.stdout)
"""


def offset_builds(n, seed=1):
    """The paper's three runs (exact, eq. 42, eq. 43), the paper's design with restitution and
    without friction, and n random builds of 6 manipulators (dx in +-0.15 m, dy in +-0.3 m)."""
    zero = [[0.0, 0.0]] * 6
    cases = [{"offsets": zero, "mu": 0.8, "eps": 0.0},
             {"offsets": [[0.0, 0.0], [0.1, -0.2]] + zero[2:], "mu": 0.8, "eps": 0.0},
             {"offsets": [[0.0, 0.0], [0.0, -0.4]] + zero[2:], "mu": 0.8, "eps": 0.0},
             {"offsets": zero, "mu": 0.8, "eps": 0.3},
             {"offsets": zero, "mu": 0.0, "eps": 0.0}]
    rng = np.random.default_rng(seed)
    for _ in range(n):
        draws = rng.uniform(-1.0, 1.0, size=(6, 2)) * [0.15, 0.3]
        cases.append({"offsets": draws.tolist(), "mu": 0.8, "eps": 0.0})
    return cases


def run_cases(cases, source: Path):
    env = dict(os.environ, PYTHONPATH=str(source))
    done = subprocess.run([sys.executable, "-c", CASE_RUNNER], input=json.dumps(cases),
                          capture_output=True, text=True, env=env, check=True, cwd=source)
    assert f"{source}" in subprocess.run(
        [sys.executable, "-c", "import pdm_design; print(pdm_design.__file__)"],
        capture_output=True, text=True, env=env, check=True, cwd=source).stdout
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def before_and_after(tmp_path_factory):
    """The same builds simulated by the code before this change and by this code."""
    if shutil.which("git") is None or subprocess.run(
            ["git", "-C", str(ROOT), "cat-file", "-e", BEFORE_COMMIT],
            capture_output=True).returncode != 0:
        pytest.skip(f"needs the repository's history (commit {BEFORE_COMMIT})")
    before = tmp_path_factory.mktemp("before")
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", BEFORE_COMMIT, "pdm_design"],
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(before)], input=archive, check=True)
    cases = offset_builds(150)
    return cases, run_cases(cases, before), run_cases(cases, ROOT)


def test_runs_that_never_lift_off_are_unchanged(before_and_after):
    cases, old, new = before_and_after
    never = [i for i, run in enumerate(old) if not any(e["kind"] == "lift_off"
                                                       for e in run["events"])]
    assert {0, 1, 3, 4} <= set(never) and len(never) >= 50  # the paper's runs among them
    for i in never:  # every number (_same; the events' words are left out: their wording is
        # not the physics, and it has been improved since)
        if _tipped(old[i]) and cases[i]["eps"] == 0.0:
            # a tip onset no longer ends the run: the object rocks (sim/rocking.py) - the run is
            # the same up to it, where a `rock` event starts (or a tip the model does not follow)
            events_old = _numbers(old[i])["events"][:-1]
            events_new = _numbers(new[i])["events"]
            assert _same(events_new[:len(events_old)], events_old), i
            follow = events_new[len(events_old)]
            assert follow["kind"] in ("rock", "tip", "stepped"), i
            assert _same(follow["time"], old[i]["events"][-1]["time"]), i
            continue
        if _pushed(old[i], new[i]):
            # the carried object meeting the next palm's rear end no longer ends the run: it
            # pushes that palm off its back stop (sim/pushing.py), or any other palm's face met
            # is followed by time stepping (sim/stepped.py) - the same run up to it, where a
            # `push` or `stepped` event starts at the time the old run was blocked
            events_old = _numbers(old[i])["events"][:-1]
            events_new = _numbers(new[i])["events"]
            assert _same(events_new[:len(events_old)], events_old), i
            push = events_new[len(events_old)]
            assert push["kind"] in ("push", "stepped"), i
            assert _same(push["time"], old[i]["events"][-1]["time"]), i
            continue
        assert _same(_numbers(new[i]), _numbers(_failing_stage(old[i]))), i


def _pushed(old: dict, new: dict) -> bool:
    """The old run ended `blocked` where the new one logs a push or time stepping."""
    return (bool(old["events"]) and old["events"][-1]["kind"] == "blocked"
            and any(e["kind"] in ("push", "stepped") for e in new["events"]))


def _tipped(run: dict) -> bool:
    return bool(run["events"]) and run["events"][-1]["kind"] == "tip"


def _failing_stage(run: dict) -> dict:
    """A failure in the feed's flight, at stage 0 before, is now at the stage that fails (1:
    stages passed + 1, docs/tolerances.md); every other number is as it was."""
    def moved(e):
        return {**e, "stage": 1} if e["stage"] == 0 else e

    return {**run, "events": [moved(e) if e["failure"] else e for e in run["events"]]}


def _same(a, b) -> bool:
    """The same structure, the same words, every float equal to 1e-10 (relative): the
    integrated phases now run on sim/rk.py, scipy's solve_ivp steps in plain floats, whose event
    times and states differ from scipy's by 2e-11 at most here, 50 times below the rtol (1e-9) the
    integrator is asked for."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, float) and isinstance(b, float):
        return a == b or math.isclose(a, b, rel_tol=1e-10, abs_tol=1e-13)
    return a == b


def _numbers(run: dict) -> dict:
    return {**run, "events": [{k: v for k, v in e.items() if k != "detail"}
                              for e in run["events"]]}


def test_builds_that_lifted_off_now_complete_or_fail_by_name(before_and_after):
    cases, old, new = before_and_after
    lifted = [i for i, run in enumerate(old) if run["events"][-1]["kind"] == "lift_off"]
    assert 2 in lifted and len(lifted) >= 30
    completed, failed = [], {}
    for i in lifted:
        was, now = old[i]["events"], new[i]["events"]
        # everything up to the lift-off is the same run; the lift-off is now an event
        assert _same(now[:len(was) - 1], was[:-1])
        lift = now[len(was) - 1]
        assert lift["kind"] == "lift_off" and not lift["failure"]
        assert _same(lift["time"], was[-1]["time"]) and lift["stage"] == was[-1]["stage"]
        assert _same(lift["before"]["theta"], was[-1]["before"]["theta"])
        assert {e["kind"] for e in now} <= set(EVENT_KINDS) | set(FAILURE_KINDS)
        if new[i]["completed"]:
            completed.append(i)
            assert new[i]["passed"] == 6 and not any(e["failure"] for e in now)
        else:
            end = now[-1]
            assert end["failure"] and end["kind"] in FAILURE_KINDS and end["detail"]
            assert end["kind"] != "lift_off"
            failed[end["kind"]] = failed.get(end["kind"], 0) + 1
    assert new[2]["completed"]  # eq. 43: over the low palm 2 onto palm 3, then to the end
    assert completed and failed, (completed, failed)


def random_builds(n, seed):
    """Random designs, sizes, feeds and pivot offsets around the paper's (6 manipulators)."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        alpha = rng.uniform(0.0, 0.8)
        beta = min(alpha + rng.uniform(0.05, 1.2), 1.5)
        drop, vx = rng.uniform(0.01, 1.5), rng.uniform(1.0, 8.0)
        fall = math.sqrt(2 * drop / G)
        scene = ManipulatorsScene(
            body=Body(mass=1.0, width=rng.uniform(0.05, 0.6), height=rng.uniform(0.02, 0.4)),
            palm=Palm(width=rng.uniform(0.5, 3.0), thickness=0.05, friction=rng.uniform(0, 3),
                      restitution=0.0, front_stop=rng.uniform(beta + 0.01, 3.0)),
            initial=ManipulatorsInitial(
                position=(-L * math.sin(alpha) - vx * fall + rng.uniform(-0.3, 0.3),
                          L * math.cos(alpha) + drop), velocity=(vx, 0.0)), gravity=G)
        design = ManipulatorsDesign(alpha=alpha, beta=beta, link_length=L,
                                    mass_ratio=10 ** rng.uniform(-1, 2))
        draws = rng.uniform(-1.0, 1.0, size=(6, 2)) * [0.2, 0.3]
        yield scene, design, [offset(k + 1, dx, dy) for k, (dx, dy) in enumerate(draws)]


def test_after_the_top_the_object_never_comes_back_onto_its_rising_palm():
    """Relative to its empty palm the object accelerates at lambda r(th), lambda = v^2/l -
    g cos th, which only grows after the top: from a lift-off at th* > 0 (gap = gap' = 0) the
    height above the palm is convex in time until the palm is horizontal. So the next thing the
    object meets is never its own palm before pi/2 - in particular not at once, which rounding
    of a gap growing like t^3 would suggest (it did, thousands of times in a row, before the
    separation was taken from this argument: in builds 486, 1333, 1393 and 1479 of this
    sequence, which are run here with the first 200)."""
    seen = 0
    for i, (scene, design, offsets) in enumerate(random_builds(1480, seed=1)):
        if i >= 200 and i not in (486, 1333, 1393, 1479):
            continue
        result = simulate_manipulators(scene, design, stages=6, offsets=offsets)
        assert result.outcome.completed or result.outcome.failure.kind != "too_many_events"
        events = [e for e in result.events if e.kind not in ("front_stop", "back_stop")]
        for lift, after in zip(events, events[1:]):
            if lift.kind != "lift_off" or lift.before["theta"] <= 0.0:
                continue
            seen += 1
            assert after.time > lift.time
            if after.kind == "landing" and after.after["palm"] == lift.stage:
                assert after.before.get("theta", math.pi) >= math.pi / 2
    assert seen >= 50
