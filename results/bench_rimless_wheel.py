"""Benchmarks of the rimless wheel; writes results/bench_rimless_wheel.md.

1. The vectorised step map: one wheel (problems/rimless_wheel_ramp.toml's) for 10^6 steps on a
   rough ramp (slope errors sigma = 0.001 rad, so it never falls), and 1000 wheels x 1000
   steps. Target: 10^6 steps <= 2 s.
2. The event simulator's logged run: 1000 steps (the numerical stance, events, the general
   impact), for scale.
3. The mean first-passage time by the Markov chain (400 and 800 bins, Richardson) of an 8-spoke
   wheel whose mean steps before a fall is above 10^7. Target <= 10 s. Beside it, the chain
   against Monte Carlo where both can run (mean about 60 steps).
Each timing is the best of REPEATS runs on one core; the load average is recorded beside it.

    python results/bench_rimless_wheel.py
"""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
REPEATS = 3


def best_of(fn):
    times, out = [], None
    for _ in range(REPEATS):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return min(times), out


def main() -> None:
    from pdm_design.scenes.rimless_wheel import (
        RimlessWheelDesign,
        RimlessWheelInitial,
        RimlessWheelScene,
        Wheel,
        rough,
    )
    from pdm_design.scenes.rimless_wheel.analysis import resolve
    from pdm_design.scenes.rimless_wheel.sim import simulate_rimless_wheel
    from pdm_design.scenes.rimless_wheel.steps import step_map

    os.sched_setaffinity(0, {0})
    scene = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.6), friction=0.8,
                              wheel=Wheel(mass=2.0, gyration=0.1, spoke_mass=0.05))
    design = RimlessWheelDesign(spokes=10, leg_length=0.5, slope=0.08)
    wh, _, _ = resolve(scene, design)
    rng = np.random.default_rng(0)
    one = design.slope + rng.normal(0.0, 0.001, (1, 10**6))
    many = design.slope + rng.normal(0.0, 0.001, (1000, 1000))
    step_map(wh, 1.6, one[:, :10], ground=wh.ground)
    t_one, run_one = best_of(lambda: step_map(wh, 1.6, one, ground=wh.ground))
    t_many, run_many = best_of(lambda: step_map(wh, 1.6, many, ground=wh.ground))
    start = time.perf_counter()
    logged = simulate_rimless_wheel(scene, design, stages=1000)
    t_logged = time.perf_counter() - start

    point = RimlessWheelScene(initial=RimlessWheelInitial(speed=1.1))
    eight = RimlessWheelDesign(spokes=8, leg_length=1.0, slope=0.08)
    t_chain, chain = best_of(lambda: rough.mfpt(point, eight, 0.0105))
    t_short, short = best_of(lambda: rough.mfpt(point, eight, 0.03))
    start = time.perf_counter()
    mc = rough.monte_carlo(point, eight, 0.03, steps=2000, samples=4000, seed=1)
    t_mc = time.perf_counter() - start

    load = os.getloadavg()[0]
    lines = [
        "# Rimless wheel benchmarks",
        "",
        f"`python results/bench_rimless_wheel.py` on {platform.processor() or platform.machine()}"
        f", one core, best of {REPEATS}; load average {load:.2f} at the end.",
        "",
        "| what | size | time (s) | result |",
        "|---|---|---|---|",
        f"| step map, one wheel | 10^6 steps | {t_one:.3f} | {int(run_one.passed[0])} steps "
        "made (target <= 2 s) |",
        f"| step map, 1000 wheels | 1000 steps each | {t_many:.3f} | "
        f"{int(np.sum(run_many.passed == 1000))} of 1000 made every step |",
        f"| event simulator, logged | 1000 steps | {t_logged:.3f} | "
        f"completed: {logged.outcome.completed} |",
        f"| mfpt, Markov chain | 400 + 800 bins | {t_chain:.3f} | {chain['estimate']:.4g} steps "
        f"[{chain['ci_low']:.4g}, {chain['ci_high']:.4g}] (target <= 10 s) |",
        f"| mfpt, Markov chain, short-lived | 400 + 800 bins | {t_short:.3f} | "
        f"{short['estimate']:.4g} [{short['ci_low']:.4g}, {short['ci_high']:.4g}] |",
        f"| Monte Carlo, the same | 4000 wheels x 2000 steps | {t_mc:.3f} | mean "
        f"{mc['mean']:.4g} +- {mc['standard_error']:.2g} (one standard error) |",
        "",
        "The long-lived design: 8 spokes of 1 m (a point mass), slope 0.08 rad, start 1.1 rad/s, "
        "slope errors sigma = 0.0035 rad. The short-lived one: sigma = 0.01 rad. The interval "
        "is the discretisation's (two resolutions and their Richardson extrapolation, "
        "docs/rimless_wheel.md section 8), not a statistical one.",
        "",
    ]
    path = ROOT / "results" / "bench_rimless_wheel.md"
    marker = "<!-- optimize: begin -->"  # bench_rimless_wheel_optimize.py's section, kept
    kept = path.read_text() if path.exists() else ""
    kept = kept[kept.index(marker):] if marker in kept else ""
    path.write_text("\n".join(lines) + ("\n\n" + kept if kept else ""))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
