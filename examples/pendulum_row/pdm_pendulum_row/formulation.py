"""The NLP rows: the margins as rows of the design (CasADi), on the shared formulation's
vocabulary (pdm_design.formulation.common)."""

from __future__ import annotations

import casadi as ca

from pdm_design.formulation.common import Condition, SceneModel, design_inputs

from . import physics as ph

DEFAULTS = {}


def build(spec):
    scene = spec.scene
    values, symbols, bounds = design_inputs(spec, ("bob_mass", "drop", "rod_length"), DEFAULTS)
    m, e, g = scene.puck.mass, scene.puck.restitution, scene.gravity
    M, h, l = values["bob_mass"], values["drop"], values["rod_length"]
    gain2 = ph.bob_gain(m, M, e) ** 2
    loop = 4.0 * g * l
    epigraph = float(spec.objective.get("max_min_margin", 0.0)) > 0.0
    t = ca.SX.sym("min_margin") if epigraph else None
    # each row: capacity - demand >= required * capacity (the analysis' margin, >= 0 holds)
    rows = (("forward", "after every impact", m - e * M, m),
            ("first_no_loop", "bob 1", loop - gain2 * scene.initial.speed**2, loop),
            ("no_loop", "periodic orbit", loop - gain2 * ph.periodic_speed2(m, M, e, h, g),
             loop))
    conditions = tuple(Condition((name,), where, ca.SX(slack) if not isinstance(slack, ca.SX)
                                 else slack, scale) for name, where, slack, scale in rows)
    xd = ca.vertcat(*symbols.values()) if symbols else ca.SX(0, 1)
    aux = (("min_margin", t, -1.0, 1.0),) if epigraph else ()
    r = ph.ratio(m, M, e)
    model = SceneModel(
        kind="pendulum_row", design_symbols=symbols, aux=aux, conditions=conditions,
        objective_terms={"max_min_margin": t if epigraph else ca.SX(0.0),
                         "fastest_convergence": r * r if isinstance(r, ca.SX) else ca.SX(r * r),
                         "min_drop": h if isinstance(h, ca.SX) else ca.SX(h)},
        margin_symbol=t,
        aux_init=ca.Function("aux_init", [xd], [ca.SX(0.0) if epigraph else ca.SX(0, 1)]),
        derived={}, tolerance_axes=())
    return model, bounds, None
