"""Benchmark: `pdm-design yield` on a row where nearly every build leaves the closed forms;
writes results/bench_crate_yield.md.

The spec, results/specs/crate_row.toml: a 2.5 kg crate on 30 manipulators, eight toleranced
quantities, pivots +-135 mm, 4000 builds (nearly all of them slip somewhere: the closed-form map
leaves them to the event simulator), and the yield-against-scale curve's builds besides.

Each run is a fresh process (`python -m pdm_design yield SPEC --format json`), timed from
outside: wall time, and the CPU seconds of the process and every worker it started
(getrusage of the waited-for children). The old code is the commit given by --base, checked out
as a git worktree and run with PYTHONPATH pointing at it, in the same invocation. The machine
is shared: the 1-minute load average is recorded before and after each run, and the JSON
documents are compared (the same builds, the same outcomes, whatever the code and workers).

    python results/bench_crate_yield.py [--builds N] [--base PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "results" / "specs" / "crate_row.toml"
OUT = ROOT / "results" / "bench_crate_yield.md"
BASE = Path("/work/wt/fastyield_base")  # `git worktree add ... af7e3d5`
BASE_COMMIT = "af7e3d5"


# `python -m pdm_design ...` that also writes, at exit, its own CPU seconds and its workers'
# to stderr (the last line)
WRAPPER = ("import atexit, resource, runpy, sys\n"
           "def cpu(who):\n"
           "    r = resource.getrusage(who)\n"
           "    return r.ru_utime + r.ru_stime\n"
           "atexit.register(lambda: print('cpu', cpu(resource.RUSAGE_SELF),"
           " cpu(resource.RUSAGE_CHILDREN), file=sys.stderr))\n"
           "sys.argv[0] = 'pdm_design'\n"
           "runpy.run_module('pdm_design', run_name='__main__')\n")


def run(code: Path, builds: int, workers: int | None) -> dict:
    """One `yield` run of the code checked out at `code`: its JSON, wall and CPU seconds (all,
    the main process' own, its workers')."""
    command = [sys.executable, "-c", WRAPPER, "yield", str(SPEC), "--builds", str(builds),
               "--format", "json"] + ([] if workers is None else ["--workers", str(workers)])
    env = dict(os.environ, PYTHONPATH=str(code))
    load_before = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall = time.perf_counter()
    done = subprocess.run(command, cwd=code, env=env, capture_output=True, text=True,
                          check=True)
    wall = time.perf_counter() - wall
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    own, workers_cpu = (float(v) for v in done.stderr.strip().splitlines()[-1].split()[1:])
    return {"json": done.stdout, "wall": wall, "cpu": cpu, "own": own, "workers": workers_cpu,
            "load": (load_before, os.getloadavg()[0])}


def idle(r: dict) -> str:
    """The wall time the run's CPU seconds allow on 2 idle cores (write: the note)."""
    if r["workers"] < 0.05 * r["cpu"]:  # one process
        return f"{r['cpu']:.1f}"
    return f"{r['cpu'] / 2:.1f} to {r['own'] + r['workers'] / 2:.1f}"


def simulated(document: dict) -> tuple[int, int]:
    """(builds of the headline left to the simulator, builds simulated in all)."""
    c = document["confirmed"]
    curve = sum(p["simulated"] for p in document["yield_against_scale"] if p["scale"] != 1.0)
    return c["left_closed_form"], c["simulated"] + curve


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--builds", type=int, default=4000)
    parser.add_argument("--base", type=Path, default=BASE)
    args = parser.parse_args()
    runs = [("old code (" + BASE_COMMIT + "), one process", args.base, None),
            ("new code, --workers 1", ROOT, 1),
            ("new code, --workers 2", ROOT, 2),
            ("new code, default (the machine's cores)", ROOT, None)]
    rows = []
    for label, code, workers in runs:
        print(f"{label} ...", file=sys.stderr, flush=True)
        rows.append((label, run(code, args.builds, workers)))
    write(rows, args.builds)


def write(rows, builds: int) -> None:
    old = rows[0][1]
    first = json.loads(old["json"])
    left, in_all = simulated(first)
    lines = [
        "# Yield of a row that leaves the closed forms: the crate row",
        "",
        f"Regenerate: `python results/bench_crate_yield.py` (--builds {builds}). Spec: "
        "`results/specs/crate_row.toml` (2.5 kg crate, 30 manipulators, eight toleranced "
        "quantities, pivots +-135 mm, palm friction 0.6). Machine: "
        f"{os.cpu_count()} cores shared with other jobs, {platform.machine()}, Python "
        f"{platform.python_version()}. Each run is a fresh `python -m pdm_design yield SPEC "
        "--format json` process; CPU is the seconds of the process and of every worker it "
        "started; load is the 1-minute load average before and after the run (2 = both cores "
        "busy).",
        "",
        f"{builds} builds: {left} of them leave the closed-form map and go to the event "
        f"simulator; with the yield-against-scale curve, {in_all} builds are simulated in all. "
        f"Yield {100 * first['yield']['estimate']:.2f} % "
        f"(95 % interval {100 * first['yield']['ci_low']:.2f} % to "
        f"{100 * first['yield']['ci_high']:.2f} %).",
        "",
        "| code | wall s | CPU s (main process + workers) | CPU per simulated build | "
        "wall on 2 idle cores, from the CPU s | load before / after | "
        "JSON the same as the old code's |",
        "|---|---|---|---|---|---|---|",
    ]
    for label, r in rows:
        same = "yes" if r["json"] == old["json"] else "NO"
        lines.append(f"| {label} | {r['wall']:.1f} | {r['cpu']:.1f} ({r['own']:.1f} + "
                     f"{r['workers']:.1f}) | {1000 * r['cpu'] / in_all:.2f} ms | "
                     f"{idle(r)} | {r['load'][0]:.1f} / {r['load'][1]:.1f} | {same} |")
    lines += ["", "*Wall on 2 idle cores*: what the CPU seconds allow when nothing else runs: "
              "one process, its CPU seconds; with workers, from all the CPU seconds shared "
              "evenly by the two cores (every process busy to the end) to the main process' "
              "own plus half the workers' (the main process never overlapping them). The "
              "machine was not idle (load column): the wall column is what this run got."]
    new1 = rows[1][1]
    lines += ["", f"CPU: the new code takes {old['cpu'] / new1['cpu']:.2f} times less than the "
              "old on one worker (the integrated phases on sim.rk instead of scipy's "
              "solve_ivp); the workers then share the builds between the cores."]
    OUT.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
