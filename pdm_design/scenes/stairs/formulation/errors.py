"""The stairs' conditions as explicit functions of every step's construction errors.

d = (er_1..er_N, et_1..et_N): step n's rise and tread differ from the design by (er_n, et_n),
numbered as the simulator and the spec's step_errors number them: er_n is the riser at the back of
tread n (er_1 the first, below the fixed top landing and launcher), et_n tread n's length. The
recursion is the one in stairs.py, step by step with each step's own errors; used to linearise the
safe set of errors (cvxpy) and to check a robust box by sampling errors inside it. (The launch row
does not depend on the errors and is not repeated here.)
"""

from __future__ import annotations

import casadi as ca

from ....formulation.common import MARGIN, ConditionInfo, Scenario
from .. import physics as phys


def scenario(spec, model, m) -> Scenario:
    N = spec.verification.stages
    er = ca.SX.sym("er", N)
    et = ca.SX.sym("et", N)
    L, v = m.trajectory([er[i] for i in range(N)], [et[i] for i in range(N)])
    r = spec.scene.ball.radius
    scale = m.tread * m.vx**2
    rows = []
    for n in range(N):
        rows.append(("riser_clearance", f"landing {n + 1}",
                     L[n] - phys.riser_reach(m.rise + er[n], r), m.tread))
        for where, slack in m.nose_slack(v[n], m.tread + et[n] - L[n]):
            rows.append(("nose_clearance", f"flight {n + 1}, {where}", slack, scale))
    x = ca.vertcat(*model.design_symbols.values(), *(s for _, s, _, _ in model.aux))
    fn = ca.Function("errors", [x, ca.vertcat(er, et)],
                     [ca.vertcat(*[row[2] for row in rows]), ca.vertcat(*[row[3] for row in rows])])
    names = tuple(f"rise{n}" for n in range(1, N + 1)) + tuple(f"tread{n}" for n in range(1, N + 1))
    infos = tuple(ConditionInfo(i, row[0], (row[0],), row[1], MARGIN, False)
                  for i, row in enumerate(rows))
    return Scenario(fn, names, {"rise": tuple(range(N)), "tread": tuple(range(N, 2 * N))}, infos)
