"""Speed against accuracy, measured: for each scene and each accuracy preset (plus a ladder of
custom tolerances that draws the curve), the wall time of a run against its error relative to a
high-precision reference computed independently. Writes results/accuracy.md and
results/accuracy.png (not a test; see tests/ for the asserted tolerances).

    python results/bench_accuracy.py           # about two minutes
    python results/bench_accuracy.py --quick   # fewer repeats, shorter ladder

Scenes and their references:
  stairs-1      paper example 1 (frictionless, eps 0.8), 200 bounces. Closed forms: impact speed
                hypot(V0, sqrt(2 g h0)), impact times t1 + (k-1)(1+eps) v*/g, landing at tread/2.
  stairs-2      paper example 2 (friction, spin, radius 0.5 m), 200 bounces. Closed forms: the
                rolling impact vx1 = (m r^2 V0 - J r w0)/(m r^2 + J), then the same orbit.
  manip-stick   paper example 3, 12 manipulators (stuck carries: closed form + root finding).
                Closed forms: ballistic first landing, momentum landing u = q/(1+q) V.t(-alpha),
                handover speeds s^2 = u^2 + 2 g l (cos a - cos b), carry times by mpmath
                quadrature at 30 digits (the simulator uses Carlson's R_F).
  manip-slide   the same with friction 0.3: every carry slips at tan th = mu and slides to the
                handover (solve_ivp). Reference: the simulator at rtol 2.2e-14 (its floor, 45x
                tighter than `precise`); its first sliding phase is checked against an
                independent Newton-Euler integration (3x3 solve per step, DOP853 at 2.2e-14).
  manip-bounce  the same with restitution 0.3: the object bounces on the moving palm
                (solve_ivp). Reference: the simulator at rtol 2.2e-14.
  optimizer     min drop with beta free and the over-the-top margin 0.5 (tests/test_optimize.py):
                beta* from brentq on the closed form; IPOPT at tol 1e-4 .. 1e-12 (the presets'
                proposed tolerances marked).
"""

from __future__ import annotations

import argparse
import math
import platform
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pdm_design.accuracy import ACCURACY_PRESETS, MIN_RTOL, Accuracy  # noqa: E402
from pdm_design.api import SOLVE_PRESETS  # noqa: E402
from pdm_design.io import atomic_path, write_atomic  # noqa: E402

G = 9.81
PRESET_COLOURS = {"fast": "tab:red", "default": "tab:blue", "precise": "tab:green"}
# IPOPT's tol per preset, as pdm_design.api wires it (measured below)
NLP_TOL = {name: preset["tol"] for name, preset in SOLVE_PRESETS.items()}


def ladder(quick: bool) -> list[Accuracy]:
    exps = range(4, 14, 2 if quick else 1)
    out = []
    for k in exps:
        rtol = max(10.0 ** -k, MIN_RTOL)
        out.append(Accuracy(f"rtol 1e-{k}", rtol=rtol, atol=rtol * 1e-2, event_tol=rtol * 0.1))
    return out


def timed(fn, *, min_time=0.3, min_runs=3, max_runs=50):
    """Median wall time of fn() (after one warm-up call) and its last result."""
    out = fn()
    times = []
    start = time.perf_counter()
    while len(times) < min_runs or (time.perf_counter() - start < min_time
                                    and len(times) < max_runs):
        tic = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - tic)
    return statistics.median(times), out


# ------------------------------------------------------------------ metrics

def max_rel(values, reference):
    v, r = np.asarray(values, float), np.asarray(reference, float)
    n = min(len(v), len(r))
    if n == 0 or len(v) != len(r):
        return math.nan
    return float(np.max(np.abs(v[:n] - r[:n]) / np.abs(r[:n])))


def max_abs(values, reference):
    v, r = np.asarray(values, float), np.asarray(reference, float)
    if len(v) != len(r) or len(v) == 0:
        return math.nan
    return float(np.max(np.abs(v - r)))


