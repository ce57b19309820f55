"""Speed against accuracy of the carry on real links: the closed form against the integrated
carry (fourth-order steps in the angle, physics.integrated_carry_speed_squared) in the NLP.
Writes results/bench_links.md (not a test; tests/test_links_pivots.py asserts the tolerances).

    python results/bench_links.py           # about three minutes
    python results/bench_links.py --quick   # one repeat, shorter ladder

Problem: problems/manipulators_real_links.toml (two 0.5 kg links of 2 m, 0.2 N m of pivot
friction) with the objective max_min_margin (the robust rows need the closed form), alpha and
beta free, IPOPT at the default preset's settings (8 starts, tol 1e-8), no linearisation.

* Without damping both paths apply. The closed form is exact to rounding; the integrated path is
  asked for by the accuracy key `carry = "integrated"` (`verification.accuracy`, `--accuracy
  carry=integrated`), with as many steps as physics.carry_steps gives for a tenth of each agreement
  tolerance of a ladder (the presets' fast / default / precise marked: 1e-4, 1e-7, 1e-9).
  Error: the periodic handover speed of the NLP's own model
  (its fixed point S = v(beta)^2, iterated in floats with the same steps) at the design it found,
  against the closed form at that design.
* With pivot damping 0.3 N m s/rad only the integrated path applies (the CLI chooses it). Error:
  the same model speed against the simulator at `precise` (rtol 1e-12, 40 manipulators: the
  handover speed converges to the fixed point geometrically), an independent integration with
  located events.
Time per solve: build of the NLP (CasADi, IPOPT set-up) plus every start's IPOPT time, median
of the repeats.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pdm_design.accuracy import accuracy  # noqa: E402
from pdm_design.formulation import build  # noqa: E402
from pdm_design.io import write_atomic  # noqa: E402
from pdm_design.scenes.manipulators import formulation as form  # noqa: E402
from pdm_design.scenes.manipulators import physics as phys  # noqa: E402
from pdm_design.scenes.manipulators.analysis import carry_terms  # noqa: E402
from pdm_design.scenes.manipulators.model import ManipulatorsDesign, Pivots  # noqa: E402
from pdm_design.scenes.manipulators.sim import simulate_manipulators  # noqa: E402
from pdm_design.solve.optimize import optimize  # noqa: E402
from pdm_design.spec.loader import load_spec  # noqa: E402

PROBLEM = ROOT / "problems" / "manipulators_real_links.toml"
PRESET_AGREEMENT = {1e-4: "fast", 1e-7: "default", 1e-9: "precise"}


def spec_for(damping: float, agreement: float, carry: str):
    spec = load_spec(PROBLEM)
    scene = dataclasses.replace(spec.scene, pivots=Pivots(
        friction_torque=spec.scene.pivots.friction_torque, damping=damping))
    return dataclasses.replace(
        spec, scene=scene, objective={"max_min_margin": 1.0},
        verification=dataclasses.replace(spec.verification, accuracy=accuracy(
            {"rtol": 1e-9, "atol": 1e-11, "event_tol": 1e-11, "agreement": agreement,
             "carry": carry})))


def solve(spec):
    """(seconds, design, steps) of one optimisation (steps: the integrated carry's, 0 for the
    closed form, as formulation.manipulators.integrated_steps gives them)."""
    values, _, bounds = form.design_inputs(spec, ManipulatorsDesign.VARIABLES, form.DEFAULTS)
    steps = form.integrated_steps(spec, False, values, bounds)
    build._CACHE.clear()  # every solve builds its NLP: its time is part of the solve's
    t0 = time.perf_counter()
    result = optimize(spec, starts=8, tol=1e-8, linearise=False, check_samples=0,
                      diagnose=False)
    seconds = time.perf_counter() - t0
    assert result.success, result.message
    return seconds, spec.design_at(result.design), steps


def model_speed(spec, design, steps):
    """The NLP model's periodic handover speed at `design`: its fixed point in floats."""
    carry = carry_terms(spec.scene, design)
    a, b, l = design.alpha, design.beta, design.link_length
    k = float(phys.momentum_fraction(carry.q))
    kw = dict(gravity=carry.gravity, link_length=l, friction=carry.friction)
    if not steps:
        return math.sqrt(float(phys.handover_speed_squared(a, b, carry.q, **kw)))
    s2 = float(phys.handover_speed_squared(a, b, carry.q, **kw))
    for _ in range(400):
        s2 = float(phys.integrated_carry_speed_squared(
            k * math.sqrt(s2) * math.cos(a + b), a, b, damping=carry.damping, steps=steps, **kw))
    return math.sqrt(s2)


