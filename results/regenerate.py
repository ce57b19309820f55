"""Regenerate the results that the `table`, `sheet` and `optimize` commands produce:

    results/paper/    the paper reproduction: `pdm-design optimize --format json` of the three
                      paper specs, and comparison.md against the paper's numbers
    results/tables/   one design table per scene (`pdm-design table`)
    results/sheets/   build sheets of the shipped problems that work (`pdm-design sheet`):
                      Markdown, CSV, the drawing (PNG, SVG, PDF) and the DXF
    results/reports/  report pages (`pdm-design report`) and a screenshot of each as headless
                      Chromium renders it (when playwright and Chromium are installed)
    results/bench_sweep.md   sweep throughput (designs per second) at 1 and 2 workers

Run from anywhere (it works in the repository's root):

    python results/regenerate.py            # everything
    python results/regenerate.py paper tables sheets reports bench   # or some of it

Every output comes from the command line, exactly as a user would run it (the commands are
printed as they run and written into the outputs).
"""

from __future__ import annotations

import json
import math
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
PAPER_SPECS = ("paper_stairs_frictionless", "paper_stairs_friction", "paper_manipulators")
OPTIMISED_SPECS = ("manipulators_robust", "manipulators_robust_all_free", "stairs_design",
                   "manipulators_long_row")
REPORT_SPECS = ("manipulators_robust", "manipulators_long_row", "stairs_design",
                "rimless_wheel_ramp", "compass_gait_ramp")
TABLES = {  # folder: (spec, sweeps)
    "manipulators_mass_ratio": ("problems/paper_manipulators.toml", ["mass_ratio=1:30:30"]),
    "manipulators_alpha_beta": ("problems/paper_manipulators.toml",
                                ["alpha=0.05:0.35:7", "beta=0.4:0.8:5"]),
    "stairs_restitution": ("problems/paper_stairs_frictionless.toml",
                           ["restitution=0.3:0.95:14"]),
    "stairs_friction_restitution": ("problems/paper_stairs_friction.toml",
                                    ["restitution=0.3:0.95:14"]),
    # optimised: alpha and beta (manipulators), launch speed and landing offset (stairs) free,
    # objective max_offset_tolerance
    "manipulators_robust_mass_ratio": ("problems/manipulators_robust.toml",
                                       ["mass_ratio=2:20:10"]),
    "stairs_design_restitution": ("problems/stairs_design.toml", ["restitution=0.5:0.9:9"]),
}
BENCH_SPEC = "problems/paper_manipulators.toml"
BENCH_WORKLOADS = {  # name: (spec, verification stages or None: as shipped, sweeps)
    "light": (BENCH_SPEC, None, ["mass_ratio=2:30:20", "friction=0.5:1.0:6"]),
    "heavy": (BENCH_SPEC, 3000, ["mass_ratio=2:30:8", "friction=0.8:1.0:2"]),
    "optimised": ("problems/manipulators_robust.toml", None, ["mass_ratio=2:30:8"]),
}
BENCH_REPEATS = 3


def cli(*args: str, capture: bool = False) -> str:
    """Run `pdm-design ARGS` in the repository root (exit 0 and 1 are both results)."""
    command = [sys.executable, "-m", "pdm_design", *args]
    print("$ pdm-design " + " ".join(args), flush=True)
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "PYTHONHASHSEED": "0"})
    if done.returncode not in (0, 1):
        sys.exit(f"failed ({done.returncode}): {' '.join(args)}\n{done.stderr}")
    return done.stdout if capture else ""


def write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


# --------------------------------------------------------------------------- paper

def paper() -> None:
    out = RESULTS / "paper"
    docs = {}
    for name in PAPER_SPECS:
        text = cli("optimize", f"problems/{name}.toml", "--format", "json", capture=True)
        write(out / f"{name}.json", text)
        docs[name] = json.loads(text)
    sim = json.loads(cli("simulate", "problems/paper_manipulators.toml", "--stages", "30",
                         "--format", "json", capture=True))
    write(out / "comparison.md", comparison(docs, sim))


