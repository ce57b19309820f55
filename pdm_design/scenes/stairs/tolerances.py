"""Many builds of one stairs design at once: the vectorised map of `run_builds`, and one build in
the event simulator (`simulate_build`).

A build is the design as a workshop makes it: each step's rise and tread off by its own error,
each tread's restitution and friction those of its material, the launcher throwing at its own
speed from its own place. `deviations` gives them, added to the nominal values (SI units), one
array per quantity: shape (N, K) for a quantity that varies per step (column k - 1 is step k's),
(N,) for one shared by the whole build (a lot of boards, the launcher). The staircase is laid
out from the design as the simulator lays it out (`scenes/stairs/sim.stairs_geometry`), and
every step is built on the one before, so errors accumulate along the stairs.

The map follows the simulator's bounce closed form by closed form, all N builds a stage at a
time (docs/physics.md, "Builds"): the impact map on step k with that step's restitution and
friction, the flight to step k + 1 (take-off from the landing L_k, the nose tread_k - L_k ahead,
a fall of rise_{k+1}), and where it ends: back on step k (double_landing), on a nose corner
(nose_hit: a disc against a point, decided where it can touch), beyond tread k + 1 (skipped_step)
or on it, L_{k+1} from its back. Its margins are the analysis' exact clearances of that flight and
landing (gap / tread), so that min_margin < 0 exactly where the build failed. A build leaves the
closed-form regime when it moves backwards, starts below the top landing's level, skips two
steps, or grazes a nose where the distance is not convex; its `closed_form` is then False and the
event simulator is the judge.

Quantities outside their physical range are taken at its end: a restitution drawn above 1 is 1,
below 0 is 0; a friction below 0 is 0. A step whose rise is negative or whose tread is not
positive cannot be built: the build fails `unbuildable_step` when the ball would fly to it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ...sim.core import Event, Outcome
from ...tolerances.outcome import BuildOutcome
from . import physics as phys
from .model import StairsDesign, StairsScene
from .quantities import QUANTITIES as ALL_QUANTITIES
from .sim import (
    build_variation,
    check_stairs_scales,
    corner_hits,
    impact_map,
    simulate_stairs,
    stairs_geometry,
)

QUANTITIES = tuple(ALL_QUANTITIES)
LOT_ONLY = ("launch_speed", "launch_x")
UNBUILDABLE = "unbuildable_step"
# failure codes of the map; names as the event simulator's (sim.stairs.FAILURE_KINDS), plus ours
FAILURES = ("", "double_landing", "skipped_step", "nose_hit", "no_rebound", UNBUILDABLE)
_OK, _DOUBLE, _SKIP, _NOSE, _NO_REBOUND, _UNBUILT = range(6)
_NEGATIVE = np.nextafter(0.0, -1.0)  # the margin of a failure decided at a graze


@dataclass(frozen=True)
class StairsBuilds:
    """A batch of builds run by `march_builds`: the outcome, and the state just after each
    build's last impact (landing offset from the back of its tread, vx, vy, omega; NaN for a
    build that never landed), as the simulator's last stage record holds it. raw_margin: the
    smallest clearance before its sign is made to follow the classification (they differ only
    at grazes)."""

    outcome: BuildOutcome
    landing: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    omega: np.ndarray
    raw_margin: np.ndarray


def run_builds(scene: StairsScene, design: StairsDesign, deviations: dict,
               stages: int) -> BuildOutcome:
    """N builds of `design` for `stages` bounces each (see the module docstring)."""
    return march_builds(scene, design, deviations, stages).outcome


class _Values:
    """The builds' actual values, nominal + deviation, per step (k from 1) or per build. A
    per-step array is held step-major (one contiguous row a step), and the values of the steps
    a stage reads are kept until the stage after next."""

    def __init__(self, scene, design, geo, deviations, stages):
        self.n, self.stages = _check_deviations(deviations, stages, scene)
        self.dev = {q: np.ascontiguousarray(d.T) if d.ndim == 2 else d
                    for q, d in deviations.items()}
        self.nominal = {"rise": geo.rise, "tread": geo.tread,
                        "restitution": design.restitution, "friction": scene.friction,
                        "launch_speed": design.launch_speed, "launch_x": 0.0}
        self._kept: dict = {}

    def at(self, name, k=None):
        """Step k's value (k beyond the staircase asked: nominal), or the build's."""
        key = (name, k)
        if key not in self._kept:
            if k is not None and len(self._kept) > 64:
                self._kept = {key: v for key, v in self._kept.items() if key[1] is None
                              or key[1] >= k - 1}
            self._kept[key] = self._value(name, k)
        return self._kept[key]

    def _value(self, name, k):
        nominal = self.nominal[name]
        d = self.dev.get(name)
        if d is None or (k is not None and k > self.stages):
            value = nominal
        else:
            value = nominal + (d[k - 1] if d.ndim == 2 else d)
        if name == "restitution":
            return np.clip(value, 0.0, 1.0)
        return np.maximum(value, 0.0) if name == "friction" else value


def _check_deviations(deviations, stages, scene) -> tuple[int, int]:
    stages = int(stages)
    if stages < 0:
        raise ValueError(f"stages must be >= 0, not {stages}")
    if not deviations:
        raise ValueError("deviations: no quantity given, so the number of builds is unknown")
    n = None
    for name, d in deviations.items():
        if name not in QUANTITIES:
            raise ValueError(f"deviations: unknown quantity {name!r} (stairs: "
                             f"{', '.join(QUANTITIES)})")
        d = np.asarray(d)
        shapes = "(N,)" if name in LOT_ONLY else f"(N,) or (N, {stages})"
        if d.ndim not in (1, 2) or (d.ndim == 2 and (name in LOT_ONLY or d.shape[1] != stages)):
            raise ValueError(f"deviations[{name!r}]: shape {d.shape}, expected {shapes}")
        if n is not None and d.shape[0] != n:
            raise ValueError(f"deviations[{name!r}]: {d.shape[0]} builds, the others {n}")
        n = d.shape[0]
        if not np.all(np.isfinite(d)):
            raise ValueError(f"deviations[{name!r}]: not every value is a finite number")
    if "friction" in deviations and scene.ball.radius == 0.0:
        raise ValueError("deviations: friction varies but the ball has radius 0 (a point ball "
                         "cannot roll)")
    return n, stages


def march_builds(scene: StairsScene, design: StairsDesign, deviations: dict,
                 stages: int) -> StairsBuilds:
    """`run_builds` with the state after each build's last impact."""
    geo = stairs_geometry(scene, design)
    check_stairs_scales(scene, design, geo)
    deviations = {k: np.asarray(v, dtype=float) for k, v in deviations.items()}
    val = _Values(scene, design, geo, deviations, stages)
    run = _Run(scene, geo.tread, val.n)
    g, r, h0 = scene.gravity, scene.ball.radius, scene.initial.drop_height
    if val.stages == 0:
        return run.finish(val)
    # the launch: from its apex h0 - rise above the top landing, whose nose is x_back_1 ahead
    v = np.broadcast_to(val.at("launch_speed"), (val.n,)).astype(float)
    ahead = np.broadcast_to(geo.x_back_1 - val.at("launch_x"), (val.n,)).astype(float)
    height = h0 - geo.rise
    run.unbuilt(val, 1)
    rise1, tread1 = val.at("rise", 1), val.at("tread", 1)
    flight = _fly(ahead, height, v, 0.0, rise1, tread1, val.at("rise", 2), val.at("tread", 2),
                  r, g)
    regular = height >= 0.0  # a launch from below the top landing is not modelled here
    with np.errstate(all="ignore"):
        gaps = phys.launch_clearances(v, g, r, height, ahead, rise1)
    run.stage(flight, np.minimum.reduce(gaps), rise1, tread1, regular, val, 1)
    run.state(flight.landing, v, flight.vy, np.full(val.n, float(scene.initial.spin)))
    for k in range(1, val.stages):
        after = run.impact(val, k)
        run.unbuilt(val, k + 1)
        rise1, tread1 = val.at("rise", k + 1), val.at("tread", k + 1)
        ahead = val.at("tread", k) - run.s
        flight = _fly(ahead, 0.0, after.vx, after.vy, rise1, tread1, val.at("rise", k + 2),
                      val.at("tread", k + 2), r, g)
        with np.errstate(all="ignore"):
            gaps = phys.flight_clearances(after.vx, after.vy, g, r, ahead, rise1)
        flight = flight._replace(code=np.where(after.vy <= 0.0, _NO_REBOUND, flight.code))
        run.stage(flight, np.minimum.reduce(gaps), rise1, tread1, True, val, k + 1)
        run.state(flight.landing, after.vx, flight.vy, after.omega)
        if not run.alive.any():
            break
    return run.finish(val)


