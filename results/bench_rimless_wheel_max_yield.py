"""The rimless wheel's max_yield NLP (scenes/rimless_wheel/nlp_yield.py): optimize time and
answer of problems/rimless_wheel_max_yield.toml at more steps, with the rows' gradients chained
through the step map (row_moments, linear in the steps) against the full Jacobian of every row
in every step's error (the first version, quadratic in the steps), in one run. --stairs:
problems/rimless_wheel_stairs_max_yield.toml, chained only (the full Jacobian is a ramp's);
--chained: the ramp's chained version only.

    python3 results/bench_rimless_wheel_max_yield.py [--stairs | --chained] [steps ...]
    (default 20 100 200)
"""

import dataclasses
import resource
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca

from pdm_design import api
from pdm_design.scenes.rimless_wheel import nlp_yield
from pdm_design.scenes.rimless_wheel import physics as phys
from pdm_design.spec.loader import load_spec

NAMES = {"old": "full Jacobian (old)", "new": "chained (new)"}
PROBLEMS = Path(__file__).resolve().parent.parent / "problems"
SPECS = {"ramp": PROBLEMS / "rimless_wheel_max_yield.toml",
         "stairs": PROBLEMS / "rimless_wheel_stairs_max_yield.toml"}


def full_jacobian(m, stages, spread):
    """The first version: every row a function of every step's error, differentiated whole."""
    slope_sigma, start_sigma = spread.each[0], spread.start
    d, ds = ca.SX.sym("slope_error", stages), ca.SX.sym("start_speed_error")
    wheel = nlp_yield.SimpleNamespace(alpha=m.alpha, rate=m.rate, leg=m.leg, k2=m.k2,
                                      eta=m.eta, beta=m.beta, gravity=m.scene.gravity,
                                      friction=m.scene.friction)
    energy = phys.stance_energy(m.scene.initial.speed + ds, m.beta - m.alpha, m.rate)
    prev, rows = m.beta, []
    for k in range(stages):
        beta = m.beta + d[k]
        rows += [g for _, g in phys.stance_rows(wheel, energy, prev, beta, m.ground)]
        energy = phys.step_energy(energy, beta, m.alpha, m.eta, m.rate)
        prev = beta
    g, errors = ca.vertcat(*rows), ca.vertcat(d, ds)
    jac = ca.jacobian(g, errors)
    weights = ca.vertcat(*([slope_sigma**2] * stages), start_sigma**2)
    g0, jac0 = ca.substitute([g, jac], [errors], [ca.SX.zeros(stages + 1)])
    return g0, ca.sqrt((jac0**2) @ weights + nlp_yield.SD_FLOOR)


def run(n, version, ground):
    """One optimize of the spec at n steps with one version, in this process (fresh caches)."""
    if version == "old":
        nlp_yield.row_moments = full_jacobian
    base = load_spec(SPECS[ground])
    spec = dataclasses.replace(base, verification=dataclasses.replace(base.verification,
                                                                      stages=n))
    start = time.perf_counter()
    out = api.optimize(spec, verify=False)
    seconds = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    chosen = "slope" if ground == "ramp" else "rise"
    print(f"| {n} | {NAMES[version]} | {seconds:.2f} | {peak:.0f} | "
          f"{out.analysis.design[chosen]:.6f} | {out.objective['terms']['max_yield']:.6f} |")


def main(steps, ground, versions):
    chosen = "slope (rad)" if ground == "ramp" else "rise (m)"
    print(f"| steps | version | optimize (s) | peak memory (MB) | {chosen} | nines |")
    print("|---|---|---|---|---|---|", flush=True)
    for n in steps:
        for version in versions:  # each in its own process: no cache, its own peak
            subprocess.run([sys.executable, __file__, "--one", str(n), version, ground],
                           check=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--one"]:
        run(int(sys.argv[2]), sys.argv[3], sys.argv[4])
    else:
        flags = {a for a in sys.argv[1:] if a.startswith("--")}
        ground = "stairs" if "--stairs" in flags else "ramp"
        versions = ("new",) if flags else ("old", "new")
        main([int(a) for a in sys.argv[1:] if not a.startswith("--")] or [20, 100, 200],
             ground, versions)