def comparison(docs: dict, sim: dict) -> str:
    g, a, b, l, q = 9.81, 0.2, 0.6, 2.0, 10.0
    k = q / (1 + q)
    drop = 2 * g * l * (math.cos(a) - math.cos(b))
    corrected = math.sqrt(drop / (1 - (k * math.cos(a + b)) ** 2))
    papers = math.sqrt(drop / (1 - (k * math.cos(b - a)) ** 2))  # the paper's eq. 28
    speeds = [s["handover_speed"] for s in sim["stages"] if s.get("handover_speed")]
    m = docs["paper_manipulators"]
    f0, f1 = docs["paper_stairs_frictionless"], docs["paper_stairs_friction"]
    rows = [
        ("1 frictionless stairs", "rise h (m)", "0.36", f0["geometry"]["rise"]),
        ("1 frictionless stairs", "tread d (m)", "1.626", f0["geometry"]["tread"]),
        ("2 stairs with friction", "rise h (m)", "0.36", f1["geometry"]["rise"]),
        ("2 stairs with friction", "tread d (m)", "1.565", f1["geometry"]["tread"]),
        ("3 manipulators", "pitch x (m)", "1.5266", m["geometry"]["pitch_x"]),
        ("3 manipulators", "pitch y, down (m)", "0.3095", m["geometry"]["pitch_y"]),
        ("3 manipulators", "periodic handover speed (m/s)", f"{papers:.4f} (eq. 28)",
         m["periodic"]["handover_speed"]),
    ]
    lines = [
        "# The paper's examples, reproduced",
        "",
        "Generated by `python results/regenerate.py paper` (do not edit by hand) from",
        "`pdm-design optimize problems/NAME.toml --format json` (the JSON files beside this) and",
        "`pdm-design simulate problems/paper_manipulators.toml --stages 30 --format json`.",
        "",
        "| example | quantity | paper | pdm-design |",
        "|---|---|---|---|",
        *(f"| {e} | {what} | {paper} | {ours:.6g} |" for e, what, paper, ours in rows),
        "",
        "The paper's handover-speed fixed point (eq. 28) projects the handover velocity on the",
        "next palm's tangent with cos(beta - alpha); the angle between them is alpha + beta",
        f"(docs/physics.md). With cos(alpha + beta) the fixed point is {corrected:.4f} m/s,",
        f"against {papers:.3f} m/s from the paper's formula. The event simulator (which assumes",
        "no fixed point) settles on the corrected value: its handover speeds over 30",
        f"manipulators go {speeds[0]:.4f}, {speeds[1]:.4f}, {speeds[2]:.4f}, ... "
        f"{speeds[-1]:.6f} m/s",
        f"(contraction factor {m['periodic']['contraction']:.4f} per stage).",
        "",
        "Statuses: " + ", ".join(f"{n}: {d['status']}" for n, d in docs.items()) + ".",
    ]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- tables, sheets

def tables() -> None:
    for folder, (spec, sweeps) in TABLES.items():
        out = RESULTS / "tables" / folder
        shutil.rmtree(out, ignore_errors=True)
        cli("table", spec, *(f"--sweep={s}" for s in sweeps), "--out", str(out.relative_to(ROOT)))


def _shipped(names):
    """The names whose spec is in problems/ (a spec not there yet is skipped, and said so)."""
    for name in names:
        if (ROOT / "problems" / f"{name}.toml").is_file():
            yield name
        else:
            print(f"(skipped: problems/{name}.toml does not exist)", flush=True)


def sheets() -> None:
    for name in _shipped((*PAPER_SPECS, *OPTIMISED_SPECS)):
        out = RESULTS / "sheets" / name
        shutil.rmtree(out, ignore_errors=True)
        cli("sheet", f"problems/{name}.toml", "--out", str(out.relative_to(ROOT)))


def reports() -> None:
    for name in _shipped(REPORT_SPECS):
        out = RESULTS / "reports" / name
        shutil.rmtree(out, ignore_errors=True)
        cli("report", f"problems/{name}.toml", "--out", str(out.relative_to(ROOT)))
        _screenshot(out / "report.html", out / "screenshot.png")