class _Flight(NamedTuple):
    code: np.ndarray      # _OK, _DOUBLE, _SKIP or _NOSE
    landing: np.ndarray   # from the back of the next tread, at its level
    vy: np.ndarray        # vertical velocity there (< 0)
    regular: np.ndarray   # inside the closed-form regime


def _fly(ahead, h, vx, up, rise1, tread1, rise2, tread2, r, g) -> _Flight:
    """Where a flight ends: the lowest point starts h above the level of the step it leaves,
    `ahead` behind that step's nose, at (vx, up); the next tread is rise1 lower and tread1 long,
    the one after rise2 and tread2. Corners are tested only where the ball can touch them (the
    lowest point passes their level less than r beyond them: `corner_hits`)."""
    two_g, up2 = 2.0 * g, up * up
    with np.errstate(all="ignore"):
        x_same = vx * (up + np.sqrt(np.maximum(up2 + two_g * h, 0.0))) / g - ahead
        root1 = np.sqrt(up2 + two_g * (h + rise1))
        t1 = (up + root1) / g
        landing = vx * t1 - ahead
        t2 = (up + np.sqrt(up2 + two_g * (h + rise1 + rise2))) / g
        landing2 = vx * t2 - ahead - tread1
    double = x_same <= 0.0
    skip = ~double & (landing > tread1)
    code = np.where(double, _DOUBLE, np.where(skip, _SKIP, _OK)).astype(np.int8)
    regular = (vx > 0.0) & ~(skip & (landing2 > tread2))
    if r > 0.0:
        near0 = ~double & (x_same < r)
        near1 = skip & (landing - tread1 < r)
        hit = _hits(near0, ahead, vx, up, r, g, np.where(skip, t2, t1), h)
        hit |= _hits(near1, ahead + tread1, vx, up, r, g, t2, h + rise1)
        code[hit] = _NOSE
        convex = vx * vx + up2 + two_g * h > g * r * (1.0 + 1e-6)
        regular &= convex | ~(near0 | near1)
    return _Flight(code, landing, -root1, regular)


