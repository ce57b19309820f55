"""The stairs' max_yield design against the worst-case optimum on the same builds; writes
results/bench_max_yield_stairs.md.

problems/stairs_yield_design.toml (stairs_yield's tolerances: every step's rise and tread
+-5 mm, one lot restitution +-0.0015 and launch speed +-0.015 m/s, normal; restitution, launch
speed and landing place free; 100 bounces) is optimised twice: with its objective max_yield
(the linearised yield, docs/optimizer.md section 10) and with max_offset_tolerance instead
(the largest box of every step's rise and tread errors, docs/optimizer.md section 4). Both
designs are built BUILDS times with the same seed, so the same deviations (tolerances.draw),
and judged as `pdm-design yield` judges them (the closed-form map, the event simulator on every
build that leaves it): both yields with their 95 % Wilson intervals, the failures by name, and
the builds one design passes and the other fails (an exact sign test on them).

    python results/bench_max_yield_stairs.py [--builds N] [--stages K]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
SPEC = "problems/stairs_yield_design.toml"
BUILDS = 10000


def judged(scene, design, tolerances, builds: int, stages: int, seed: int):
    """(passed all stages, failure name) of every build: the map, the event simulator on the
    builds that leave its closed forms (as `pdm-design yield`)."""
    import numpy as np

    from pdm_design.tolerances.yield_ import map_builds, simulate_one

    out = map_builds(scene, design, tolerances, builds, stages, seed)
    passed, failure = out.stages_passed.copy(), out.failure.copy()
    for i in np.flatnonzero(~out.closed_form):
        run = simulate_one(scene, design, tolerances, seed, int(i), stages).outcome
        passed[i] = run.stages_passed
        failure[i] = "" if run.completed else run.failure.kind
    return passed >= stages, failure, int((~out.closed_form).sum())


def design_of(spec, objective: str):
    """(the optimizer's answer for `objective`, the design it gives, seconds)."""
    from pdm_design.solve import optimize

    asked = dataclasses.replace(spec, objective={objective: 1.0})
    tic = time.perf_counter()
    found = optimize(asked, check_samples=0)
    return found, asked.design_at(found.design), time.perf_counter() - tic


def sign_test(better: int, worse: int) -> float:
    """One-sided exact sign test: P(at least `better` of better + worse fair coin flips)."""
    n = better + worse
    return sum(math.comb(n, k) for k in range(better, n + 1)) / 2.0 ** n if n else 1.0


def run(objective: str, spec, builds: int) -> dict:
    from pdm_design.scenes.stairs.formulation.statistical import linearised_yield
    from pdm_design.tolerances.yield_ import wilson

    found, design, solve = design_of(spec, objective)
    stages, tolerances = spec.verification.stages, spec.tolerances
    passed, failure, left = judged(spec.scene, design, tolerances, builds, stages,
                                   tolerances.seed)
    low, high = wilson(passed.sum(), builds)
    return {"objective": objective, "status": found.status.name, "design": found.design,
            "tolerance": found.tolerance, "solve": solve, "passed": passed,
            "yield": passed.mean(), "low": float(low), "high": float(high),
            "failures": Counter(failure[~passed]), "left": left,
            "linearised": linearised_yield(spec.scene, design, tolerances, stages)}


def pct(x: float) -> str:
    return f"{100.0 * x:.2f} %"


def report(rows: list[dict], spec, builds: int, command: str) -> str:
    lines = [
        "# The stairs' max_yield design against the worst-case optimum", "",
        f"Command: `{command}` (a shared, loaded machine: times are indicative).", "",
        f"`{SPEC}` at {spec.verification.stages} bounces: every step's rise and tread +-5 mm, "
        "one lot restitution +-0.0015 and launch speed +-0.015 m/s, all normal (sigma = t/3); "
        "restitution, launch speed and landing place free. Each design is built "
        f"{builds} times with the same seed (the same deviations) and judged as `pdm-design "
        "yield` judges it: the closed-form map, the event simulator on every build that "
        "leaves it.", "",
        "| objective | status | restitution | launch speed m/s | landing offset m | MC yield | "
        "95 % interval | failures | left the map | linearised yield (Hunter's bound, the "
        "objective's) | union bound's | smallest beta_i | solve s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        d, lin = r["design"], r["linearised"]
        fails = ", ".join(f"{k} {v}" for k, v in r["failures"].items()) or "none"
        lines.append(
            f"| `{r['objective']}` | {r['status']} | {d['restitution']:.4f} | "
            f"{d['launch_speed']:.4f} | {d['landing_offset']:.4f} | {pct(r['yield'])} | "
            f"{pct(r['low'])} - {pct(r['high'])} | {fails} | {r['left']} | "
            f"{pct(lin['yield'])} | {pct(max(0.0, 1.0 - lin['union_bound']))} | "
            f"{lin['min_beta']:.2f} | {r['solve']:.1f} |")
    best, worst = rows
    better = int((best["passed"] & ~worst["passed"]).sum())
    worse = int((~best["passed"] & worst["passed"]).sum())
    p = sign_test(better, worse)
    lines += ["", f"Paired on the builds: {better} builds only the max_yield design passes, "
              f"{worse} only the worst-case optimum; one-sided exact sign test p = {p:.2g}."]
    box = worst["tolerance"] or {}
    if box:
        lines += ["", f"The worst-case optimum's box: +-{1e3 * box['rise']:.2f} mm on every "
                  "step's rise and tread (the steps alone: the lot's restitution and launch "
                  "speed are not in it)."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--builds", type=int, default=BUILDS)
    parser.add_argument("--stages", type=int, default=None)
    args = parser.parse_args()
    from pdm_design.io import write_atomic
    from pdm_design.spec import load_spec

    spec = load_spec(ROOT / SPEC)
    if args.stages:
        spec = dataclasses.replace(spec, verification=dataclasses.replace(
            spec.verification, stages=args.stages))
    rows = [run("max_yield", spec, args.builds), run("max_offset_tolerance", spec, args.builds)]
    command = "python results/bench_max_yield_stairs.py" + (
        f" --builds {args.builds}" if args.builds != BUILDS else "") + (
        f" --stages {args.stages}" if args.stages else "")
    text = report(rows, spec, args.builds, command)
    write_atomic(ROOT / "results" / "bench_max_yield_stairs.md", text)
    print(text)


if __name__ == "__main__":
    main()
