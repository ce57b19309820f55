"""The cost of `max_yield` and of a yield target on long rows, this code against an older
checkout in the same run; writes results/bench_max_yield_speed.md.

Each case runs `python -m pdm_design optimize SPEC --format json [--no-verify]` as a
subprocess under /usr/bin/time -v (wall time, CPU seconds (user + system) and peak resident
memory, end to end: import, NLP build, every IPOPT start, the tie-break, the checks and,
without --no-verify, the simulator's verification), once with this checkout and once with the
old one (--old DIR: its own PYTHONPATH), on problems/manipulators_long_row_yield.toml at 20,
100 and 1,000 stages ([verification] stages rewritten in a copy) and
problems/manipulators_yield_target.toml (20 and 100 stages) and
results/specs/manipulators_yield_target_1000.toml (its given tolerances a tenth). A run longer
than --timeout seconds is stopped and reported as such. Each answer's design is then built
`--builds` times with the spec's seed and judged as `pdm-design yield` judges it
(tolerances.yield_.yield_of, this checkout's), both designs on the same builds (one run where
the designs agree to 12 digits).
The machine is shared: the load average is written beside every run, and CPU seconds beside
the wall's.

    python results/bench_max_yield_speed.py --old /path/to/old/checkout [--builds N]
        [--cases 0,1,2] [--no-verify] [--timeout S]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
LONG = "problems/manipulators_long_row_yield.toml"
TARGET = "problems/manipulators_yield_target.toml"
TARGET_1000 = "results/specs/manipulators_yield_target_1000.toml"  # its given tolerances a tenth
CASES = [(LONG, 20, True), (LONG, 100, True), (LONG, 1000, True), (TARGET, 20, True),
         (TARGET, 100, True), (TARGET_1000, 1000, True)]


def spec_copy(source: str, stages: int, folder: Path) -> Path:
    text = (ROOT / source).read_text()
    text = re.sub(r"(?m)^stages = \d+", f"stages = {stages}", text)
    path = folder / f"{Path(source).stem}_{stages}.toml"
    path.write_text(text)
    return path


def optimize(checkout: Path, spec: Path, extra: list[str], timeout: float) -> dict:
    """Wall and CPU seconds, peak RSS (MB), the JSON answer and the load around one CLI run."""
    env = dict(os.environ, PYTHONPATH=str(checkout))
    load = os.getloadavg()[0]
    tic = time.perf_counter()
    try:
        run = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "pdm_design",
                              "optimize", str(spec), "--format", "json", *extra], cwd=checkout,
                             env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"wall": None, "rss": None, "cpu": None, "answer": None, "load": load,
                "stopped": timeout}
    wall = time.perf_counter() - tic
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", run.stderr)
    cpu = sum(float(m) for m in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)",
                                           run.stderr))
    try:
        answer = json.loads(run.stdout)
    except json.JSONDecodeError:
        answer = None
    return {"wall": wall, "rss": int(rss.group(1)) / 1024.0 if rss else None, "cpu": cpu,
            "answer": answer, "load": (load + os.getloadavg()[0]) / 2.0}


def monte_carlo(spec_path: Path, design: dict, builds: int):
    from pdm_design.spec import load_spec
    from pdm_design.tolerances.yield_ import yield_of

    spec = load_spec(spec_path)
    tolerances = spec.tolerances
    if any(t.allocate for t in tolerances):
        return None  # sized tolerances: `optimize` itself reports their check
    return yield_of(spec.scene, spec.design_at(design), tolerances, builds=builds,
                    stages=spec.verification.stages, seed=tolerances.seed,
                    confirm=tolerances.confirm, scales=(), sensitivity_samples=0)


def _seconds(run: dict | None) -> str:
    """Wall seconds (CPU seconds), or the limit a stopped run reached."""
    if run is None:
        return "-"
    if run.get("stopped"):
        return f"stopped at {run['stopped']:.0f}"
    return f"{cell(run, 'wall', '{:.1f}')} ({cell(run, 'cpu', '{:.1f}')})"


def cell(run: dict | None, key: str, fmt: str) -> str:
    if run is None or run.get(key) is None:
        return "-"
    return fmt.format(run[key])


def describe(answer: dict | None) -> str:
    if answer is None:
        return "no answer"
    d, solver = answer["design"], answer["solver"]
    extra = ""
    if answer.get("tolerances"):
        extra = " pivot " + ", ".join(f"{t['quantity']} {t['value']:.6g}"
                                      for t in answer["tolerances"][:1]
                                      if isinstance(t, dict) and "value" in t)
    value = answer["objective"]["value"]
    checked = answer.get("tolerances_yield") or {}
    check = (f"; Monte Carlo check {100 * checked['estimate']:.2f} % "
             f"(from {100 * checked['ci_low']:.2f} %) at {checked['scale']:.4g} of the size, "
             f"{len(checked['steps'])} runs" if checked else "")
    return (f"{answer['status']}: alpha {d['alpha']:.10f}, beta {d['beta']:.10f}, objective "
            f"{'none' if value is None else f'{value:.10g}'}{extra}; "
            f"{solver['total_iterations']} iterations, build {solver['build_time']:.1f} s, "
            f"IPOPT {solver['total_solve_time']:.1f} s{check}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True)
    parser.add_argument("--builds", type=int, default=10000)
    parser.add_argument("--cases", default="all", help="'all' or indices, e.g. 0,1")
    parser.add_argument("--no-verify", action="store_true", help="optimize --no-verify")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds a run may take")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "bench_max_yield_speed.md")
    args = parser.parse_args()
    chosen = range(len(CASES)) if args.cases == "all" else [int(i) for i in
                                                             args.cases.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in chosen:
            source, stages, with_old = CASES[i]
            spec = spec_copy(source, stages, Path(tmp))
            extra = ["--no-verify"] if args.no_verify else []
            old = optimize(args.old, spec, extra, args.timeout) if with_old else None
            new = optimize(ROOT, spec, extra, args.timeout)
            yields, seen = {}, {}
            for label, run in (("old", old), ("new", new)):
                if run is not None and run["answer"] is not None:
                    design = run["answer"]["design"]
                    key = tuple(f"{design[n]:.12e}" for n in sorted(design))
                    if key not in seen:
                        seen[key] = monte_carlo(spec, design, args.builds)
                    yields[label] = seen[key]
            rows.append((source, stages, old, new, yields))
            print(source, stages, cell(old, "wall", "{:.1f}"), cell(new, "wall", "{:.1f}"),
                  flush=True)
    command = "python results/bench_max_yield_speed.py " + " ".join(sys.argv[1:])
    args.out.write_text(report(rows, args.builds, command))


def report(rows, builds, command) -> str:
    lines = ["# max_yield and a yield target on long rows: this code against the old", "",
             f"Command: `{command}`. End to end `pdm-design optimize --format json` under "
             "/usr/bin/time -v, old and new in the same run; CPU s is user + system time; the "
             "load average (2 cores, shared) is the mean of its values before and after each "
             "run.", "",
             "| spec | stages | old s (CPU s) | new s (CPU s) | old / new | old MB | new MB | "
             "old / new | load old, new |", "|---|---|---|---|---|---|---|---|---|"]
    for source, stages, old, new, _ in rows:
        ratio_t = (f"{old['wall'] / new['wall']:.1f}" if old and old["wall"] and new["wall"]
                   else "-")
        ratio_m = (f"{old['rss'] / new['rss']:.1f}" if old and old["rss"] and new["rss"]
                   else "-")
        lines.append(f"| `{Path(source).name}` | {stages} | {_seconds(old)} | {_seconds(new)} | "
                     f"{ratio_t} | {cell(old, 'rss', '{:.0f}')} | {cell(new, 'rss', '{:.0f}')} | "
                     f"{ratio_m} | {cell(old, 'load', '{:.1f}')}, {cell(new, 'load', '{:.1f}')} |")
    lines += ["", "Answers (the design to 10 digits, the solver's own counts) and the Monte "
              f"Carlo yield of each design on the same {builds} builds (95 % Wilson interval):",
              ""]
    for source, stages, old, new, yields in rows:
        lines.append(f"- `{Path(source).name}`, {stages} stages:")
        for label, run in (("old", old), ("new", new)):
            if run is None or run.get("stopped"):
                lines.append(f"  - {label}: " + ("not run" if run is None else
                                                 f"stopped after {run['stopped']:.0f} s"))
                continue
            y = yields.get(label)
            mc = (f"; MC yield {100 * y.estimate:.2f} % ({100 * y.ci_low:.2f} - "
                  f"{100 * y.ci_high:.2f} %)" if y is not None else "")
            lines.append(f"  - {label}: {describe(run['answer'])}{mc}")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
