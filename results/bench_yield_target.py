"""Tolerances allocated for a yield target: the design chosen with them (`optimize`) against the
spec's own design sized alone; writes results/bench_yield_target.md.

problems/manipulators_yield_target.toml (the long row's parts, the pivots' places and heights
to allocate with weight 1, every other part at its given tolerance, stop angles free, target
99.73 %) at 20 stages and the same at 100 stages. For each:

* fixed design: the spec's guess (the long row's alpha 0.0613, beta 0.4928) sized alone, the
  largest common scale s at which its linearised yield reaches the target (grid and bisection:
  solve/yield_allocation.allocate_for_yield);
* optimize: the design and s together (formulation/manipulators/yield_target.py: one NLP, log s
maximised,
  the nines of the union bound >= those of the target);

then each built BUILDS times with the same seed (the same deviations per unit tolerance) and
judged as `pdm-design yield` judges it (the closed-form map, the event simulator on every build
that leaves it and on a random sample): the Monte Carlo yield with its 95 % Wilson interval
against the target the linearisation promised.

    python results/bench_yield_target.py [--builds N] [--stages 20 100]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
SPEC = "problems/manipulators_yield_target.toml"
BUILDS = 10000
STAGES = (20, 100)


def run(stages: int, builds: int) -> list[dict]:
    """The fixed design's and the optimized answer's s, linearised and Monte Carlo yields."""
    from pdm_design.formulation import formulate
    from pdm_design.scenes.manipulators.formulation.statistical import linearised_yield
    from pdm_design.scenes.manipulators.formulation.yield_target import AUX
    from pdm_design.solve import optimize
    from pdm_design.solve.yield_allocation import allocate_for_yield, with_scale
    from pdm_design.spec import load_spec

    spec = load_spec(ROOT / SPEC)
    spec = dataclasses.replace(spec, verification=dataclasses.replace(spec.verification,
                                                                      stages=stages))
    tolerances = spec.tolerances
    tic = time.perf_counter()
    fixed = allocate_for_yield(spec.scene, spec.design_at(), tolerances, stages=stages)
    rows = [{"how": "fixed design (the spec's), s alone", "design": spec.design_at(),
             "scale": fixed.scale, "seconds": time.perf_counter() - tic}]
    tic = time.perf_counter()
    found = optimize(spec)
    seconds = time.perf_counter() - tic
    scale = float(found.solution.x[formulate(spec).x_names.index(AUX)])
    rows.append({"how": "optimize: design and s", "status": found.status.name,
                 "design": spec.design_at({n: found.design[n] for n in spec.free_variables}),
                 "scale": scale, "seconds": seconds})
    for row in rows:
        sized = with_scale(tolerances, row["scale"])
        row["linearised"] = linearised_yield(spec.scene, row["design"], sized, stages)
        row["mc"], row["mc_seconds"] = monte_carlo(spec, row["design"], sized, stages, builds)
        row["stages"] = stages
    return rows


def monte_carlo(spec, design, tolerances, stages, builds):
    from pdm_design.tolerances.yield_ import yield_of

    tic = time.perf_counter()
    result = yield_of(spec.scene, design, tolerances, builds=builds, stages=stages,
                      seed=tolerances.seed, confirm=tolerances.confirm, scales=(),
                      sensitivity_samples=0)
    return result, time.perf_counter() - tic


def pct(x: float) -> str:
    return f"{100.0 * x:.2f} %"


def report(rows: list[dict], builds: int, target: float, command: str) -> str:
    lines = [
        "# Tolerances allocated for a yield target: optimize against the fixed design", "",
        f"Command: `{command}` (a shared, loaded machine: times are indicative).", "",
        f"`{SPEC}`: the long row's parts (link +-5 mm, back stop +-1 deg, palm +-10 g, "
        "friction +-0.1 per lot, all normal, sigma = t/3), the pivots' places and heights "
        "allocated (weight 1: one half-width s for both), target "
        f"{pct(target)}, at each row length. Both answers built {builds} times with the same "
        "seed and judged as `pdm-design yield` judges them.", "",
        "| stages | answer | alpha | beta | s (pivot +- mm) | linearised yield | MC yield | "
        "95 % interval | failures | simulated | agreed (of random) | solve s | MC s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        y, c = r["mc"], r["mc"].confirmed
        fails = ", ".join(f"{k} {v}" for k, v in y.failures.items()) or "none"
        lines.append(
            f"| {r['stages']} | {r['how']} | {r['design'].alpha:.4f} | {r['design'].beta:.4f} | "
            f"{1e3 * r['scale']:.2f} | {pct(r['linearised']['yield'])} | {pct(y.estimate)} | "
            f"{pct(y.ci_low)} - {pct(y.ci_high)} | {fails} | {c['simulated']} | "
            f"{c['agreed']} of {c['random']} | {r['seconds']:.1f} | {r['mc_seconds']:.1f} |")
    lines += ["", "Gain of optimize over the fixed design, and where the target stands in the "
              "Monte Carlo interval:", ""]
    for fixed, best in zip(rows[::2], rows[1::2]):
        lines.append(f"- {fixed['stages']} stages: s* / s_fixed = "
                     f"{best['scale'] / fixed['scale']:.4f}; " + "; ".join(
                         f"{name} {_versus(r['mc'], target)}"
                         for name, r in (("fixed", fixed), ("optimize", best))))
    return "\n".join(lines) + "\n"


def _versus(y, target) -> str:
    if y.ci_low > target:
        return f"above the target (interval's lower end {pct(y.ci_low)})"
    if y.ci_high < target:
        return f"below the target (interval's upper end {pct(y.ci_high)}): optimistic"
    return "the target within the interval"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--builds", type=int, default=BUILDS)
    parser.add_argument("--stages", type=int, nargs="+", default=list(STAGES))
    args = parser.parse_args()
    from pdm_design.io import write_atomic
    from pdm_design.spec import load_spec

    rows = [row for stages in args.stages for row in run(stages, args.builds)]
    command = "python results/bench_yield_target.py" + (
        f" --builds {args.builds}" if args.builds != BUILDS else "") + (
        f" --stages {' '.join(map(str, args.stages))}" if tuple(args.stages) != STAGES else "")
    target = load_spec(ROOT / SPEC).tolerances.yield_target
    text = report(rows, args.builds, target, command)
    write_atomic(ROOT / "results" / "bench_yield_target.md", text)
    print(text)


if __name__ == "__main__":
    main()
