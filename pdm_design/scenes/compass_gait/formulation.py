"""The compass gait's NLP: the periodic gait as constraints, its multipliers inside a circle,
its margins along the step, and a box of every step's own slope error.

Decision vector: [free design variables (slope, hip_mass, leg_mass, leg_length, leg_com,
leg_inertia: whichever the spec leaves free), the gait's post-strike state (stance, swing,
stance_rate, swing_rate), its step time, rho (the spectral-radius bound, when minimised), tau (the
slope box, when maximised), t (margin epigraph)].

Model rows (equalities): strike(phi(T, x)) = x and guard(phi(T, x)) = 0, the stance flow by
NLP_SUBSTEPS RK4 steps (the same discretisation as stepmap.py at fewer steps: the NLP's gait is
within ~1e-6 of fixed_point's, 8e-7 at the robust spec's optimum, its box within 4e-8 of 60
substeps' at a third of the CPU time: results/bench_compass_gait_nlp.md; verification uses
fixed_point and the simulator).

Stability: every multiplier inside the circle of radius rho (the requirement
max_spectral_radius, or the variable rho minimised). The 4 x 4 Jacobian's characteristic
polynomial is lambda (lambda^3 + c2 lambda^2 + c1 lambda + c0) (its trivial root 0), with
c2 = -tr J, c1 = (tr(J)^2 - tr(J^2)) / 2, c0 = -(tr(J)^3 - 3 tr(J) tr(J^2) + 2 tr(J^3)) / 6;
z = lambda / rho: z^3 + a2 z^2 + a1 z + a0 with a2 = c2 / rho, a1 = c1 / rho^2, a0 = c0 / rho^3,
and Jury's conditions (all roots in the unit disc, exactly):
    1 + a2 + a1 + a0 > 0,  1 - a2 + a1 - a0 > 0,  1 - a0^2 > |a0 a2 - a1|  (so |a0| < 1).

Margins along the step, at every NODE_EVERY-th RK4 node and at the strike: stance_contact
(normal force per weight), no_slip ((friction normal - |tangential|) / (friction weight)),
hip_limit (with a walker's hip_limit: the angle between the legs below it); over_the_top (the
stance rate stays positive, validity).

Slope box tau (max_slope_tolerance), linearised: a slope error d on one step moves the next
post-strike state by B d (B = dP/dslope by AD) and that deviation decays by J each step; every
margin row m(x, slope) is held at m >= tau (|m_slope| + |m_x| sum_{k < K} |J^k B|) (absolute
values entry by entry: the worst signs of every step's error), K = verification.stages up to
ROBUST_HORIZON. First order in tau: the box is verified by the event simulator.
"""

from __future__ import annotations

import functools

import casadi as ca

from ...formulation.common import MARGIN, MODEL, VALIDITY, Condition, SceneModel, design_inputs
from . import physics as phys
from .scene import CompassGaitDesign

NLP_SUBSTEPS = 30
NODE_EVERY = 5
ROBUST_HORIZON = 12
DEFAULTS = {k: None for k in CompassGaitDesign.VARIABLES}
# This scene's objectives by the shared objective term that carries each (formulation.common.
# OBJECTIVE_SENSE knows only those): the spectral radius is the contraction per step, as the
# stairs' restitution squared is; the slope box is the tolerance variable.
SHARED_OBJECTIVES = {"min_spectral_radius": "fastest_convergence",
                     "max_slope_tolerance": "max_offset_tolerance"}


def shared_objective(objective: dict) -> dict:
    """The [objective] table with this scene's names as the shared terms' (SHARED_OBJECTIVES)."""
    return {SHARED_OBJECTIVES.get(k, k): v for k, v in objective.items()}


def _weight(objective, name) -> float:
    return float(objective.get(name, objective.get(SHARED_OBJECTIVES[name], 0.0)))