@dataclass
class Scene:
    name: str
    title: str
    run: object            # accuracy -> metrics dict (speed, times, positions: lists)
    reference: dict
    reference_note: str
    speed_label: str


# ------------------------------------------------------------------ stairs

def stairs_scene(which: str, bounces: int) -> Scene:
    from pdm_design.scenes.stairs.sim import simulate_stairs
    from pdm_design.spec import load_spec

    spec = load_spec(ROOT / "problems" / f"paper_stairs_{which}.toml")
    scene, design = spec.scene, spec.design_at()
    g, h0, eps, v0 = scene.gravity, scene.initial.drop_height, design.restitution, \
        design.launch_speed
    ball, w0 = scene.ball, scene.initial.spin
    v_star = math.sqrt(2 * g * h0)
    if scene.friction > 0:
        mr2 = ball.mass * ball.radius ** 2
        vx1 = (mr2 * v0 - ball.inertia * ball.radius * w0) / (mr2 + ball.inertia)
    else:
        vx1 = v0
    flight = (1 + eps) * v_star / g
    tread = vx1 * flight
    t1 = math.sqrt(2 * h0 / g)
    reference = {
        "speed": [math.hypot(v0, v_star)] + [math.hypot(vx1, v_star)] * (bounces - 1),
        "times": [t1 + k * flight for k in range(bounces)],
        "positions": [tread / 2] * bounces,
    }

    def run(acc):
        result = simulate_stairs(scene, design, stages=bounces, accuracy=acc)
        st = result.stages
        return {"speed": [s["impact_speed"] for s in st], "times": [s["impact_time"] for s in st],
                "positions": [s["landing_x"] for s in st]}

    title = ("stairs, paper ex. 1 (frictionless)" if which == "frictionless"
             else "stairs, paper ex. 2 (friction, spin)")
    return Scene(f"stairs-{'1' if which == 'frictionless' else '2'}", title, run, reference,
                 "closed forms", "impact speed")


# ------------------------------------------------------------------ manipulators

def paper_manipulators(friction=None, restitution=None):
    from pdm_design.scenes.manipulators.model import ManipulatorsScene, Palm
    from pdm_design.spec import load_spec

    spec = load_spec(ROOT / "problems" / "paper_manipulators.toml")
    scene, design = spec.scene, spec.design_at()
    palm = scene.palm
    palm = Palm(width=palm.width, thickness=palm.thickness,
                friction=palm.friction if friction is None else friction,
                restitution=palm.restitution if restitution is None else restitution,
                front_stop=palm.front_stop)
    return ManipulatorsScene(body=scene.body, palm=palm, initial=scene.initial,
                             gravity=scene.gravity), design


def manip_metrics(result):
    st = result.stages
    speeds = [s["handover_speed"] for s in st if s["handover_speed"] is not None]
    times = [t for s in st for t in (s["landing_time"], s["handover_time"]) if t is not None]
    positions = [s["landing_offset"] for s in st]
    return {"speed": speeds, "times": times, "positions": positions,
            "completed": result.outcome.completed}


def mp_carry_time(u, alpha, beta, g, l):
    import mpmath

    mpmath.mp.dps = 30
    a, b, u, g, l = (mpmath.mpf(x) for x in (alpha, beta, u, g, l))

    def rate(th):
        return l / mpmath.sqrt(u ** 2 + 2 * g * l * (mpmath.cos(a) - mpmath.cos(th)))

    return float(mpmath.quad(rate, [-a, 0, b]))


