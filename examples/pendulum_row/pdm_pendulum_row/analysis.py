"""The closed-form analysis of one design (pdm_design.analysis.Analysis)."""

from __future__ import annotations

import math

from pdm_design.analysis.result import Analysis, margin

from . import physics as ph

KIND = "pendulum_row"


def analyse(scene, design, stages=None) -> Analysis:
    m, e, g = scene.puck.mass, scene.puck.restitution, scene.gravity
    M, h, l = design.bob_mass, design.drop, design.rod_length
    r, gain = ph.ratio(m, M, e), ph.bob_gain(m, M, e)
    s_star = float(ph.periodic_speed2(m, M, e, h, g)) if r < 1.0 else math.inf
    s_first = scene.initial.speed ** 2
    loop = 4.0 * g * l
    margins = {
        "forward": margin(m, e * M),
        "first_no_loop": margin(loop, gain**2 * s_first),
        "no_loop": margin(loop, gain**2 * s_star),
    }
    v_star = math.sqrt(s_star) if r > 0.0 else None
    periodic = {"bob_speed": v_star, "speed_after": None if v_star is None else r * v_star,
                "contraction": r * r}
    return Analysis(kind=KIND, design={"bob_mass": M, "drop": h, "rod_length": l},
                    geometry={"pitch": h / math.tan(scene.ramp_angle)}, periodic=periodic,
                    margins=margins, approach={"first_speed": scene.initial.speed})
