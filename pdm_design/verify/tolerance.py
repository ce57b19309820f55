"""Verification of a claimed tolerance box by simulation.

The optimizer claims that every stage's pair of build errors (Scene.box_axes: a pivot's
(dx, dy), a step's (rise, tread)) may be off by up to the box's half-widths, and the device
still works. We do not take its
word: the simulator runs the device at the box's corner patterns and at random samples inside
it, from the spec's initial state, and any run that does not complete refutes the claim.

Corner patterns (each of the four sign corners (+-dx, +-dy)):
- every pivot (step) at the same corner: the whole row shifted or skewed;
- alternating corners on odd and even pivots: the largest relative offsets, 2 x the box;
- only the second pivot at the corner: the paper's experiment.
With an allocated box (`lots`), each pattern with every sign corner of the other quantities;
the link lengths also alternately long and short.

Random builds: `samples` of them on rows up to RANDOM_ROW stages; on longer rows fewer, so that
the simulated random stages stay samples x RANDOM_ROW (at least one build): the event simulator
costs about 0.07 ms a stage, and 16 random builds of a row of 10 000 took 11 s of a 23 s
optimize. Many random builds of a long row are the closed-form stage maps' job (the optimizer's
sampled check streams 256 through every stage: solve/check.py); the simulator judges the
nominal run, every corner pattern and these few.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..plugin import of
from ..progress import progress_bar
from ..sim.core import SimulationRefused
from ..spec.model import Spec

SIGNS = tuple(itertools.product((1.0, -1.0), repeat=2))
RANDOM_ROW = 100


def random_builds(samples: int, stages: int) -> int:
    """How many random builds are simulated for `samples` asked on a row of `stages`."""
    if samples <= 0:
        return 0
    return min(samples, max(1, -(-samples * RANDOM_ROW // max(stages, 1))))


def corner_patterns(stages: int) -> list[tuple[str, list[tuple[float, float]]]]:
    """(name, per-stage sign pairs) of every corner pattern for a row of `stages`."""
    patterns = []
    for sx, sy in SIGNS:
        patterns.append((f"all at ({sx:+.0f}, {sy:+.0f})", [(sx, sy)] * stages))
        patterns.append((f"alternating ({sx:+.0f}, {sy:+.0f})",
                         [(sx, sy) if k % 2 == 0 else (-sx, -sy) for k in range(stages)]))
        if stages >= 2:
            only_second = [(0.0, 0.0)] * stages
            only_second[1] = (sx, sy)
            patterns.append((f"second at ({sx:+.0f}, {sy:+.0f})", only_second))
    return patterns


def verify_tolerance(spec: Spec, design, tolerance: dict, *, samples: int, accuracy=None,
                     seed: int = 0, lots=None) -> dict:
    """Simulate the corner patterns and `samples` uniform random builds inside the box (fewer
    on rows longer than RANDOM_ROW: `random_builds`). lots: an allocated tolerance list
    (formulation/allocation.py); its quantities other than the box's own (a lot: one value a
    build; a part's quantity, BoxAxes.per_part: every part alike) take every sign corner with
    every pattern of the box, and a uniform value in each random build (a part's quantity: one
    per part); the quantities of BoxAxes.alternating also alternately high and low."""
    stages = spec.verification.stages
    half = _half_widths(spec, tolerance)
    rng = np.random.default_rng(seed)
    box = of(spec).box_axes_of(spec)
    per_stage = set(box.quantities)  # the corner patterns' own quantities
    pair = (*half, 0.0)[:2]  # a box of one axis: its errors' second entry 0
    lot = {e["quantity"]: e["value"] for e in (lots or ()) if e["quantity"] not in per_stage}
    builds = [(name + _lot_name(signs_l), [(sx * pair[0], sy * pair[1]) for sx, sy in signs],
               {q: _scaled(sl, lot[q]) for q, (_, sl) in zip(lot, signs_l)})
              for name, signs in corner_patterns(stages)
              for signs_l in itertools.product(*(_lot_signs(q, stages, box) for q in lot))]
    for i in range(random_builds(samples, stages)):
        draws = rng.uniform(-1.0, 1.0, size=(stages, 2)) * np.asarray(pair)
        built = {q: rng.uniform(-t, t, stages).tolist() if q in box.per_part  # part by part
                 else float(rng.uniform(-t, t)) for q, t in lot.items()}
        builds.append((f"random sample {i + 1}", [tuple(map(float, d)) for d in draws], built))

    failures = []
    with progress_bar(len(builds), "verifying the tolerance box") as advance:
        for name, errors, deviations in builds:
            try:
                result = _simulate(spec, design, errors, deviations, accuracy)
            except (SimulationRefused, ValueError) as refusal:  # e.g. a rise error larger
                # than the rise; a lot no scene can hold (a negative friction)
                failures.append({"build": name, "errors": errors, "lots": deviations,
                                 "stages_passed": 0,
                                 "failure": f"the simulator refuses this build: {refusal}"})
                continue
            finally:
                advance()
            if not result.outcome.completed:
                f = result.outcome.failure
                what = f"{f.kind} at stage {f.stage}" if f else "incomplete"
                failures.append({"build": name, "errors": errors, "lots": deviations,
                                 "failure": what,
                                 "stages_passed": result.outcome.stages_passed})
    return {"passed": not failures, "samples": len(builds), "failures": failures,
            "box": dict(zip(_axes(spec), half, strict=True))}


def _lot_signs(quantity: str, stages: int, box) -> list[tuple[str, object]]:
    """(name, sign) of a quantity's corners: +-1 (a lot, or every part alike), and for an
    alternating quantity (BoxAxes.alternating) every other part at the other end
    (+-(1, -1, 1, ...))."""
    signs = [("+1", 1.0), ("-1", -1.0)]
    if quantity in box.alternating:
        alternate = [(-1.0) ** k for k in range(stages)]
        signs += [("alternating +1", alternate), ("alternating -1", [-s for s in alternate])]
    return signs


def _scaled(sign, value):
    return sign * value if isinstance(sign, float) else [s * value for s in sign]


def _lot_name(signs) -> str:
    return "" if not signs else " with " + ", ".join(name for name, _ in signs)


def _simulate(spec: Spec, design, errors, deviations: dict, accuracy):
    """One build: the spec's own path (offsets or step errors), or, with deviations of other
    quantities (an allocated box), the yield's per-part build (Scene.simulate_box_build)."""
    from ..accuracy import accuracy as accuracy_preset

    accuracy = accuracy_preset(accuracy or spec.verification.accuracy)
    return of(spec).simulate_box_build(spec, design, errors, deviations, accuracy)


def _axes(spec: Spec) -> tuple[str, ...]:
    return of(spec).box_axes_of(spec).names


def _half_widths(spec: Spec, tolerance: dict) -> tuple[float, float]:
    return tuple(float(tolerance.get(axis, 0.0)) for axis in _axes(spec))