def manip_stick_scene(stages: int) -> Scene:
    from pdm_design.scenes.manipulators.sim import simulate_manipulators

    scene, design = paper_manipulators()
    g, l, a, b, q = scene.gravity, design.link_length, design.alpha, design.beta, \
        design.mass_ratio
    (x0, y0), (vx0, vy0) = scene.initial.position, scene.initial.velocity
    drop = y0 - (design.first_pivot_y + l * math.cos(a))
    t_land = (vy0 + math.sqrt(vy0 ** 2 + 2 * g * drop)) / g
    vx, vy = vx0, vy0 - g * t_land
    offset = x0 + vx0 * t_land - (design.first_pivot_x - l * math.sin(a))
    k = q / (1 + q)
    u = k * (vx * math.cos(a) + vy * math.sin(a))
    speeds, times, t = [], [t_land], t_land
    for i in range(stages):
        s = math.sqrt(u * u + 2 * g * l * (math.cos(a) - math.cos(b)))
        t += mp_carry_time(u, a, b, g, l)
        if i < stages - 1:
            speeds.append(s)
            times += [t, t]  # handover k = landing k+1
        else:
            times.append(t)  # completion at beta on the last manipulator
        u = k * s * math.cos(a + b)
    reference = {"speed": speeds, "times": times, "positions": [offset] * stages}

    def run(acc):
        result = simulate_manipulators(scene, design, stages=stages, accuracy=acc)
        m = manip_metrics(result)
        st = result.stages
        m["times"] = [t for s in st for t in (s["landing_time"], s["handover_time"])
                      if t is not None] + ([result.events[-1].time]
                                           if result.outcome.completed else [])
        return m

    return Scene("manip-stick", f"manipulators, paper ex. 3 ({stages} stages, stuck carries)",
                 run, reference, "closed forms + 30-digit quadrature", "handover speed")


TIGHTEST = Accuracy("reference", rtol=MIN_RTOL, atol=1e-16, event_tol=1e-15)


def manip_integrated_scene(name, title, stages, **palm) -> Scene:
    from pdm_design.scenes.manipulators.sim import simulate_manipulators

    scene, design = paper_manipulators(**palm)

    def run(acc):
        return manip_metrics(simulate_manipulators(scene, design, stages=stages, accuracy=acc))

    reference = run(TIGHTEST)
    return Scene(name, title, run, reference, "the simulator at rtol 2.2e-14 (its floor)",
                 "handover speed")


def independent_slide_check():
    """The reference's first sliding phase (friction 0.3) against an independent Newton-Euler
    integration: unknowns (th'', s'', N) from a 3x3 linear solve each step, DOP853 at 2.2e-14,
    handover where th = beta (the next palm's top is pitch_y lower: l cos th = l cos beta)."""
    from scipy.integrate import solve_ivp

    from pdm_design.scenes.manipulators.sim import simulate_manipulators

    scene, design = paper_manipulators(friction=0.3)
    result = simulate_manipulators(scene, design, stages=2, accuracy=TIGHTEST)
    slip = next(e for e in result.events if e.kind == "slip")
    handover = next(e for e in result.events if e.kind == "handover")
    m, q, mu = scene.body.mass, design.mass_ratio, scene.palm.friction
    M, g, l, beta = m / q, scene.gravity, design.link_length, design.beta
    th0, om0 = slip.after["theta"], slip.after["omega"]
    sigma = -1.0 if th0 > 0 else 1.0  # the object slides back down the tilted palm

    def rhs(t, z):
        th, om, s, sd = z
        sn, cs = math.sin(th), math.cos(th)
        # m (l cos th th'' + s'') + sigma mu N = m l sin th om^2      (x, friction -sigma mu N)
        # -m l sin th th'' - N = -m g + m l cos th om^2                (y)
        # M l th'' - sigma mu N cos th - N sin th = M g sin th          (palm, along t)
        a = np.array([[m * l * cs, m, sigma * mu],
                      [-m * l * sn, 0.0, -1.0],
                      [M * l, 0.0, -sigma * mu * cs - sn]])
        rhs_ = np.array([m * l * sn * om * om, -m * g + m * l * cs * om * om, M * g * sn])
        thdd, sdd, _ = np.linalg.solve(a, rhs_)
        return [om, thdd, sd, sdd]

    def reach(t, z):
        return z[0] - beta

    reach.terminal, reach.direction = True, 1
    sol = solve_ivp(rhs, (slip.time, slip.time + 5.0), [th0, om0, slip.after["offset"], 0.0],
                    method="DOP853", rtol=MIN_RTOL, atol=1e-16, events=reach)
    th, om, s, sd = sol.y_events[0][0]
    speed = math.hypot(l * om * math.cos(th) + sd, l * om * math.sin(th))
    return {"time": abs(sol.t_events[0][0] - handover.time),
            "speed": abs(speed - result.stages[0]["handover_speed"]) / speed,
            "sign_held": bool(np.all(np.sign(sol.y[3][1:]) == sigma))}