def _hits(mask, d, vx, up, r, g, t_land, h):
    out = np.zeros(mask.shape, dtype=bool)
    idx = np.flatnonzero(mask)
    if idx.size:
        def at(x):
            return np.broadcast_to(x, mask.shape)[idx]
        out[idx] = corner_hits(at(d), at(vx), at(up), r, g, at(t_land), at(h))
    return out


class _Run:
    """The batch's running state: who is still going, their stages, failures and margins."""

    def __init__(self, scene, tread, n):
        ball = scene.ball
        self.r, self.m, self.J, self.tread = ball.radius, ball.mass, ball.inertia, tread
        self.alive = np.ones(n, dtype=bool)
        self.passed = np.zeros(n, dtype=np.int64)
        self.code = np.zeros(n, dtype=np.int8)
        self.margin = np.ones(n)
        self.raw = np.ones(n)
        self.regular = np.ones(n, dtype=bool)
        self.s = self.vx = self.vy = self.om = None
        self.last = [np.full(n, np.nan) for _ in range(4)]  # landing, vx, vy, omega after

    def unbuilt(self, val, k):
        """Fail the builds still going whose step k cannot be built."""
        rise, tread = val.at("rise", k), val.at("tread", k)
        bad = self.alive & ((rise < 0.0) | (tread <= 0.0))
        if bad.any():
            worst = np.minimum(rise / max(val.nominal["rise"], 1e-300), tread / self.tread)
            worst = np.clip(np.broadcast_to(worst, bad.shape), -1.0, 1.0)
            self.raw = np.where(bad, np.minimum(self.raw, worst), self.raw)
            self._fail(bad, _UNBUILT, worst)

    def _fail(self, mask, code, margin):
        self.code[mask] = code
        self.margin[mask] = np.minimum(np.minimum(self.margin[mask], margin[mask]), _NEGATIVE)
        self.alive &= ~mask

    def stage(self, flight, gap, rise1, tread1, regular, val, k):
        """Judge one flight and its landing on step k; margins are clearances / tread."""
        with np.errstate(all="ignore"):
            land = np.minimum(flight.landing - phys.riser_reach(rise1, self.r),
                              tread1 - flight.landing)
            m = np.nan_to_num(np.minimum(gap, land) / self.tread, nan=-1.0)
        m = np.clip(m, -1.0, 1.0)
        alive = self.alive
        self.regular &= ~alive | (flight.regular & regular)
        self.raw = np.where(alive, np.minimum(self.raw, m), self.raw)
        failed = alive & (flight.code != _OK)
        code = flight.code
        for c in np.unique(code[failed]):
            self._fail(failed & (code == c), c, m)
        ok = self.alive
        self.margin[ok] = np.minimum(self.margin[ok], np.maximum(m[ok], 0.0))
        self.passed += ok

    def state(self, s, vx, vy, om):
        """The state just before the impact on the step reached (for the builds still going)."""
        if self.s is None:
            self.s, self.vx, self.vy, self.om = s, vx, vy, om
            return
        a = self.alive
        self.s, self.vx = np.where(a, s, self.s), np.where(a, vx, self.vx)
        self.vy, self.om = np.where(a, vy, self.vy), np.where(a, om, self.om)

    def impact(self, val, k):
        """The impact on step k with its restitution and friction; recorded as the state after
        the last impact of the builds still going."""
        mu = val.at("friction", k)
        if np.ndim(mu) == 0 and mu == 0.0 or self.r == 0.0:
            mu = 0.0
        after = impact_map(self.vx, self.vy, self.om, val.at("restitution", k), mu, self.r,
                           self.m, self.J)
        a = self.alive
        for i, x in enumerate((self.s, after.vx, after.vy, after.omega)):
            self.last[i] = np.where(a, x, self.last[i])
        return after

    def finish(self, val) -> StairsBuilds:
        if self.s is not None and self.alive.any():
            self.impact(val, int(self.passed.max()))
        outcome = BuildOutcome(self.passed, np.array(FAILURES, dtype=object)[self.code],
                               self.margin, self.regular)
        return StairsBuilds(outcome, *self.last, raw_margin=self.raw)


