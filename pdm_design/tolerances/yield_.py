"""The Monte Carlo yield of a design under its spec's tolerances.

Builds are drawn (tolerances.draw, reproducible one by one), run through the scene's
vectorised closed-form map (run_builds) in chunks, and the event simulator then runs
  * every build that left the closed-form regime (its verdict replaces the map's), and
  * `confirm` builds picked at random among the others (agreement reported: same number of
    stages passed and the same failure).
The yield is the fraction of builds that pass every one of the K stages, with a 95 % Wilson
score interval; the survival curve is the fraction still going after each stage (each with
its Wilson interval), and the mean number of stages before failure is the mean of the
stages passed over all builds, a build that passes all counting K (the area under the
survival curve). The sensitivity is the Sobol' indices of the builds' smallest margin
(tolerances.sensitivity), the same closed-form map as the model.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from ..plugin import of
from ..tolerance_model import Tolerances
from .draw import draw
from .outcome import BuildOutcome

Z95 = 1.959963984540054  # two-sided 95 % normal quantile
CHUNK_ENTRIES = 2_000_000  # builds x stages drawn and mapped at once (memory: ~16 MB an array)
PARALLEL_ENTRIES = 1_000_000  # builds x stages from which the map runs on the local workers
SCALES = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0)  # tolerance scales of the yield curve
SCALE_BUILDS = 500  # builds per point of that curve, at most
SHOWN_COMMANDS = 100  # failing builds listed with their simulate command, at most
# The Sobol' sensitivity: base sample of SALib's Saltelli scheme (a power of 2; the map runs
# base x (quantities + 2) builds), shrunk so that the sample holds at most SOBOL_ENTRIES numbers;
# the Sobol' sequence has at most 21201 dimensions, twice the variables.
SOBOL_SAMPLES = 1024
SOBOL_ENTRIES = 8_000_000
SOBOL_MIN_SAMPLES = 64
SOBOL_MAX_VARIABLES = 10_600


def wilson(passed, total, z: float = Z95):
    """Wilson score interval (low, high) of a binomial proportion; arrays allowed."""
    passed, total = np.asarray(passed, float), np.asarray(total, float)
    p = passed / total
    denom = 1.0 + z * z / total
    centre = (p + z * z / (2.0 * total)) / denom
    half = z * np.sqrt(p * (1.0 - p) / total + z * z / (4.0 * total * total)) / denom
    # (at p = 0 and p = 1 an end is exactly 0 or 1, which rounding may miss)
    low = np.where(passed == 0.0, 0.0, np.clip(centre - half, 0.0, 1.0))
    high = np.where(passed == total, 1.0, np.clip(centre + half, 0.0, 1.0))
    return low, high


@dataclass(frozen=True)
class YieldResult:
    """Plain data of one yield run (JSON by to_json; report and sheet read the fields)."""

    kind: str
    builds: int
    stages: int
    seed: int
    estimate: float
    ci_low: float
    ci_high: float
    survival: tuple[float, ...]
    survival_low: tuple[float, ...]
    survival_high: tuple[float, ...]
    mean_stages_before_failure: float
    failures: dict[str, int]
    failing: tuple[dict, ...]  # {index, stages_passed, failure, command}: the first ones
    confirmed: dict
    tolerances: tuple[dict, ...]
    sensitivity: tuple[dict, ...] = ()
    sensitivity_note: str = ""
    scale_curve: tuple[dict, ...] = ()
    source: str = ""
    # what the run was made from (schema, spec, spec_sha256, name, scene, design: the yield
    # command's, commands.yield_.yield_identity), first in the JSON document
    identity: dict = field(default_factory=dict)
    extras: dict = field(default_factory=dict)  # the scene's own entries (Scene.yield_extras)
    # the event simulator's verdicts, build index -> (stages passed, failure): not in the JSON
    verdicts: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return {
            **self.identity,
            "yield": {"estimate": self.estimate, "ci_low": self.ci_low, "ci_high": self.ci_high,
                      "builds": self.builds, "stages": self.stages, "seed": self.seed},
            "survival": list(self.survival),
            "survival_band": {"low": list(self.survival_low), "high": list(self.survival_high)},
            "mean_stages_before_failure": self.mean_stages_before_failure,
            "failures": dict(self.failures),
            "failing_builds": [dict(f) for f in self.failing],
            "sensitivity": [dict(s) for s in self.sensitivity],
            "sensitivity_note": self.sensitivity_note,
            "confirmed": dict(self.confirmed),
            "tolerances": [dict(t) for t in self.tolerances],
            "yield_against_scale": [dict(s) for s in self.scale_curve],
            **self.extras,
        }


def build_command(source: str, seed: int, index: int, stages: int) -> str:
    """The command that simulates build `index` of a yield run."""
    return f"pdm-design simulate {source} --build {seed}:{index} --stages {stages}"


def one_build(tolerances, seed: int, index: int, stages: int, *, scene) -> dict:
    """Deviations of build `index` of `scene` alone (1-row arrays), as the yield run drew
    them."""
    return draw(tolerances, 1, stages, seed, scene=scene, start=index)


def simulate_one(scene, design, tolerances, seed, index, stages, *, accuracy="default",
                 record_trajectory=False, allow_skips=False):
    """The event simulator on build `index` of a yield run with `seed` and `stages`
    (allow_skips: the spec's [verification] allow_skips)."""
    from ..plugin import of

    deviations = one_build(tolerances, seed, index, stages, scene=scene)
    return of(scene).simulate_build(scene, design, deviations, stages, accuracy=accuracy,
                                    record_trajectory=record_trajectory,
                                    allow_skips=allow_skips)


def map_builds(scene, design, tolerances, builds: int, stages: int, seed: int,
               workers: int = 1) -> BuildOutcome:
    """The closed-form outcome of builds 0 .. builds - 1, drawn and mapped chunk by chunk: on
    `workers` local processes where the run has PARALLEL_ENTRIES builds x stages or more (each
    build drawn alone: the same outcome whatever the chunks, tolerances.parallel)."""
    from .parallel import map_chunks

    chunk = max(1, CHUNK_ENTRIES // stages)
    if workers > 1 and builds * stages >= PARALLEL_ENTRIES:  # a few chunks a worker
        chunk = min(chunk, max(1, -(-builds // (2 * workers))))
    else:
        workers = 1
    tasks = [(scene, design, tolerances, start, min(chunk, builds - start), stages, seed)
             for start in range(0, builds, chunk)]
    parts = map_chunks(_mapped_chunk, tasks, workers)
    return BuildOutcome(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                          ("stages_passed", "failure", "min_margin", "closed_form")))


def drawn(scene, tolerances, indices, stages: int, seed: int) -> dict[str, np.ndarray]:
    """The deviations of the builds `indices` (non-empty) of a yield run, each drawn alone."""
    parts = [draw(tolerances, 1, stages, seed, scene=scene, start=int(i)) for i in indices]
    return {q: np.concatenate([part[q] for part in parts]) for q in parts[0]}


def _mapped_chunk(task) -> BuildOutcome:
    """The closed-form outcome of `count` builds from `start` (map_builds' task)."""
    from . import run_builds

    scene, design, tolerances, start, count, stages, seed = task
    deviations = draw(tolerances, count, stages, seed, scene=scene, start=start)
    return run_builds(scene, design, deviations, stages)


def yield_of(scene, design, tolerances: Tolerances, *, builds: int, stages: int, seed: int = 0,
             confirm: int = 20, accuracy="default", source: str = "SPEC",
             scales=SCALES, sensitivity_samples: int = SOBOL_SAMPLES,
             progress=None, allow_skips: bool = False, workers: int | None = None,
             scheduler: str | None = None, mapped: BuildOutcome | None = None,
             meanwhile=None, known: dict | None = None) -> YieldResult:
    """Yield of `design` built with `tolerances` (every one with a value), K = `stages`.
    scales: the tolerance scales of the yield curve (() for none); sensitivity_samples: the
    Sobol' base sample (0: no sensitivity); allow_skips: the spec's [verification]
    allow_skips. A build passes iff its run completes (failure "").
    workers, scheduler: where the event simulator runs the builds (tolerances.parallel;
    default: the tolerances' workers, else one process per core); the result is the same.
    mapped: the closed-form outcome of these builds (map_builds of the same arguments) when
    the caller has it already. meanwhile: the caller's own work (a callable), done while the
    workers simulate (in this process: it must not start worker processes of its own).
    known: the simulator's verdicts of builds of the same run (a previous result's
    `verdicts`), not simulated again."""
    missing = [t.quantity for t in tolerances if t.value is None]
    if missing or not len(tolerances):
        raise ValueError("a yield needs tolerances with values" + (
            f"; {', '.join(missing)} are still to be allocated" if missing else ""))
    from .parallel import local_workers

    if workers is None:
        workers = getattr(tolerances, "workers", None)
    outcome = mapped if mapped is not None else map_builds(
        scene, design, tolerances, builds, stages, seed,
        workers=local_workers(workers) if scheduler is None else 1)
    passed = outcome.stages_passed.copy()
    failure = outcome.failure.copy()
    sample, open_builds = _to_confirm(outcome, seed, confirm)
    curve = _scale_maps(scene, design, tolerances, builds, stages, seed, scales)
    # every build the event simulator runs, the headline's and the curve's, in one batch
    known = known or {}
    tasks = [(1.0, int(i)) for i in (*sample, *open_builds) if int(i) not in known]
    tasks += [(scale, int(i)) for scale, o in curve for i in np.flatnonzero(~o.closed_form)]
    from .parallel import BuildRun, start_builds

    run = BuildRun(scene, design, {1.0: tolerances} | {
        scale: tolerances.scaled(scale) for scale, _ in curve}, seed, stages, accuracy,
        allow_skips)
    started = start_builds(run, tasks, workers=workers, scheduler=scheduler, progress=progress)
    try:  # the sensitivity, the scene's extras and the caller's work while the workers simulate
        if meanwhile is not None:
            meanwhile()
        sensitivity, note = _sensitivity(scene, design, tolerances, stages, seed,
                                         sensitivity_samples)
        extras = of(scene).yield_extras(scene, design, tolerances, stages)
    except BaseException:
        started.close()
        raise
    got = dict(zip(tasks, started.answers())) | {(1.0, i): v for i, v in known.items()}
    confirmed = _confirm(got, sample, open_builds, passed, failure)
    whole = failure == ""
    low, high = wilson(whole.sum(), builds)
    alive = np.array([(passed >= j).sum() for j in range(1, stages + 1)])
    s_low, s_high = wilson(alive, builds)
    failing = np.flatnonzero(~whole)
    shown = tuple({"index": int(i), "stages_passed": int(passed[i]), "failure": failure[i],
                   "command": build_command(source, seed, int(i), stages)}
                  for i in failing[:SHOWN_COMMANDS])
    return YieldResult(
        kind=scene.kind, builds=builds, stages=stages, seed=seed,
        estimate=float(whole.mean()), ci_low=float(low), ci_high=float(high),
        survival=tuple(map(float, alive / builds)), survival_low=tuple(map(float, s_low)),
        survival_high=tuple(map(float, s_high)),
        mean_stages_before_failure=float(passed.mean()),
        failures=dict(Counter(failure[failing]).most_common()), failing=shown,
        confirmed=confirmed, tolerances=tuple(t.to_json(scene.kind) for t in tolerances),
        sensitivity=tuple(sensitivity), sensitivity_note=note,
        scale_curve=tuple(_scale_curve(curve, got, builds, scales,
                                       headline=(int(whole.sum()), confirmed))),
        source=source, extras=extras,
        verdicts={int(i): got[(1.0, int(i))] for i in (*sample, *open_builds)})


def _to_confirm(outcome, seed, confirm):
    """(the `confirm` closed-form builds picked at random, sorted; every build outside the
    closed-form regime)."""
    open_builds = np.flatnonzero(~outcome.closed_form)
    closed = np.flatnonzero(outcome.closed_form)
    rng = np.random.default_rng([seed, 1])
    sample = rng.choice(closed, size=min(confirm, len(closed)), replace=False) \
        if len(closed) else closed
    return np.sort(sample), open_builds


def _confirm(got, sample, open_builds, passed, failure) -> dict:
    """The simulator's verdicts (got: (scale, index) -> (stages passed, failure)) on every
    build outside the closed-form regime (they replace the map's) and on the random
    closed-form sample (agreement counted); passed and failure are updated in place."""
    agreed, disagreements = 0, []
    for i in sample:
        i = int(i)
        result = got[(1.0, i)]
        same = result == (int(passed[i]), failure[i])
        agreed += same
        if not same:
            disagreements.append({"index": i, "closed_form": [int(passed[i]), failure[i]],
                                  "simulated": list(result)})
        passed[i], failure[i] = result
    for i in open_builds:
        passed[i], failure[i] = got[(1.0, int(i))]
    return {"simulated": len(sample) + len(open_builds), "agreed": int(agreed),
            "random": len(sample), "left_closed_form": len(open_builds),
            "disagreements": disagreements}


def simulated(scene, design, tolerances, seed, index, stages, accuracy,
              allow_skips=False, deviations=None) -> tuple[int, str]:
    """(stages passed, failure name or "") of one build in the event simulator: "" exactly
    when the run completed. deviations: the build's own (one_build's, drawn already)."""
    from ..sim.core import SimulationRefused

    if deviations is None:
        deviations = one_build(tolerances, seed, index, stages, scene=scene)
    try:
        result = of(scene).simulate_build(scene, design, deviations, stages,
                                          accuracy=accuracy, allow_skips=allow_skips)
    except SimulationRefused:  # a build the simulator cannot hold is no part a workshop makes
        return 0, "invalid_part"
    outcome = result.outcome
    if outcome.completed:
        return outcome.stages_passed, ""
    return (min(outcome.stages_passed, stages - 1),
            outcome.failure.kind if outcome.failure else "incomplete")


def _scale_maps(scene, design, tolerances, builds, stages, seed, scales) -> list:
    """[(scale, the closed-form outcome of the first SCALE_BUILDS builds (at most) with every
    tolerance scaled)] of the yield curve's scales other than 1."""
    count = min(builds, SCALE_BUILDS)
    return [(scale, map_builds(scene, design, tolerances.scaled(scale), count, stages, seed))
            for scale in scales if scale != 1.0]


def _scale_curve(curve, got, builds, scales, *, headline) -> list[dict]:
    """Yield against a common scale of every tolerance, on the first SCALE_BUILDS builds (at
    most): the closed-form map (curve: _scale_maps), and the event simulator for every build
    outside its regime (got: (scale, index) -> its verdict). At scale 1 the point is the
    headline's own (headline: builds that passed, its confirmation), on all its builds."""
    maps = dict(curve)
    out = []
    for scale in scales:
        if scale == 1.0:
            low, high = wilson(headline[0], builds)
            out.append({"scale": scale, "estimate": headline[0] / builds, "ci_low": float(low),
                        "ci_high": float(high), "builds": builds,
                        "simulated": headline[1]["left_closed_form"]})
            continue
        o = maps[scale]
        failure = o.failure.copy()
        for i in np.flatnonzero(~o.closed_form):
            failure[i] = got[(scale, int(i))][1]
        count = len(failure)
        ok = int((failure == "").sum())
        low, high = wilson(ok, count)
        out.append({"scale": scale, "estimate": ok / count, "ci_low": float(low),
                    "ci_high": float(high), "builds": count,
                    "simulated": int((~o.closed_form).sum())})
    return out


def _sensitivity(scene, design, tolerances, stages, seed, samples) -> tuple[list, str]:
    """Sobol' total-order indices of the builds' smallest margin (tolerances.sensitivity), the
    closed-form map as the model; the base sample shrinks to SOBOL_ENTRIES (never below
    SOBOL_MIN_SAMPLES: then not computed, in words)."""
    if not samples:
        return [], "not computed (no Sobol' samples asked)"
    from . import run_builds
    from .sensitivity import sobol_indices

    variables = sum(stages if t.applies_to == "each" else 1 for t in tolerances)
    fits = SOBOL_ENTRIES // (variables * (len(tolerances) + 2))
    if variables > SOBOL_MAX_VARIABLES or fits < SOBOL_MIN_SAMPLES:
        return [], (f"not computed: {variables} varying parts are more than the Sobol' sample "
                    f"holds here (at most {SOBOL_MAX_VARIABLES}, and {SOBOL_ENTRIES} numbers "
                    "drawn); fewer stages allow it")
    base = min(samples, 1 << (fits.bit_length() - 1))

    def run(deviations, k):
        return run_builds(scene, design, deviations, k)

    rows = sobol_indices(run, tolerances, stages=stages, samples=base, seed=seed)
    return rows, ""
