"""The compass gait on rough ground: the mean steps before a fall by forward flux sampling
(scenes/compass_gait/rough.py) against plain Monte Carlo, and what each costs. Writes
results/bench_compass_gait_rough.md.

    python results/bench_compass_gait_rough.py

The classic walker at 3 deg, every step's slope error normal with sigma = t / 3. Where walkers
can be walked until they all fall (t = 0.012, 0.010 rad), their mean steps is the reference;
where falls are rarer (t = 0.007 rad: thousands of steps), the fraction of 2000 walkers that
fall within 100 steps is, against 1 - exp(-100 / mfpt) of the flux sampling.
"""

from __future__ import annotations

import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from pdm_design.scenes.compass_gait import (  # noqa: E402
    CompassGaitDesign,
    CompassGaitInitial,
    CompassGaitScene,
    rough,
)
from pdm_design.scenes.compass_gait.builds import walk_builds  # noqa: E402
from pdm_design.tolerance_model import Tolerance  # noqa: E402

SCENE = CompassGaitScene(initial=CompassGaitInitial(-0.22, 0.32, 1.1, 0.4))
DESIGN = CompassGaitDesign(slope=math.radians(3.0))


def walked(t, walkers, steps, seed=1):
    deviations = {"slope": np.random.default_rng(seed).normal(0.0, t / 3, (walkers, steps))}
    t0 = time.perf_counter()
    run = walk_builds(SCENE, DESIGN, deviations, steps)
    return run, time.perf_counter() - t0


def main():
    rows = []
    for t, walkers, steps in ((0.012, 1000, 1000), (0.010, 2000, 3000), (0.007, 2000, 100)):
        t0 = time.perf_counter()
        found = rough.mfpt(SCENE, DESIGN, (Tolerance("slope", "each", t),))
        t_ffs = time.perf_counter() - t0
        run, t_mc = walked(t, walkers, steps)
        ffs = (f"{found['estimate']:.4g} ({found['ci_low']:.4g} to {found['ci_high']:.4g}), "
               f"{max(found['levels'])} levels")
        if np.all(run.fall >= 0):
            mean = run.steps.mean()
            se = run.steps.std(ddof=1) / math.sqrt(walkers)
            mc = f"{mean:.4g} +- {1.96 * se:.2g} ({walkers} walkers until all fell)"
        else:
            fell = float(np.mean(run.fall >= 0))
            half = 1.96 * math.sqrt(fell * (1 - fell) / walkers)
            implied = [100 * (1 - math.exp(-steps / found[k]))
                       for k in ("estimate", "ci_high", "ci_low")]
            mc = (f"{100 * fell:.2f} +- {100 * half:.2f} % fell within {steps} steps "
                  f"({walkers} walkers); flux sampling: {implied[0]:.2f} % "
                  f"({implied[1]:.2f} to {implied[2]:.2f} %)")
        rows.append(f"| {t} | {ffs} | {t_ffs:.1f} s | {mc} | {t_mc:.1f} s |")
    lines = [
        "# Compass gait on rough ground: mean steps before a fall",
        "",
        f"`python results/bench_compass_gait_rough.py` on "
        f"{platform.processor() or platform.machine()}, Python {platform.python_version()}; "
        "the classic walker at 3 deg, every step's slope error normal with sigma = t / 3; "
        "one run each (the machine shared: times are wall clock).",
        "",
        "| t (rad) | forward flux sampling: mean steps (95 %) | time | Monte Carlo | time |",
        "|---|---|---|---|---|",
        *rows, "",
    ]
    (HERE / "bench_compass_gait_rough.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
