"""Many builds of one rimless wheel design at once (the yield): each step's slope (a ramp) or
rise and tread (stairs) off by its own error, drawn normal with sigma = t / 3 (or uniform in
+-t), and the start speed by one; every build run on the vectorised step map
(`steps.step_map`) for `stages` steps. As pdm_design/tolerances/stairs.py does for the ball:
the yield is the fraction of builds that make every step, and each failure is named.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import physics as phys
from .analysis import resolve
from .steps import CODES, step_map

QUANTITIES = {"ramp": ("slope", "speed"), "stairs": ("rise", "tread", "speed")}


@dataclass(frozen=True)
class WheelBuilds:
    """passed: steps each build made; failure: each build's failure kind ("" for none)."""

    stages: int
    passed: np.ndarray
    failure: list[str]

    @property
    def yield_(self) -> float:
        return float(np.mean(self.passed >= self.stages))

    def survival(self) -> np.ndarray:
        """survival[s]: the fraction of builds that made at least s steps (s = 0..stages)."""
        counts = np.bincount(np.minimum(self.passed, self.stages), minlength=self.stages + 1)
        return 1.0 - np.concatenate([[0], np.cumsum(counts)[:-1]]) / len(self.passed)


def _draw(rng, t, shape, distribution):
    if distribution == "uniform":
        return rng.uniform(-t, t, shape)
    return rng.normal(0.0, t / 3.0, shape)


def run_builds(scene, design, tolerances: dict[str, float], *, stages: int, builds: int,
               seed: int = 0, distribution: str = "normal") -> WheelBuilds:
    """`builds` builds of the design with every quantity of `tolerances` ({quantity: t}:
    slope (rad) on a ramp, rise and tread (m) on stairs, each step its own; speed (rad/s), the
    start's) drawn independently."""
    unknown = set(tolerances) - set(QUANTITIES[scene.ground])
    if unknown:
        raise ValueError(f"not a quantity of a rimless wheel on a {scene.ground}: "
                         f"{', '.join(sorted(unknown))} (expected "
                         f"{', '.join(QUANTITIES[scene.ground])})")
    wh, geo, problems = resolve(scene, design)
    if problems:
        raise ValueError("; ".join(problems))
    rng = np.random.default_rng(seed)
    shape = (builds, stages)
    speed = scene.initial.speed + _draw(rng, tolerances.get("speed", 0.0), builds, distribution)
    stairs = None
    if scene.ground == "ramp":
        betas = wh.beta + _draw(rng, tolerances.get("slope", 0.0), shape, distribution)
    else:
        rises = geo["rise"] + _draw(rng, tolerances.get("rise", 0.0), shape, distribution)
        ratio = rises / wh.chord
        unbuildable = ~((ratio >= 0.0) & (ratio < 1.0))
        betas = np.arcsin(np.clip(ratio, 0.0, 1.0 - 1e-15))
        # a rise beyond the chord: no spoke reaches the tread; one below 0: the step goes up
        betas = np.where(unbuildable, wh.beta - 4.0 * wh.alpha, betas)
        treads = geo["tread"] + _draw(rng, tolerances.get("tread", 0.0), shape, distribution)
        treads = np.concatenate([np.full((builds, 1), geo["tread"]), treads], axis=1)
        stairs = {"tread": treads, "landing_offset": geo["landing_offset"]}
    run = step_map(wh, speed, betas, ground=wh.ground, stairs=stairs)
    return WheelBuilds(stages, run.passed, [CODES[c] for c in run.failure])


def landing_threshold(scene, design) -> float:
    """The rise error of step 1 beyond which (below it) the first foothold lands past tread 1's
    nose, tread 0 and tread 1 as designed: s_1 = s_0 + sqrt(c^2 - (rise + e)^2) - tread >= tread
    iff rise + e <= sqrt(c^2 - (2 tread - s_0)^2)."""
    wh, geo, _ = resolve(scene, design)
    far = 2.0 * geo["tread"] - geo["landing_offset"]
    return float(np.sqrt(wh.chord**2 - far**2) - geo["rise"]) if far < wh.chord else -np.inf


__all__ = ["QUANTITIES", "WheelBuilds", "landing_threshold", "run_builds", "phys"]