# ------------------------------------------------------------------ optimizer

def optimizer_rows(tols, *, bound_relax_factor: float):
    """IPOPT tol ladder on a problem with a known optimum, at one bound_relax_factor (IPOPT's
    default 1e-8 relaxes every bound and constraint by 1e-8 relative, which floors the error of
    an optimum on an active constraint at ~1e-8 whatever tol is; the precise preset sets 0)."""
    from scipy.optimize import brentq

    from pdm_design.scenes.manipulators.model import (
        Body,
        ManipulatorsInitial,
        ManipulatorsScene,
        Palm,
    )
    from pdm_design.solve import optimize
    from pdm_design.spec.model import Bounds, Spec

    a, l, k, r = 0.2, 2.0, 10.0 / 11.0, 0.5

    def u_star_sq(b):
        c = (k * math.cos(a + b)) ** 2
        return c * 2 * G * l * (math.cos(a) - math.cos(b)) / (1 - c)

    b_star = brentq(lambda b: u_star_sq(b) * (1 - r) - 2 * G * l * (1 - math.cos(a)),
                    a + 1e-9, 0.6, xtol=1e-15)
    scene = ManipulatorsScene(body=Body(mass=1.0, width=0.4, height=0.2),
                              palm=Palm(width=1.6, friction=0.8),
                              initial=ManipulatorsInitial(position=(-1.25, 3.05),
                                                          velocity=(3.0, 0.0)))
    spec = Spec(source="bench", scene=scene,
                design={"alpha": 0.2, "beta": Bounds(min=0.2, max=1.0, initial=0.8),
                        "link_length": 2.0, "mass_ratio": 10.0},
                objective={"min_drop": 1.0}, requirements={"over_the_top": r})
    optimize(spec, tol=1e-8, linearise=False, check_samples=0)  # build the NLP once
    rows = []
    for tol in tols:
        seconds, res = timed(lambda tol=tol: optimize(
            spec, tol=tol, bound_relax_factor=bound_relax_factor, linearise=False,
            check_samples=0), min_time=0.5)
        beta = res.design["beta"] if res.design else math.nan
        rows.append({"tol": tol, "seconds": seconds, "error": abs(beta - b_star),
                     "status": res.status.name.lower()})
    return rows, b_star


# ------------------------------------------------------------------ driver

def measure(scene: Scene, accuracies, quick):
    rows = []
    for acc in accuracies:
        seconds, m = timed(lambda acc=acc: scene.run(acc), min_time=0.1 if quick else 0.4)
        ref = scene.reference
        rows.append({
            "accuracy": acc.name, "seconds": seconds,
            "speed": max_rel(m["speed"], ref["speed"]),
            "times": max_abs(m["times"], ref["times"]),
            "positions": max_abs(m["positions"], ref["positions"]),
            "completed": m.get("completed", True),
        })
    return rows


def fmt(x, digits=2):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    if x == 0:
        return "0"
    return f"{x:.{digits}e}"