class _StepError(NamedTuple):
    step: int
    rise: float
    tread: float


def simulate_build(scene: StairsScene, design: StairsDesign, deviations: dict, stages: int,
                   accuracy="default", **options):
    """One build in the event simulator (`sim.simulate_stairs`; options go to
    it): deviations of that build, by quantity, a number (lot) or one per step (K values).
    Values beyond their physical range are taken at its end, as `run_builds` takes them. A build
    with a step that cannot be built runs up to the step before it, and fails there
    `unbuildable_step` if the ball gets that far."""
    batch = {k: np.asarray(v, dtype=float)[None, ...] for k, v in deviations.items()}
    geo = stairs_geometry(scene, design)
    val = _Values(scene, design, geo, batch, stages)
    def one(q, k=None):
        return float(np.ravel(val.at(q, k))[0])

    per_step = {q: [one(q, k) for k in range(1, val.stages + 1)]
                for q in ("rise", "tread", "restitution", "friction")}
    bad = [k for k in range(1, val.stages + 1)
           if per_step["rise"][k - 1] < 0.0 or per_step["tread"][k - 1] <= 0.0]
    built = bad[0] - 1 if bad else val.stages
    errors = [_StepError(k, per_step["rise"][k - 1] - geo.rise,
                         per_step["tread"][k - 1] - geo.tread) for k in range(1, built + 1)]
    variation = build_variation(
        restitution=per_step["restitution"] if "restitution" in batch else None,
        friction=per_step["friction"] if "friction" in batch else None,
        launch_speed=one("launch_speed") if "launch_speed" in batch else None,
        launch_x=one("launch_x"), radius=scene.ball.radius)
    result = simulate_stairs(scene, design, stages=built, accuracy=accuracy, step_errors=errors,
                             variation=variation, **options)
    if not bad or not result.outcome.completed:
        return result
    step = bad[0]
    state = result.events[-1].after if result.events else {}
    state = {**state, "step": step}
    event = Event(result.events[-1].time if result.events else 0.0, UNBUILDABLE, step, state,
                  dict(state), f"step {step} cannot be built: rise "
                  f"{per_step['rise'][step - 1]:.6g} m, tread {per_step['tread'][step - 1]:.6g} m",
                  failure=True)
    outcome = Outcome(completed=False, stages_passed=result.outcome.stages_passed, failure=event)
    return dataclasses.replace(result, outcome=outcome, events=[*result.events, event])
