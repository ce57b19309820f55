"""Speed of the stairs build map (not a test): 10^5 builds x 100 bounces on one core, with the
event simulator's confirmation of a random subset and the Sobol' indices, on the design and
tolerances of problems/stairs_yield.toml (drawn as `pdm-design yield` draws them), and the
command `pdm-design yield problems/stairs_yield.toml` end to end. Writes
results/bench_yield_stairs.md.

    python results/bench_yield_stairs.py            # about half a minute
    python results/bench_yield_stairs.py --quick    # 10^4 builds

Target: 10^5 builds x 100 stages <= 10 s on one core (vectorised).
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from pdm_design.io import write_atomic  # noqa: E402
from pdm_design.scenes.stairs import physics as phys  # noqa: E402
from pdm_design.scenes.stairs.sim import bounce_sequence, stairs_geometry  # noqa: E402
from pdm_design.scenes.stairs.tolerances import run_builds, simulate_build  # noqa: E402
from pdm_design.spec import load_spec  # noqa: E402
from pdm_design.tolerances.draw import draw as draw_builds  # noqa: E402
from pdm_design.tolerances.sensitivity import sobol_indices  # noqa: E402

SPEC_PATH = "problems/stairs_yield.toml"
SPEC = load_spec(ROOT / SPEC_PATH)
SCENE, DESIGN, TOLERANCES = SPEC.scene, SPEC.design_at(), SPEC.tolerances


def draw(n, stages, seed):
    return draw_builds(TOLERANCES, n, stages, seed, scene=SCENE)


def end_to_end() -> tuple[float, str]:
    """`pdm-design yield` on the spec in a fresh process: wall time and its report."""
    exe = Path(sys.executable).with_name("pdm-design")
    tic = time.perf_counter()
    done = subprocess.run([str(exe), "yield", SPEC_PATH], cwd=ROOT, capture_output=True,
                          text=True, check=True)
    return time.perf_counter() - tic, done.stdout


def timed(fn, repeats):
    best, out = float("inf"), None
    for _ in range(repeats):
        tic = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - tic)
    return best, out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    t_cli, report = end_to_end()  # before this process pins itself to one core
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core
    n, stages, confirm = (10_000 if args.quick else 100_000), 100, 300
    t_draw, dev = timed(lambda: draw(n, stages, TOLERANCES.seed), 1)
    t_map, out = timed(lambda: run_builds(SCENE, DESIGN, dev, stages), 3)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    # baseline, same run: bounce_sequence, the uniform staircase's map (no per-step values)
    geo = stairs_geometry(SCENE, DESIGN)
    v1 = phys.impact_speed_vertical(9.81, 1.0)
    t_uniform, _ = timed(lambda: bounce_sequence(
        np.full(n, geo.landing_offset), 3.0, -v1, 0.0, bounces=stages, rise=geo.rise,
        tread=geo.tread, eps=0.8, r=0.05), 3)

    rng = np.random.default_rng(2)
    picked = rng.choice(n, confirm, replace=False)
    tic = time.perf_counter()
    agreed = 0
    for i in picked:
        result = simulate_build(SCENE, DESIGN, {q: v[i] for q, v in dev.items()}, stages)
        kind = result.outcome.failure.kind if result.outcome.failure else ""
        agreed += (kind, result.outcome.stages_passed) == (out.failure[i], out.stages_passed[i])
    t_sim = (time.perf_counter() - tic) / confirm

    tic = time.perf_counter()
    rows = sobol_indices(lambda d, s: run_builds(SCENE, DESIGN, d, s), TOLERANCES,
                         stages=stages, samples=1024, seed=TOLERANCES.seed)
    t_sobol = time.perf_counter() - tic
    write(args, n, stages, t_draw, t_map, peak, t_uniform, t_sim, confirm, agreed, out, rows,
          t_sobol, t_cli, report)


def write(args, n, stages, t_draw, t_map, peak, t_uniform, t_sim, confirm, agreed, out, rows,
          t_sobol, t_cli, report):
    bounces = int(out.stages_passed.sum())
    counts = {k or "passed": int((out.failure == k).sum()) for k in sorted(set(out.failure))}
    verdict = "met" if t_map <= 10.0 else "NOT met"
    command = "python results/bench_yield_stairs.py" + (" --quick" if args.quick else "")
    lines = [
        "# Stairs builds: speed of the vectorised map",
        "",
        f"Regenerate: `{command}`. Machine: pinned to one core of "
        f"{os.cpu_count()}, {platform.machine()}, Python {platform.python_version()}, "
        f"numpy {np.__version__}. Design and tolerances of `problems/stairs_yield.toml` "
        "(stairs_design's optimum; rise and tread +-5 mm per step, restitution +-0.0015 and "
        "launch speed +-0.015 m/s per lot, normal, sigma = t/3), drawn as `pdm-design yield` "
        "draws them (seed 0). Best of 3.",
        "",
        "| target | measured | baseline (same run) | verdict |",
        "|---|---|---|---|",
        f"| {n:,} builds x {stages} stages <= 10 s on one core | {t_map:.2f} s "
        f"({bounces / t_map:.3g} bounces/s; {bounces:,} bounces flown) | `bounce_sequence` "
        f"(one uniform staircase, no per-step values) {t_uniform:.2f} s | {verdict} |",
        "",
        f"Drawing the deviations: {t_draw:.2f} s. Peak RSS of the process: {peak:.0f} MB "
        f"(the (N, K) arrays of rise and tread deviations are {2 * n * stages * 8 / 1e6:.0f} MB).",
        "",
        f"Yield: {counts.get('passed', 0) / n:.4f} ({n:,} builds); failures "
        + ", ".join(f"{k} {v:,}" for k, v in counts.items() if k != "passed")
        + f"; {int((~out.closed_form).sum())} builds left the closed-form regime.",
        "",
        f"Event simulator (`simulate_build`): {confirm} builds drawn at random, "
        f"{agreed} agree with the map on stages passed and failure name; "
        f"{t_sim * 1e3:.1f} ms a build ({t_map / n * 1e3:.4f} ms a build for the map, "
        f"{t_sim / (t_map / n):.0f}x).",
        "",
        f"Sobol' indices of the smallest margin (1024 x (4 + 2) = 6144 builds, {t_sobol:.1f} s "
        "with SALib's analysis):",
        "",
        "| quantity | total order ST | first order S1 | ST 95 % half width |",
        "|---|---|---|---|",
        *(f"| {r['quantity']} | {r['index']:.3f} | {r['first']:.3f} | {r['confidence']:.3f} |"
          for r in rows),
        "",
        f"`pdm-design yield {SPEC_PATH}` end to end ({TOLERANCES.builds:,} builds, the scale "
        f"curve, the sensitivity; a fresh process, not pinned): {t_cli:.1f} s wall (load "
        f"{os.getloadavg()[0]:.1f}).",
        "",
        "```",
        f"$ pdm-design yield {SPEC_PATH}",
        report.rstrip(),
        "```",
        "",
    ]
    write_atomic(ROOT / "results" / "bench_yield_stairs.md", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