def _time_axis(ax, times):
    """A log time axis at least a factor 4 wide, labelled with plain numbers."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    lo, hi = min(times), max(times)
    if hi / lo < 4:
        mid = math.sqrt(lo * hi)
        lo, hi = mid / 2, mid * 2
    ax.set_xlim(lo / 1.2, hi * 1.2)
    ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


def plot(results, opt_rows, exact_rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(results) + 1
    cols = 3
    fig, axes = plt.subplots((n + cols - 1) // cols, cols, figsize=(13, 7.5))
    axes = axes.ravel()
    floor = 1e-17
    for ax, (scene, rows) in zip(axes, results):
        lad = [r for r in rows if r["accuracy"] not in ACCURACY_PRESETS]
        for key, style, label in (("speed", "o-", scene.speed_label + " (rel.)"),
                                  ("times", "s--", "event times (s)")):
            xs = [1e3 * r["seconds"] for r in lad]
            ys = [max(r[key], floor) for r in lad]
            ax.loglog(xs, ys, style, color="0.55", ms=3, lw=1, label=f"ladder: {label}")
            for r in rows:
                if r["accuracy"] in ACCURACY_PRESETS:
                    ax.loglog(1e3 * r["seconds"], max(r[key], floor),
                              "o" if key == "speed" else "s", ms=8, mfc="none" if key ==
                              "times" else PRESET_COLOURS[r["accuracy"]],
                              color=PRESET_COLOURS[r["accuracy"]])
        same = len({(r["speed"], r["times"]) for r in rows}) == 1
        ax.set_title(scene.title + ("\nevery preset and tolerance: the same answer" if same
                                    else ""), fontsize=9)
        _time_axis(ax, [1e3 * r["seconds"] for r in rows])
        ax.set_xlabel("wall time per run (ms)")
        ax.set_ylabel("max error vs reference")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_ylim(floor / 3, 1e-2)
    ax = axes[len(results)]
    for rows_, style, label in ((opt_rows, "o-", "IPOPT defaults"),
                                (exact_rows, "s--", "bound_relax_factor 0")):
        ax.loglog([1e3 * r["seconds"] for r in rows_], [max(r["error"], floor) for r in rows_],
                  style, color="0.55", ms=3, lw=1, label=label)
        for name, tol in NLP_TOL.items():
            r = next(r for r in rows_ if r["tol"] == tol)
            ax.loglog(1e3 * r["seconds"], max(r["error"], floor), style[0], ms=8,
                      color=PRESET_COLOURS[name])
    ax.legend(fontsize=7)
    ax.set_ylim(floor / 3, 1e-2)
    _time_axis(ax, [1e3 * r["seconds"] for r in opt_rows + exact_rows])
    ax.set_title("optimizer: beta* of min drop (IPOPT tol 1e-4..1e-12)", fontsize=9)
    ax.set_xlabel("wall time per optimize (ms)")
    ax.set_ylabel("|beta - beta*| (rad)")
    ax.grid(True, which="both", alpha=0.3)
    for extra in axes[n:]:
        extra.set_visible(False)
    handles = [plt.Line2D([], [], marker="o", ls="", color=c, label=f"preset {p}")
               for p, c in PRESET_COLOURS.items()]
    handles += [plt.Line2D([], [], marker="o", ls="-", color="0.55", label="tolerance ladder: "
                           "speed (filled) / event times (open)")]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle("Speed against accuracy (errors at 1e-17 are exact to rounding)", fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    quick = args.quick
    tic = time.perf_counter()
    import scipy.integrate  # noqa: F401  (imported by the integrated phases: not timed)

    accuracies = list(ACCURACY_PRESETS.values()) + ladder(quick)
    scenes = [
        stairs_scene("frictionless", 200),
        stairs_scene("friction", 200),
        manip_stick_scene(12),
        manip_integrated_scene("manip-slide", "manipulators, friction 0.3 (sliding carries)",
                               6, friction=0.3),
        manip_integrated_scene("manip-bounce", "manipulators, restitution 0.3 (bouncing)", 6,
                               restitution=0.3),
    ]
    results = [(scene, measure(scene, accuracies, quick)) for scene in scenes]
    check = independent_slide_check()
    opt_tols = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
    opt_rows, b_star = optimizer_rows(opt_tols, bound_relax_factor=1e-8)
    exact_rows, _ = optimizer_rows(opt_tols, bound_relax_factor=0.0)
    plot(results, opt_rows, exact_rows, ROOT / "results" / "accuracy.png")
    write_atomic(ROOT / "results" / "accuracy.md",
                 report(results, opt_rows, exact_rows, b_star, check,
                        time.perf_counter() - tic, quick))
    print(f"wrote results/accuracy.md and results/accuracy.png in "
          f"{time.perf_counter() - tic:.0f} s")


def report(results, opt_rows, exact_rows, b_star, check, seconds, quick):
    lines = [
        "# Speed against accuracy",
        "",
        "Regenerate: `python results/bench_accuracy.py` "
        f"({'--quick, ' if quick else ''}{seconds:.0f} s on this machine: "
        f"{platform.processor() or platform.machine()}, Python {platform.python_version()}).",
        "Each run's wall time (median of repeats, imports excluded) against its largest error",
        "relative to an independent reference. Columns: speed = largest relative error of the",
        "impact speeds (stairs) or handover speeds (manipulators); event times = largest",
        "absolute error of the impact / landing / handover times (s); positions = largest",
        "absolute error of the landing positions on the tread or palm (m). `0` is exact to the",
        "last bit. The ladder rows are custom tolerances (rtol; atol = rtol/100, event_tol =",
        "rtol/10) that draw the curve in `accuracy.png`.",
        "",
        "![speed against accuracy](accuracy.png)",
        "",
        "| preset | rtol | atol | event_tol | agreement demanded by verification |",
        "|---|---|---|---|---|",
    ]
    for acc in ACCURACY_PRESETS.values():
        lines.append(f"| {acc.name} | {acc.rtol:g} | {acc.atol:g} | {acc.event_tol:g} | "
                     f"{acc.agreement:g} |")
    for scene, rows in results:
        lines += ["", f"## {scene.title}", "", f"Reference: {scene.reference_note}.", "",
                  "| accuracy | wall time (ms) | speed (rel.) | event times (s) | positions (m) |",
                  "|---|---|---|---|---|"]
        for r in rows:
            name = f"**{r['accuracy']}**" if r["accuracy"] in ACCURACY_PRESETS else r["accuracy"]
            done = "" if r["completed"] else " (run incomplete)"
            lines.append(f"| {name}{done} | {1e3 * r['seconds']:.3g} | {fmt(r['speed'])} | "
                         f"{fmt(r['times'])} | {fmt(r['positions'])} |")
    lines += [
        "",
        "Check of the sliding reference (its first sliding phase against an independent "
        "Newton-Euler integration, see the script): handover time differs by "
        f"{fmt(check['time'])} s, handover speed by {fmt(check['speed'])} (relative); the slip "
        f"direction held throughout: {check['sign_held']}.",
        "",
        "## The optimizer",
        "",
        f"min drop with beta free (over-the-top margin 0.5): beta* = {b_star:.15f} rad by brentq "
        "on the closed form. IPOPT's `tol` against the error of the optimum found and the wall "
        "time of one `optimize` (8 starts, no tolerance box, no sampling check), with IPOPT's",
        "default `bound_relax_factor` (1e-8), and with `bound_relax_factor = 0` (`optimize`'s",
        "keyword; the precise preset sets it):",
        "",
        "| IPOPT tol | preset that uses it | wall time (ms) | abs. error of beta | status "
        "| with bound_relax_factor 0: wall time (ms) | abs. error | status |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r, e in zip(opt_rows, exact_rows):
        preset = ", ".join(p for p, t in NLP_TOL.items() if t == r["tol"]) or ""
        lines.append(f"| {r['tol']:g} | {preset} | {1e3 * r['seconds']:.3g} | "
                     f"{fmt(r['error'])} | {r['status']} | {1e3 * e['seconds']:.3g} | "
                     f"{fmt(e['error'])} | {e['status']} |")
    lines += ["", *recommendation(results, opt_rows, exact_rows)]
    return "\n".join(lines) + "\n"


def presets_in_words() -> str:
    """The optimizer's settings per preset, as wired, e.g. for the closing recommendation."""
    names = " / ".join(SOLVE_PRESETS)
    def each(key):
        return " / ".join(f"{SOLVE_PRESETS[n][key]:g}" for n in SOLVE_PRESETS)
    return (f"`tol` {each('tol')}, `bound_relax_factor` {each('bound_relax_factor')} and "
            f"{each('starts')} starts ({names})")


