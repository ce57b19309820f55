"""The robust compass-gait NLP (problems/compass_gait_robust.toml: the largest box of every
step's slope error) at fewer RK4 substeps of its stance flow: CPU seconds to build and to solve,
IPOPT's iterations, the box and design found, and the NLP's gait against the step map's
(stepmap.fixed_point: 200 RK4 steps) at the design found. Writes results/bench_compass_gait_nlp.md.

    python results/bench_compass_gait_nlp.py [SUBSTEPS ...]     (default 60 30 20 30L)

A count ending in L (30L): IPOPT's limited-memory Hessian instead of the exact one.
The margins are held at 6 nodes along the step whatever the substeps (every substeps / 6-th).
CPU seconds (time.process_time): the machine is shared, wall clock is not this code's.
"""

from __future__ import annotations

import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import casadi as ca  # noqa: E402

from pdm_design.formulation.common import assemble  # noqa: E402
from pdm_design.scenes.compass_gait import formulation  # noqa: E402
from pdm_design.scenes.compass_gait.gait import fixed_point  # noqa: E402
from pdm_design.scenes.compass_gait.scene import CompassGaitDesign  # noqa: E402
from pdm_design.solve.ipopt import SolverOptions  # noqa: E402
from pdm_design.spec import load_spec  # noqa: E402

SPEC = load_spec(str(HERE.parent / "problems" / "compass_gait_robust.toml"))
STATE = ("stance", "swing", "stance_rate", "swing_rate")
# The whole command, not measured by this script: `time python3 -m pdm_design optimize
# problems/compass_gait_robust.toml --format json` (8 starts, then the verification) on the same
# shared machine, before and after the NLP went from 60 to 30 substeps.
WHOLE_COMMAND = (
    "The whole `pdm-design optimize problems/compass_gait_robust.toml --format json` (8 starts "
    "and the verification; measured with `time`, user CPU, on the same shared machine, not by "
    "this script): at 60 substeps 1414 IPOPT iterations, 91 and 96 s in two runs; at 30, 736 "
    "iterations, 45 s. Both give hip_mass 5 kg, leg_com 0.3 m and a box of 0.0092994 rad, "
    "which the simulator confirms (every corner pattern and random builds from the gait).")


def run(token: str) -> dict:
    """One row: `token` the substeps, with an L for IPOPT's limited-memory Hessian."""
    substeps, limited = int(token.rstrip("L")), token.endswith("L")
    formulation.NLP_SUBSTEPS, formulation.NODE_EVERY = substeps, substeps // 6
    t0 = time.process_time()
    model, bounds, _ = formulation.build(SPEC)
    form = assemble(SPEC, model, key=f"bench{substeps}", bounds=bounds)
    options = SolverOptions().casadi()
    if limited:
        options["ipopt.hessian_approximation"] = "limited-memory"
    solver = ca.nlpsol("bench", "ipopt", form.nlp, options)
    t1 = time.process_time()
    guess = {n: SPEC.design[n].guess for n in form.design_names}
    sol = solver(x0=form.start_vector(guess), p=form.parameters(), lbx=form.lbx, ubx=form.ubx,
                 lbg=form.lbg, ubg=form.ubg)
    t2 = time.process_time()
    x = dict(zip(form.x_names, np.asarray(sol["x"]).ravel()))
    design = CompassGaitDesign(slope=SPEC.design["slope"], hip_mass=x["hip_mass"],
                               leg_com=x["leg_com"])
    point = fixed_point(SPEC.scene, design)["fixed_point"]
    return {"substeps": token, "build": t1 - t0, "solve": t2 - t1,
            "iterations": solver.stats()["iter_count"], "status": solver.stats()["return_status"],
            "tau": x["tolerance"], "hip_mass": x["hip_mass"], "leg_com": x["leg_com"],
            "gait_error": max(abs(x[k] - point[k]) for k in STATE)}


def main(counts):
    rows = [run(n) for n in counts]
    base = rows[0]["tau"]
    lines = [
        "# Compass gait: the robust NLP against its RK4 substeps",
        "",
        f"`python results/bench_compass_gait_nlp.py {' '.join(map(str, counts))}` on "
        f"{platform.processor() or platform.machine()}, Python {platform.python_version()}; "
        "CPU seconds (the machine is shared); IPOPT with the project's options, the exact Hessian "
        "(L: limited-memory); one start, the spec's guess.",
        "",
        "| RK4 substeps | build (CPU s) | solve (CPU s) | iterations | status | box tau (rad) | "
        "tau - tau(first) | hip_mass, leg_com | NLP gait - fixed_point (max, rad or rad/s) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['substeps']} | {r['build']:.1f} | {r['solve']:.1f} | "
                     f"{r['iterations']} | {r['status']} | {r['tau']:.6f} | "
                     f"{r['tau'] - base:.1e} | {r['hip_mass']:.4f}, {r['leg_com']:.4f} | "
                     f"{r['gait_error']:.1e} |")
    lines += ["", WHOLE_COMMAND]
    (HERE / "bench_compass_gait_nlp.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1:] or ["60", "30", "20", "30L"])
