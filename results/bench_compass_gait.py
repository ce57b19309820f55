"""The compass gait's speed, measured: the periodic gait and its multipliers of one design, a
200-point continuation over the slope with its bifurcations and period-2 gaits, and 10^5 steps
of the vectorised step map on a rough ramp. Writes results/bench_compass_gait.md (and
results/bench_compass_gait.png, the step length against the slope).

    python results/bench_compass_gait.py

Targets: fixed point + multipliers <= 50 ms; the sweep <= 10 s; 10^5 steps <= 5 s. Each time is
the median of `repeats` runs after one warm-up (which builds the CasADi functions once).
"""

from __future__ import annotations

import math
import platform
import statistics
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
    Walker,
    fastmap,
)
from pdm_design.scenes.compass_gait.bifurcation import plot_sweep, sweep  # noqa: E402
from pdm_design.scenes.compass_gait.gait import find_gait, fixed_point  # noqa: E402
from pdm_design.scenes.compass_gait.ground import params_for  # noqa: E402

SCENE = CompassGaitScene(initial=CompassGaitInitial(-0.22, 0.32, 1.1, 0.4),
                         walker=Walker(hip_mass=10.0, leg_mass=5.0, leg_length=1.0,
                                       leg_com=0.5))
DESIGN = CompassGaitDesign(slope=math.radians(3.0))


OTHERS = """
The robust NLP and rough ground have their own benchmarks: `results/bench_compass_gait_nlp.md`
(`python results/bench_compass_gait_nlp.py`: the robust spec's NLP at 60 RK4 substeps, the old
discretisation, against 30, the new, and 20, and a limited-memory Hessian, in one run) and
`results/bench_compass_gait_rough.md` (`python results/bench_compass_gait_rough.py`: the mean
steps before a fall by forward flux sampling against Monte Carlo).
"""


def timed(fn, repeats):
    fn()  # warm-up: builds the CasADi functions
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main():
    t_fp, gait = timed(lambda: fixed_point(SCENE, DESIGN), 20)
    slopes = np.radians(np.linspace(0.5, 6.0, 200))
    t_sweep, swept = timed(lambda: sweep(SCENE, DESIGN, slopes), 3)
    plot_sweep(swept, HERE / "bench_compass_gait.png")
    params = params_for(SCENE, DESIGN)
    state = find_gait(SCENE, DESIGN).state
    walkers, steps = 10_000, 10
    errors = np.random.default_rng(0).normal(0.0, 0.0005, (walkers, steps))
    t_walk, walk = timed(lambda: fastmap.walk(params, np.tile(state, (walkers, 1)),
                                              DESIGN.slope, steps, SCENE.friction, errors), 3)
    point = gait["fixed_point"]
    lines = [
        "# Compass gait: speed",
        "",
        f"`python results/bench_compass_gait.py` on {platform.processor() or platform.machine()}"
        f", Python {platform.python_version()} (medians after a warm-up).",
        "",
        "| what | time | target |",
        "|---|---|---|",
        f"| fixed point + multipliers, one design (3 deg) | {1e3 * t_fp:.1f} ms | <= 50 ms |",
        f"| 200-point slope sweep (0.5 to 6 deg) with bifurcations and period-2 gaits | "
        f"{t_sweep:.2f} s | <= 10 s |",
        f"| 10^5 steps ({walkers} walkers x {steps} steps, slope errors sd 0.0005 rad) | "
        f"{t_walk:.2f} s | <= 5 s |",
        "",
        "The 3 deg gait: stance {stance:.6f}, swing {swing:.6f} rad, rates {stance_rate:.6f}, "
        "{swing_rate:.6f} rad/s; step {length:.6f} m in {period:.6f} s; spectral radius "
        "{rho:.6f}.".format(**point, length=gait["step_length"], period=gait["step_period"],
                            rho=gait["spectral_radius"]),
        "",
        "Bifurcations found: " + "; ".join(
            f"{b['kind']} at {math.degrees(b['value']):.5f} deg ({b['value']:.7f} rad)"
            for b in swept["bifurcations"]) + f". Period-2 gaits at {len(swept['period_two'])} "
        "slopes. Steps taken by the walkers: " + f"{int(walk.steps.sum())}, falls "
        f"{walk.falls() or 'none'}.",
        "",
        "![step length against slope](bench_compass_gait.png)",
        "",
        *OTHERS.strip("\n").split("\n"),
        "",
    ]
    (HERE / "bench_compass_gait.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