def _screenshot(page: Path, png: Path) -> None:
    """The page as headless Chromium shows it 1.5 s after loading (the animation playing)."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        print("(no screenshot: the playwright package is not installed)", flush=True)
        return
    flags = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync"]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=shutil.which("chromium") or
                                    "/usr/bin/chromium", args=flags)
        tab = browser.new_page(viewport={"width": 1200, "height": 900})
        tab.goto(page.resolve().as_uri())
        tab.wait_for_timeout(1500)
        tab.screenshot(path=str(png))
        browser.close()


# --------------------------------------------------------------------------- benchmark

def bench() -> None:
    """Designs per second of two sweeps at 1 and 2 workers, measured in this run."""
    import tempfile

    results: dict[str, dict[int, list[float]]] = {}
    points = {}
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        for name, (source, stages, sweeps) in BENCH_WORKLOADS.items():
            spec = Path(tmp) / f"bench_{name}.toml"
            text = (ROOT / source).read_text()
            if stages is not None:
                text = text.replace("stages = 6 ", f"stages = {stages} ", 1)
            spec.write_text(text)
            points[name] = math.prod(int(s.rsplit(":", 1)[1]) for s in sweeps)
            results[name] = {}
            for workers in (1, 2):
                times = []
                for repeat in range(BENCH_REPEATS):
                    out = Path(tmp) / f"{name}-w{workers}-{repeat}"
                    args = ["table", str(spec), *(f"--sweep={s}" for s in sweeps),
                            "--workers", str(workers), "--chain", "1", "--no-plots",
                            "--out", str(out)]
                    start = time.perf_counter()
                    cli(*args)
                    times.append(time.perf_counter() - start)
                results[name][workers] = times
    _bench_figure(results, points, RESULTS / "bench_sweep.png")
    lines = [
        "# Sweep throughput",
        "",
        "Generated by `python results/regenerate.py bench` (do not edit by hand), all numbers",
        "from one run. Each time is the wall time of the whole command (Python start-up,",
        "reading the spec, starting the worker processes and writing the table included), for",
        "a fresh output folder:",
        "",
        "    pdm-design table SPEC --sweep ... --workers N --chain 1 --no-plots --out DIR",
        "",
        "SPEC is the spec named below, with `[verification] stages` changed where the",
        "stages column says so; each grid point is solved by `pdm_design.api.design`: closed",
        "forms then the event simulator's verification over that many manipulators (light,",
        "heavy), or the IPOPT multistart optimisation of alpha and beta for the largest pivot",
        "tolerance then the simulator's check of the design and of its tolerance box",
        f"(optimised). Best of {BENCH_REPEATS} runs; every run is listed.",
        "",
        "| workload | spec | stages | sweeps | points | workers | wall time (s), best | "
        "all runs (s) | designs per second | speed-up |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, (source, stages, sweeps) in BENCH_WORKLOADS.items():
        best = {w: min(t) for w, t in results[name].items()}
        for w, t in results[name].items():
            lines.append(
                f"| {name} | `{source}` | {stages or 'as shipped'} | "
                f"{' '.join(f'`{s}`' for s in sweeps)} | {points[name]} "
                f"| {w} | {best[w]:.2f} | {', '.join(f'{x:.2f}' for x in t)} | "
                f"{points[name] / best[w]:.1f} | {best[1] / best[w]:.2f} |")
    per = {name: min(results[name][1]) / points[name] for name in results}
    gain = {name: min(results[name][1]) / min(results[name][2]) for name in results}
    busy = load_before > 0.5
    lines += [
        "",
        "Speed-up with a second worker: " + ", ".join(
            f"{name} {gain[name]:.2f} ({per[name]:.3f} s per design at one worker, fixed "
            "costs included)" for name in results) + ". Starting the worker processes and "
        "handing each point to them costs a few tenths of a second per command, which light "
        "designs (milliseconds each) barely amortise; heavier ones can gain up to the number "
        "of idle cores (2 here)."
        + (" The machine was not idle when the measurements started (load average below; "
           "other jobs, or an earlier run decaying from the 1-minute average): a busy core "
           "lowers the speed-up; the spread of the runs in one row shows the noise."
           if busy else ""),
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python "
        f"{platform.python_version()}, {platform.system()}; 1-minute load average just "
        f"before the measurements (other jobs): {load_before:.2f}.",
        "",
        "![throughput](bench_sweep.png)",
    ]
    write(RESULTS / "bench_sweep.md", "\n".join(lines) + "\n")


def _bench_figure(results, points, path):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(3.0 * len(results), 3.0), layout="constrained")
    for ax, (name, runs) in zip(figure.subplots(1, len(results), squeeze=False)[0],
                                results.items()):
        workers = sorted(runs)
        ax.bar([str(w) for w in workers], [points[name] / min(runs[w]) for w in workers],
               color="tab:blue")
        for w in workers:
            ax.plot([str(w)] * len(runs[w]), [points[name] / t for t in runs[w]], "k.",
                    markersize=4)
        ax.set_xlabel("local worker processes")
        ax.set_ylabel("designs per second")
        ax.set_title(f"{name}: {points[name]} points", fontsize=9)
    FigureCanvasAgg(figure)
    figure.savefig(path, dpi=110, metadata={"Software": None})


STEPS = {"paper": paper, "tables": tables, "sheets": sheets, "reports": reports, "bench": bench}

if __name__ == "__main__":
    chosen = sys.argv[1:] or list(STEPS)
    unknown = [c for c in chosen if c not in STEPS]
    if unknown:
        sys.exit(f"unknown step(s) {unknown}; choose from {list(STEPS)}")
    for step in chosen:
        tic = time.perf_counter()
        STEPS[step]()
        print(f"[{step}: {time.perf_counter() - tic:.1f} s]", flush=True)