def build_outcome(scene, design, deviations: dict, stages: int):
    """The yield engine's map (Scene.run_builds): builds with `deviations` ({quantity: (builds,
    stages) array for each step's own slope, rise or tread; (builds,) for the start_speed
    lot}, SI) added to the nominal, on the step map. The map gives no margins: min_margin is 0
    for a build that made every step and -1 for one that did not (the sensitivity is of the
    pass/fail outcome); every build stays in the closed forms (the step map is exact between
    impacts, docs/rimless_wheel.md)."""
    from ...tolerances.outcome import BuildOutcome

    wh, geo, problems = resolve(scene, design)
    if problems:
        raise ValueError("; ".join(problems))
    builds = len(next(iter(deviations.values())))
    speed = scene.initial.speed + np.asarray(deviations.get("start_speed", np.zeros(builds)))
    stairs, shape, rises = None, (builds, stages), None

    def per_step(name):  # a lot: one value for every step of a build
        value = np.asarray(deviations.get(name, np.zeros(shape)), dtype=float)
        return np.broadcast_to(value[:, None] if value.ndim == 1 else value, shape)

    if scene.ground == "ramp":
        betas = wh.beta + per_step("slope")
    else:
        rises = geo["rise"] + per_step("rise")
        ratio = rises / wh.chord
        unbuildable = ~((ratio >= 0.0) & (ratio < 1.0))
        betas = np.where(unbuildable, wh.beta - 4.0 * wh.alpha,
                         np.arcsin(np.clip(ratio, 0.0, 1.0 - 1e-15)))
        treads = geo["tread"] + per_step("tread")
        treads = np.concatenate([np.full((builds, 1), geo["tread"]), treads], axis=1)
        stairs = {"tread": treads, "landing_offset": geo["landing_offset"]}
    if "leg_length" in deviations or "mass" in deviations:
        run = _spoke_run(scene, design, wh, deviations, speed, betas,
                         stairs and {**stairs, "rise": rises})
    else:
        run = step_map(wh, speed, betas, ground=wh.ground, stairs=stairs)
    passed = np.minimum(run.passed, stages)
    failure = np.array(["" if p >= stages else CODES[c] for p, c in zip(passed, run.failure)],
                       dtype=object)
    return BuildOutcome(passed, failure, np.where(passed >= stages, 0.0, -1.0),
                        np.ones(builds, dtype=bool))


def spoke_lengths_of(deviations: dict, design, spokes: int):
    """Each spoke's length of every build (builds, spokes): the design's plus leg_length's
    deviation, spoke j taking step j's draw (a tolerance on each part: one a spoke; the
    yield needs stages >= spokes) or the build's one (a lot)."""
    value = np.asarray(deviations["leg_length"], dtype=float)
    value = value[:, None] if value.ndim == 1 else value[:, :spokes]
    return design.leg_length + np.broadcast_to(value, (value.shape[0], spokes))


def _spoke_run(scene, design, wh, deviations, speed, betas, stairs):
    """The step map of builds whose spokes have their own lengths (leg_length) or whose hub its
    own mass (mass): steps.spoke_map."""
    from .steps import spoke_map

    n, builds = wh.n, len(speed)
    lengths = (spoke_lengths_of(deviations, design, n) if "leg_length" in deviations
               else np.full((builds, n), wh.leg))
    w = scene.wheel
    mass = np.maximum(w.mass + np.asarray(deviations.get("mass", np.zeros(builds)), float),
                      1e-300)
    k2 = phys.gyration_squared(mass, w.gyration, w.spoke_mass, n, design.leg_length)
    if stairs is None:
        return spoke_map(wh, speed, lengths, k2, ground=wh.ground, betas=betas)
    return spoke_map(wh, speed, lengths, k2, ground=0.0, stairs=stairs)


def step_errors_of(deviations: dict, stages: int) -> list[dict]:
    """One build's per-step deviations (1-row arrays) as the simulator's step_errors."""
    rows = []
    for k in range(stages):
        row = {"step": k + 1}
        for name in ("slope", "rise", "tread"):
            if name in deviations:
                value = np.asarray(deviations[name])[0]
                row[name] = float(value if value.ndim == 0 else value[k])
        rows.append(row)
    return rows