def recommendation(results, opt_rows, exact_rows):
    """'Which preset when', with the figures of this run."""
    by = {scene.name: {r["accuracy"]: r for r in rows} for scene, rows in results}
    slide, bounce = by["manip-slide"], by["manip-bounce"]
    closed = [by[n]["default"] for n in ("stairs-1", "stairs-2", "manip-stick")]
    worst_closed = max(max(r["speed"], r["positions"]) for r in closed)

    def cell(r):
        return f"{fmt(r['speed'], 1)} on speeds and {fmt(r['times'], 1)} s on times in " \
               f"{1e3 * r['seconds']:.3g} ms"

    relaxed_floor = min(r["error"] for r in opt_rows)  # bound_relax_factor 1e-8 at any tol
    exact = {p: next(r for r in exact_rows if r["tol"] == t)["error"] for p, t in NLP_TOL.items()}
    return [
        "## Which preset when",
        "",
        "- **Closed-form regimes: any preset, the same answer.** Stairs flights and impacts, and",
        "  the manipulators' flights, impacts and stuck carries (every working design of the",
        "  paper's kind) are closed forms; the preset only sets the tolerance of guards that do",
        f"  not fire there. Errors stay at rounding (at most {fmt(worst_closed, 1)} here) and the",
        "  time is the same for all presets: use `default`; `precise` buys nothing.",
        "- **Integrated phases (a sliding carry, bouncing on a moving palm): the presets differ.**",
        f"  Sliding: `fast` errs by {cell(slide['fast'])}; `default` by {cell(slide['default'])};",
        f"  `precise` by {cell(slide['precise'])} (near the reference's own floor). Bouncing:",
        f"  `fast` {cell(bounce['fast'])}, `default` {cell(bounce['default'])} (its phase is held",
        "  to a maximum step of 0.05 sqrt(l/g), which costs more than the tolerance).",
        "  Use `fast` for exploring, sweeps and design tables (1e-6 is far below any build",
        "  tolerance); `default` for verification and build sheets; `precise` to check a design",
        "  before it is built or to study sub-micron sensitivities.",
        "- **Verification** (verify.py, `Accuracy.agreement`) demands 1e-4 / 1e-7 / 1e-9 between",
        "  simulator and closed forms: 100x or more above the errors measured here, so a",
        "  disagreement means the design or the closed form, not the integrator.",
        "- **The optimizer** keeps every row 100 times its tolerance inside its limit (the",
        "  backoff of `pdm_design/formulation/common.py`: an answer on a limit within IPOPT's",
        "  tolerance of it failed the simulator), so its optimum sits that far inside the",
        "  closed-form one, in proportion to `max(tol, bound_relax_factor)`: "
        f"{fmt(exact['fast'], 1)} / {fmt(exact['default'], 1)} / {fmt(exact['precise'], 1)} "
        "rad at",
        "  the fast / default / precise tolerances with `bound_relax_factor = 0`, and no better",
        f"  than {fmt(relaxed_floor, 1)} with IPOPT's default 1e-8, for the same wall time. The",
        "  presets (`pdm_design.api.SOLVE_PRESETS`) use " + presets_in_words() + ".",
    ]


if __name__ == "__main__":
    main()