def closed_speed(spec, design):
    return model_speed(dataclasses.replace(spec), design, 0)


def simulated_speed(spec, design):
    run = simulate_manipulators(spec.scene, design, stages=40, accuracy="precise")
    assert run.outcome.completed, run.outcome
    return run.stages[-2]["handover_speed"]


def measure(damping, agreement, carry, repeats):
    spec = spec_for(damping, agreement, carry)
    runs = [solve(spec) for _ in range(repeats)]
    seconds = statistics.median(r[0] for r in runs)
    _, design, steps = runs[0]
    got = model_speed(spec, design, steps)
    truth = closed_speed(spec, design) if damping == 0.0 else simulated_speed(spec, design)
    return {"agreement": agreement, "steps": steps, "seconds": seconds, "speed": got,
            "error": abs(got - truth) / truth, "truth": truth}


def table(rows, title, truth_name):
    lines = [f"### {title}", "",
             f"| path | agreement (preset) | steps | time per solve (s) | handover speed (m/s) | "
             f"relative error vs {truth_name} |", "|---|---|---|---|---|---|"]
    for r in rows:
        path = "closed form" if not r["steps"] else "integrated"
        rtol = "–" if not r["steps"] else (
            f"{r['agreement']:.0e}" + (f" ({PRESET_AGREEMENT[r['agreement']]})"
                                       if r["agreement"] in PRESET_AGREEMENT else ""))
        lines.append(f"| {path} | {rtol} | {r['steps'] or '–'} | {r['seconds']:.2f} | "
                     f"{r['speed']:.12f} | {r['error']:.2e} |")
    return lines + [""]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    repeats = 1 if args.quick else 3
    ladder = [1e-4, 1e-7, 1e-9] if args.quick else [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8,
                                                     1e-9, 1e-10]
    plain = [measure(0.0, 1e-7, "closed", repeats)]
    plain += [measure(0.0, target, "integrated", repeats) for target in ladder]
    damped = [measure(0.3, target, "closed", repeats) for target in ladder]
    command = "python results/bench_links.py" + (" --quick" if args.quick else "")
    lines = [
        "# The carry on real links: closed form against integrated, in the NLP", "",
        f"Generated by `{command}` ({platform.python_implementation()} "
        f"{platform.python_version()}, {platform.machine()}); see the script's docstring for "
        "the method. Median of "
        f"{repeats} solve(s) each; the machine is shared, so times are indicative.", "",
        *table(plain, "No damping: both paths apply (friction 0.2 N m, links 2 x 0.5 kg)",
               "the closed form"),
        *table(damped, "Pivot damping 0.3 N m s/rad: only the integrated path applies",
               "the simulator (precise)"),
        "The integrated path's error falls as h⁴ (steps ∝ (agreement/10)^(-1/4)); its cost is "
        "the NLP's "
        "size: every row with a carry holds that many steps (CasADi SX, inlined). Without "
        "damping the tool uses the closed form unless the accuracy asks for the integrated "
        "carry (`--accuracy carry=integrated`, or `carry = \"integrated\"` in "
        "`verification.accuracy`); with damping it integrates with the steps of the spec's "
        "accuracy (`--accuracy fast | default | precise`).", "",
    ]
    write_atomic(ROOT / "results" / "bench_links.md", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
