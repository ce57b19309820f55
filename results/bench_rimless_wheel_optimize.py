"""`pdm-design optimize` of each rimless wheel problem end to end (a fresh process: imports,
solve or search, verification), in this checkout and, given one, in another (the old code) in
the same run; writes its section of results/bench_rimless_wheel.md.

Wall time and CPU time (user + system of the process) are each the best of REPEATS runs; on a
shared machine the wall time follows the load (recorded beside), the CPU time much less.

    python results/bench_rimless_wheel_optimize.py [OLD_CHECKOUT]
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ("ramp", "stairs", "rough", "max_yield", "yield_target")
REPEATS = 3
BEGIN, END = "<!-- optimize: begin -->", "<!-- optimize: end -->"


def run(checkout: Path, problem: str) -> tuple[float, float]:
    """(wall, cpu) seconds of one `optimize` in a fresh process from `checkout`."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pdm_design", "optimize",
                    str(ROOT / "problems" / f"rimless_wheel_{problem}.toml")], cwd=checkout,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def best(checkout: Path, problem: str) -> tuple[float, float]:
    runs = [run(checkout, problem) for _ in range(REPEATS)]
    return min(r[0] for r in runs), min(r[1] for r in runs)


def main() -> None:
    checkouts = [("this", ROOT)] + ([("old", Path(sys.argv[1]).resolve())]
                                    if len(sys.argv) > 1 else [])
    rows = []
    for problem in PROBLEMS:
        for name, checkout in checkouts:
            wall, cpu = best(checkout, problem)
            rows.append(f"| {problem} | {name} | {wall:.2f} | {cpu:.2f} |")
            print(rows[-1], flush=True)
    load = os.getloadavg()[0]
    section = "\n".join([
        BEGIN, "", "## `optimize` end to end", "",
        f"`python results/bench_rimless_wheel_optimize.py{' OLD' if len(checkouts) > 1 else ''}`"
        f": `python3 -m pdm_design optimize problems/rimless_wheel_PROBLEM.toml` in a fresh "
        f"process, best of {REPEATS}; the old code (OLD, the checkout before these changes) in "
        f"the same run. Load average {load:.2f} at the end (2 cores): the wall time follows "
        "the load, the CPU time (user + system) much less. Target: <= 1 s.", "",
        "| problem | code | wall (s) | CPU (s) |", "|---|---|---|---|", *rows, "", END])
    path = ROOT / "results" / "bench_rimless_wheel.md"
    text = path.read_text()
    if BEGIN in text:
        text = text[:text.index(BEGIN)] + section + text[text.index(END) + len(END):]
    else:
        text = text.rstrip() + "\n\n" + section + "\n"
    path.write_text(text)


if __name__ == "__main__":
    main()
