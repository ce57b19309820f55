"""Long rows at scale: `pdm-design optimize problems/manipulators_robust.toml` with only
`[verification] stages` changed, and a `table` of robust-optimised points, each timed end to end
(a fresh process, as a user runs it) against the old code measured in the same run.

    python results/bench_scale.py            # writes results/bench_scale.md and results/scale.png
    python results/bench_scale.py --quick    # fewer rows and a smaller table (a few minutes)

Options: --base DIR (the old code's checkout; default: round 1's code, commit ROUND1 below,
extracted with git archive into a temporary folder), --old-max N (the longest
row run on the old code: it took 144 s and 9 GB at 10 000 stages), --table-points N,
--before DIR (a checkout of the code before a table change: its table is run with the same
points, right after the new one), --repeat K (new and before alternately, K times each),
--table-only (only the tables: the table section of results/bench_scale.md is rewritten, the
rows above it kept), --profile N (where the time of N points goes, in this process).
Wall time and peak memory (the process' maximum resident set, from os.wait4, which covers a
table's worker processes too) are of one run each, the fastest of three for rows up to 100
stages; the machine's load is printed with them.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
SPEC = REPO / "problems" / "manipulators_robust.toml"
TARGETS = {6: (0.5, None), 100: (1.0, None), 1000: (3.0, 300.0), 10000: (30.0, 1024.0)}
TABLE_HEADING = "## Table of robust-optimised points (mass_ratio x friction, 2 workers)"
TABLE_TARGET = (10_000, 120.0)  # points, seconds with 2 workers
REPEATS, REPEAT_MAX = 3, 100  # rows up to REPEAT_MAX stages: the fastest of REPEATS runs
TABLE_NOTE = (
    "A row simulates the nominal build, the 12 corner patterns and 4 of the spec's 16 random "
    "builds (sweep/run.py `table_verification`) and checks its box through the stage maps (256 "
    "samples). CPU a point is the user and system time of the table's process and its workers "
    "(os.wait4), less sensitive to the shared machine's load than the wall time. The table's "
    "points share one NLP (friction and mass ratio are its parameters, formulation/"
    "parametric.py), so a worker formulates it, creates its solvers and builds its stage maps "
    "once; a chain's first point is solved from the 8 starts (stacked), each later point from "
    "the local optima of the point before (docs/tables.md, \"Speed\"), and the tie-break is "
    "skipped where it cannot move the design (solve/tiebreak.py `pinned`). `old` is round 1's "
    "code, where every point was a new NLP solved from every start.")
AGREEMENT_SAMPLE = 200  # rows of the new table compared with optimize of their points


def run(code: Path, args: list[str], timeout: float) -> dict:
    """One `python -m pdm_design ARGS` of the code in `code`: wall s, peak MB, exit, stdout."""
    env = dict(os.environ, PYTHONPATH=str(code))  # not a tty: no progress bars
    # as installed code runs: its bytecode cached (pip compiles it; a checkout writes it on the
    # first run), not compiled again at every start as PYTHONDONTWRITEBYTECODE makes it
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryFile() as out:
        tic = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "pdm_design", *args], cwd=code, env=env,
                                stdout=out, stderr=subprocess.DEVNULL)
        deadline = tic + timeout
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() > deadline:
                proc.kill()
                os.wait4(proc.pid, 0)
                return {"wall": None, "peak_mb": None, "exit": None, "out": "", "timeout": timeout}
            time.sleep(0.01)
        wall = time.perf_counter() - tic
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        text = out.read().decode()
    return {"wall": wall, "peak_mb": usage.ru_maxrss / 1024, "exit": proc.returncode,
            "out": text, "cpu": usage.ru_utime + usage.ru_stime}  # its workers' included


def fastest(code: Path, args: list[str], repeats: int) -> dict:
    """The fastest of `repeats` runs (the machine is shared: the least disturbed one)."""
    runs = [run(code, args, timeout=600) for _ in range(repeats)]
    done = [r for r in runs if r["wall"] is not None]
    return min(done, key=lambda r: r["wall"]) if done else runs[0]


def row_spec(folder: Path, stages: int) -> Path:
    text = SPEC.read_text().replace("stages = 6", f"stages = {stages}")
    path = folder / f"robust_{stages}.toml"
    path.write_text(text)
    return path


def tolerance_of(result: dict) -> float | None:
    try:
        return json.loads(result["out"])["tolerance"]["dx"]
    except (ValueError, KeyError, TypeError):
        return None


def optimize_rows(stages_list, base: Path, old_max: int, folder: Path) -> list[dict]:
    rows = []
    for n in stages_list:
        spec = row_spec(folder, n)
        args = ["optimize", str(spec), "--format", "json"]
        repeats = REPEATS if n <= REPEAT_MAX else 1
        new = fastest(REPO, args, repeats)
        old = fastest(base, args, repeats) if n <= old_max else None
        rows.append({"stages": n, "new": new, "old": old, "load": os.getloadavg()[0]})
        print(f"stages {n}: new {fmt(new['wall'])} s {fmt(new['peak_mb'])} MB tol "
              f"{tolerance_of(new)}; old "
              + (f"{fmt(old['wall'])} s {fmt(old['peak_mb'])} MB tol {tolerance_of(old)}"
                 if old else "not run") + f"; load {rows[-1]['load']:.1f}", flush=True)
    return rows


def table_run(code: Path, points: int, folder: Path, label: str) -> dict:
    """A table of `points` robust-optimised points: mass_ratio x friction, 2 workers."""
    side = max(1, round(points ** 0.5))
    out = folder / f"table_{label}"
    args = ["table", str(SPEC), "--sweep", f"mass_ratio=8:12:{side}",
            "--sweep", f"friction=0.7:0.9:{side}", "--workers", "2", "--out", str(out),
            "--no-plots"]
    result = run(code, args, timeout=3600)
    result["points"] = side * side
    result["csv"] = out / "table.csv"
    return result


def agreement(csv_path: Path, sample: int) -> dict:
    """`sample` random rows of a table (seed 0) against `optimize` of their points, each
    solved alone in this process from every start (its own NLP, not the table's): how many
    agree (alpha and beta within 1e-5 rad, the box within 1e-6 of itself, the same status: what
    tests/test_sweep.py asks of a row and its point solved alone) and the largest differences."""
    import csv
    import random

    sys.path.insert(0, str(REPO))
    from pdm_design.api import design
    from pdm_design.spec import parse_spec, read_spec_data

    rows = list(csv.DictReader(csv_path.open()))
    chosen = random.Random(0).sample(rows, min(sample, len(rows)))
    data = read_spec_data(SPEC)
    worst = {"alpha": 0.0, "beta": 0.0, "tolerance": 0.0}
    agree = 0
    for row in chosen:
        data["design"]["mass_ratio"] = float(row["design.mass_ratio"])
        data["scene"]["palm"]["friction"] = float(row["scene.palm.friction"])
        alone = design(parse_spec(data, "point"))
        diffs = {n: abs(float(row[n]) - alone.analysis.design[n]) for n in ("alpha", "beta")}
        diffs["tolerance"] = abs(float(row["tolerance"]) / alone.tolerance["dx"] - 1.0)
        for n, d in diffs.items():
            worst[n] = max(worst[n], d)
        agree += (row["status"] == alone.status.value and diffs["alpha"] <= 1e-5
                  and diffs["beta"] <= 1e-5 and diffs["tolerance"] <= 1e-6)
    return {"rows": len(chosen), "agree": agree, "worst": worst}


# where a table point's time goes: (label, the function whose cumulative time it is)
PHASES = (
    ("formulate the NLP (CasADi expressions)", "formulation/build.py", "formulate"),
    ("create IPOPT solvers (nlpsol: derivatives)", "casadi.py", "nlpsol"),
    ("IPOPT: the 8 starts, stacked (a chain's first point)", "solve/stacked.py",
     "solve_stacked"),
    ("IPOPT: the optima of the point before, continued", "solve/optimize.py", "_continue"),
    ("tie-break (its bound, and its run where that does not settle it)", "solve/tiebreak.py",
     "nearest_optimum"),
    ("stage-map check of the box (256 samples)", "solve/check.py", "sampled_offsets_check"),
    ("simulator: nominal, corners, random builds", "api.py", "_verify_with_box"),
)


def profile_points(count: int) -> dict:
    """cProfile of `count` table points solved in this process along the table's chains (two
    points solved before, unprofiled): the point's mean time and each phase's (ms)."""
    import cProfile
    import pstats

    sys.path.insert(0, str(REPO))
    from pdm_design.spec import parse_spec, read_spec_data
    from pdm_design.sweep.grid import chains, grid_points, sweep_axes
    from pdm_design.sweep.run import DEFAULT_CHAIN, PointTask, solve_point

    data = read_spec_data(SPEC)
    axes = sweep_axes(data, ["mass_ratio=8:12:10", "friction=0.7:0.9:10"])
    paths = tuple(a.path for a in axes)
    points = grid_points(axes)
    parse_spec(data, str(SPEC))

    def solve(chosen):  # along the table's chains: each later point continued
        for chain in chains(chosen, DEFAULT_CHAIN):
            optima = ()
            for i in chain:
                optima = solve_point(PointTask(data, str(SPEC), paths, chosen[i].values,
                                               continued=optima)).get("optima", ())

    solve(points[-2:])
    profiler = cProfile.Profile()
    tic = time.perf_counter()
    profiler.runcall(solve, points[:count])
    total = time.perf_counter() - tic
    stats = pstats.Stats(profiler).stats
    out = {"point": 1e3 * total / count}
    for label, where, name in PHASES:
        out[label] = 1e3 * sum(v[3] for (f, _, n), v in stats.items()
                               if n == name and f.endswith(where)) / count
    return out


def profile_lines(profile: dict, count: int) -> list[str]:
    lines = ["", f"Where a point's time goes (`--profile {count}`: cProfile of {count} points "
             "in one process, no workers; ms a point, profiler overhead included):", "",
             "| phase | ms a point |", "|---|---|"]
    lines += [f"| {k} | {v:.0f} |" for k, v in profile.items() if k != "point"]
    lines.append(f"| whole point | {profile['point']:.0f} |")
    return lines


def fmt(v, digits=2):
    return "-" if v is None else f"{v:.{digits}f}"


def verdict(value, target):
    if target is None:
        return ""
    if value is None:
        return "not measured"
    return "met" if value <= target else "missed"


def write_markdown(rows, tables, args, quick: bool) -> None:
    load = os.getloadavg()
    lines = [
        "# Long rows at scale",
        "",
        f"Command: `python results/bench_scale.py{''.join(' ' + a for a in sys.argv[1:])}` "
        f"(old code: {args.base_label}). Each figure is one fresh process "
        "(`python -m pdm_design optimize SPEC --format json`; the fastest of "
        f"{REPEATS} up to {REPEAT_MAX} stages) on "
        "`problems/manipulators_robust.toml` with only `[verification] stages` changed: wall "
        "time end to end and peak resident memory (os.wait4). The machine is shared: load "
        f"average at the end {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} on {os.cpu_count()} "
        "cores, so times are upper bounds; old and new run alternately, under the same load. "
        "Bytecode is cached, as an installed package has it (the first of the repeated runs "
        "writes it). "
        "The tolerances differ where the new landing-drift bound (docs/optimizer.md section 4) "
        "gives a larger sound box.",
        "",
        "| stages | wall (s) | peak (MB) | tolerance (mm) | old wall (s) | old peak (MB) | "
        "old tolerance (mm) | target | verdict |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        new, old, n = r["new"], r["old"], r["stages"]
        t_wall, t_mem = TARGETS.get(n, (None, None))
        target = ("" if t_wall is None else f"<= {t_wall:g} s"
                  + (f", <= {t_mem:g} MB" if t_mem else ""))
        ok = [verdict(new["wall"], t_wall)] + ([verdict(new["peak_mb"], t_mem)] if t_mem else [])
        tol = tolerance_of(new)
        old_tol = tolerance_of(old) if old else None
        lines.append(
            f"| {n} | {fmt(new['wall'])} | {fmt(new['peak_mb'], 0)} | "
            f"{fmt(tol and tol * 1e3)} | {fmt(old and old['wall'])} | "
            f"{fmt(old and old['peak_mb'], 0)} | {fmt(old_tol and old_tol * 1e3)} | {target} | "
            f"{', '.join(v for v in ok if v)} |")
    lines += table_lines(tables)
    lines += ["", "![wall time and peak memory against stages](scale.png)", ""]
    (HERE / "bench_scale.md").write_text("\n".join(lines))


def table_lines(tables) -> list[str]:
    if not tables:
        return []
    load = os.getloadavg()
    profile, count = tables.pop("profile", None), tables.pop("profile_count", 0)
    agreed = tables.pop("agreement", None)
    lines = ["", TABLE_HEADING, "",
             f"Command: `python results/bench_scale.py{''.join(' ' + a for a in sys.argv[1:])}`. "
             f"Load average at the end of the tables: {load[0]:.1f} / {load[1]:.1f} / "
             f"{load[2]:.1f} on {os.cpu_count()} cores.", "",
             "| code | points | wall (s) | per point (ms) | CPU a point (ms) | exit |",
             "|---|---|---|---|---|---|"]
    for label, t in tables.items():
        per = None if t["wall"] is None else 1e3 * t["wall"] / t["points"]
        cpu = None if t["wall"] is None else 1e3 * t["cpu"] / t["points"]
        lines.append(f"| {label} | {t['points']} | {fmt(t['wall'])} | {fmt(per, 0)} | "
                     f"{fmt(cpu, 0)} | {t['exit']} |")
    done = [t for label, t in tables.items() if label.startswith("new") and t["wall"]]
    new = min(done, key=lambda t: t["wall"] / t["points"], default=None)  # the least loaded
    if new:
        rate = new["wall"] / new["points"] * TABLE_TARGET[0]
        idle = new["cpu"] / new["points"] * TABLE_TARGET[0] / 2  # 2 workers, 2 free cores
        lines += ["", f"Target: {TABLE_TARGET[0]} points in <= {TABLE_TARGET[1]:g} s; at this "
                  f"run's rate {rate:.0f} s ({verdict(rate, TABLE_TARGET[1])}); at its CPU a "
                  f"point on 2 cores of its own {idle:.0f} s ({verdict(idle, TABLE_TARGET[1])}).",
                  "", TABLE_NOTE]
    if agreed:
        w = agreed["worst"]
        lines += ["", f"Rows against `optimize` of their points: {agreed['agree']} of "
                  f"{agreed['rows']} random rows of the new table (seed 0) agree with their point "
                  "solved alone from every start on its own NLP (the same status, alpha and beta "
                  "within 1e-5 rad, the box within 1e-6 of itself); largest differences: alpha "
                  f"{w['alpha']:.1e} rad, beta {w['beta']:.1e} rad, box {w['tolerance']:.1e} of "
                  "itself."]
    if profile:
        lines += profile_lines(profile, count)
    return lines


def rewrite_tables(tables) -> None:
    """Replace the table section of results/bench_scale.md (--table-only)."""
    path = HERE / "bench_scale.md"
    text = path.read_text()
    head, _, rest = text.partition("\n" + TABLE_HEADING)
    plot_line = "![wall time and peak memory against stages]"
    tail = rest[rest.index(plot_line):] if plot_line in rest else plot_line + "(scale.png)\n"
    path.write_text(head.rstrip("\n") + "\n" + "\n".join(table_lines(tables)) + "\n\n" + tail)


def plot(rows) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(10, 4))
    for key, style in (("new", "o-"), ("old", "s--")):
        pts = [(r["stages"], r[key]) for r in rows if r[key] and r[key]["wall"] is not None]
        if not pts:
            continue
        ax_t.loglog([n for n, _ in pts], [p["wall"] for _, p in pts], style, label=key)
        ax_m.loglog([n for n, _ in pts], [p["peak_mb"] for _, p in pts], style, label=key)
    for i, (n, (t, m)) in enumerate(TARGETS.items()):
        ax_t.plot(n, t, "rv", label="target (at most)" if i == 0 else None)
        if m:
            ax_m.plot(n, m, "rv", label="target (at most)" if n == 1000 else None)
    ax_t.text(300, ax_t.get_ylim()[0] * 1.2, "old at 300: no cvxpy sets beyond 128 stages",
              fontsize=7)
    ax_t.set(xlabel="stages", ylabel="wall time (s)", title="optimize, end to end")
    ax_m.set(xlabel="stages", ylabel="peak memory (MB)", title="peak resident memory")
    for ax in (ax_t, ax_m):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(HERE / "scale.png", dpi=100)


ROUND1 = "a6ce8ef7f9628524a938f6a2ab86012c374433d2"  # the code before long rows were reworked


def round1_checkout(folder: Path) -> Path:
    """Round 1's pdm_design (commit ROUND1), extracted from the repository's history."""
    out = folder / "round1"
    out.mkdir()
    archive = subprocess.run(["git", "-C", str(REPO), "archive", ROUND1, "pdm_design"],
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(out)], input=archive, check=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--base", type=Path, default=None)
    parser.add_argument("--old-max", type=int, default=1000)
    parser.add_argument("--table-points", type=int, default=None)
    parser.add_argument("--before", type=Path, default=None)
    parser.add_argument("--table-only", action="store_true")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--profile", type=int, default=0, metavar="POINTS")
    args = parser.parse_args()
    stages = [6, 100, 1000] if args.quick else [6, 20, 100, 300, 1000, 3000, 10000]
    points = args.table_points or (100 if args.quick else TABLE_TARGET[0])
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        args.base_label = f"`{args.base}`" if args.base else f"round 1's, commit {ROUND1[:7]}"
        if args.base is None:
            args.base = round1_checkout(folder)
        rows = [] if args.table_only else optimize_rows(stages, args.base, args.old_max, folder)
        runs = [("new", REPO, points)]
        if args.before is not None:  # alternately, under the same load
            runs = [("new", REPO, points), ("before", args.before, points)] * args.repeat
        if args.base.exists():
            runs.append(("old", args.base, min(points, 100)))
        tables = {}
        for i, (label, code, count) in enumerate(runs):
            name = label if runs.count(runs[i]) == 1 else f"{label} ({runs[:i].count(runs[i]) + 1})"
            tables[name] = table_run(code, count, folder, label)
            print(f"table {name}: {tables[name]}", flush=True)
        new = tables.get("new")
        if new and new.get("exit") == 0:
            tables["agreement"] = agreement(new["csv"], AGREEMENT_SAMPLE)
            print(f"agreement: {tables['agreement']}", flush=True)
    for t in tables.values():
        t.pop("out", None)
        t.pop("csv", None)
    if args.profile:
        tables["profile"] = profile_points(args.profile)
        tables["profile_count"] = args.profile
        print(f"profile: {tables['profile']}", flush=True)
    if args.table_only:
        rewrite_tables(tables)
        return
    write_markdown(rows, tables, args, args.quick)
    plot(rows)


if __name__ == "__main__":
    main()