@functools.lru_cache(maxsize=2)
def _flow(substeps: int):
    """SX Function (x0, T, params[6]) -> the RK4 nodes (4 x substeps+1)."""
    x, p, h = ca.SX.sym("x", 4), ca.SX.sym("p", 6), ca.SX.sym("h")

    def rhs(z):
        a1, a2 = phys.accelerations(z[0], z[1], z[2], z[3], phys.Params(*[p[i] for i in range(6)]))
        return ca.vertcat(z[2], z[3], a1, a2)

    k1 = rhs(x)
    k2 = rhs(x + h / 2 * k1)
    k3 = rhs(x + h / 2 * k2)
    k4 = rhs(x + h * k3)
    rk4 = ca.Function("rk4", [x, h, p], [x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    x0, T, pp = ca.SX.sym("x0", 4), ca.SX.sym("T"), ca.SX.sym("p", 6)
    nodes, z = [x0], x0
    for _ in range(substeps):
        z = rk4(z, T / substeps, pp)
        nodes.append(z)
    return ca.Function("nodes", [x0, T, pp], [ca.horzcat(*nodes)])


def walker_params(scene, values) -> phys.Params:
    """Params from the scene's walker with the design's (possibly symbolic) values."""
    w = scene.walker
    get = {k: (values[k] if values.get(k) is not None else getattr(w, k))
           for k in CompassGaitDesign.WALKER}
    if w.model == "simplest":
        l = get["leg_length"]
        return phys.Params(0.0, 0.0, l, l, 0.0, scene.gravity)
    l, b = get["leg_length"], get["leg_com"]
    return phys.Params(get["leg_mass"] / get["hip_mass"], l - b, b, l,
                       get["leg_inertia"] / get["leg_mass"], scene.gravity)


def build(spec):
    """(SceneModel, bounds, the gait's symbols) of a compass-gait spec: spec.scene, spec.design
    (numbers or Bounds), spec.objective, spec.requirements, spec.verification.stages."""
    scene = spec.scene
    values, symbols, bounds = design_inputs(spec, CompassGaitDesign.VARIABLES, DEFAULTS)
    if values["slope"] is None:
        raise ValueError("the compass gait's NLP needs a ramp: design.slope")
    params = walker_params(scene, values)
    error = ca.SX.sym("slope_error")  # one step's own slope error, 0 in the NLP
    slope = values["slope"] + error
    state, T = ca.SX.sym("gait_state", 4), ca.SX.sym("step_time")
    nodes = _flow(NLP_SUBSTEPS)(state, T, ca.vertcat(*params))
    end = nodes[:, -1]
    after = ca.vertcat(*phys.heel_strike(end[0], end[1], end[2], end[3], params))
    guard = phys.strike_guard(end[0], end[1], slope, 0.0)
    J, B = _return_jacobians(after, guard, state, T, error)

    minimise = _weight(spec.objective, "min_spectral_radius") > 0.0
    robust = _weight(spec.objective, "max_slope_tolerance") > 0.0
    epigraph = float(spec.objective.get("max_min_margin", 0.0)) > 0.0
    rho = ca.SX.sym("spectral_radius_bound") if minimise else \
        float(spec.requirements.get("max_spectral_radius", 1.0))
    tau = ca.SX.sym("tolerance") if robust else 0.0
    t = ca.SX.sym("min_margin") if epigraph else None

    guess = _guess(spec)
    aux = [("stance", state[0], -1.5, 1.5), ("swing", state[1], -1.5, 1.5),
           ("stance_rate", state[2], -50.0, 50.0), ("swing_rate", state[3], -50.0, 50.0),
           ("step_time", T, 1e-3, 100.0)]
    start = list(guess)
    if minimise:
        aux.append(("spectral_radius_bound", rho, 0.0, 2.0))
        start.append(1.0)
    if robust:
        aux.append(("tolerance", tau, 0.0, 0.2))
        start.append(1e-3)
    if epigraph:
        aux.append(("min_margin", t, 0.0, 1.0))
        start.append(0.0)
    xd = ca.vertcat(*symbols.values()) if symbols else ca.SX(0, 1)
    aux_init = ca.Function("aux_init", [xd], [ca.DM(start)])

    def nominal(expr):
        return ca.substitute(expr, error, ca.SX(0.0))

    after, guard, J, B, end = (nominal(e) for e in (after, guard, J, B, end))
    conditions = [Condition((), f"periodic gait: {name} returns", after[i] - state[i], 1.0,
                            MODEL, equality=True)
                  for i, name in enumerate(("stance", "swing", "stance rate", "swing rate"))]
    conditions.append(Condition((), "periodic gait: the heel strikes", guard, 1.0, MODEL,
                                equality=True))
    conditions.append(Condition((), "the swing foot is ahead at the strike", end[0] - end[1],
                                1.0, VALIDITY))
    conditions += _jury(J, rho)
    margin_rows = _margin_rows(scene, params, nodes, nodes[:, -1], slope)
    conditions += [Condition(c.keys, c.where, nominal(c.slack), nominal(c.scale), c.kind)
                   for c in _robust(margin_rows, J, B, state, error, tau,
                                    spec.verification.stages)]
    slope = values["slope"]
    speed = phys.step_length(state[1], state[0], params) / T
    model = SceneModel(
        kind="compass_gait", design_symbols=symbols, aux=tuple(aux),
        conditions=tuple(conditions),
        objective_terms={
            "max_offset_tolerance": tau if robust else ca.SX(0.0),
            "max_min_margin": t if epigraph else ca.SX(0.0),
            "min_drop": ca.SX(0.0) + slope,
            "fastest_convergence": rho if minimise else ca.SX(0.0),
            "max_yield": ca.SX(0.0),
        },
        margin_symbol=t, aux_init=aux_init,
        derived={"step_length": phys.step_length(state[1], state[0], params),
                 "step_period": T, "speed": speed},
        tolerance_axes=("slope",), stack_starts=False,
    )
    return model, bounds, {"state": state, "T": T, "J": J, "B": B}


def _guess(spec):
    """The gait at the spec's guess (stepmap, from [initial]) as the NLP's start."""
    from .gait import find_gait
    from .spec import design_at

    gait = find_gait(spec.scene, design_at(spec.design))
    return [*gait.state, gait.step_period]


def _return_jacobians(after, guard, state, T, error):
    """(J, B): the return map's derivatives by the state and by the step's own slope error
    (implicit function theorem through the guard; the strike does not depend on the slope)."""
    G_T = ca.jacobian(guard, T)
    P_T = ca.jacobian(after, T)
    J = ca.jacobian(after, state) - P_T @ ca.jacobian(guard, state) / G_T
    B = -P_T @ ca.jacobian(guard, error) / G_T
    return J, B


def _jury(J, rho):
    J2 = J @ J
    tr1, tr2, tr3 = ca.trace(J), ca.trace(J2), ca.trace(J2 @ J)
    c2 = -tr1
    c1 = (tr1**2 - tr2) / 2
    c0 = -(tr1**3 - 3 * tr1 * tr2 + 2 * tr3) / 6
    a2, a1, a0 = c2 / rho, c1 / rho**2, c0 / rho**3
    b = a0 * a2 - a1
    rows = [("z = 1 is outside", 1 + a2 + a1 + a0), ("z = -1 is outside", 1 - a2 + a1 - a0),
            ("the product of the roots", 1 - a0**2 - b), ("the product of the roots, other sign",
                                                          1 - a0**2 + b)]
    return [Condition(("stability",), f"multipliers inside the circle (Jury: {where})", slack,
                      1.0, VALIDITY) for where, slack in rows]


def _margin_rows(scene, params, nodes, end, slope):
    """[(key, where, slack, scale)] along the step and at the strike."""
    weight = (1 + 2 * params.beta) * params.g
    mu = scene.friction
    rows = []
    for k in range(NODE_EVERY, nodes.shape[1], NODE_EVERY):
        x = nodes[:, k]
        n, tang = phys.ground_reaction(x[0], x[1], x[2], x[3], slope, params)
        rows.append(("stance_contact", f"node {k}", n, weight))
        rows.append(("no_slip", f"node {k}, ahead", mu * n - tang, mu * weight))
        rows.append(("no_slip", f"node {k}, back", mu * n + tang, mu * weight))
        rows.append((None, f"node {k}: the stance leg moves forward", x[2], 1.0))
        if scene.walker.hip_limit is not None:
            limit = scene.walker.hip_limit
            rows.append(("hip_limit", f"node {k}, legs apart", limit - ca.fabs(x[0] - x[1]),
                         limit))
    if scene.walker.hip_limit is not None:  # and at the strike
        limit = scene.walker.hip_limit
        rows.append(("hip_limit", "heel strike", limit - (end[0] - end[1]), limit))
    pn, pt = phys.strike_impulse(end[0], end[1], end[2], end[3], params, slope)
    rows.append(("no_slip", "heel strike, ahead", mu * pn - pt, mu * ca.fabs(pn) + 1e-9))
    rows.append(("no_slip", "heel strike, back", mu * pn + pt, mu * ca.fabs(pn) + 1e-9))
    rows.append((None, "heel strike: the foot stays down", pn, 1.0))
    return rows


def _robust(rows, J, B, state, error, tau, stages):
    """Each margin row, held against the linearised worst case of a box tau on every step's
    slope (module docstring); tau = 0: the rows themselves."""
    out = []
    horizon = max(1, min(int(stages), ROBUST_HORIZON))
    if isinstance(tau, float):
        spread = None
    else:
        spread, Jk = ca.fabs(B), B
        for _ in range(horizon - 1):
            Jk = J @ Jk
            spread = spread + ca.fabs(Jk)
    for key, where, slack, scale in rows:
        if spread is not None:
            d_state = ca.jacobian(slack, state)
            d_slope = ca.jacobian(slack, error)
            slack = slack - tau * (ca.fabs(d_slope) + ca.fabs(d_state) @ spread)
        if key is None:
            out.append(Condition(("over_the_top",), where, slack, 1.0, VALIDITY))
        else:
            out.append(Condition((key,), where, slack, scale, MARGIN))
    return out
