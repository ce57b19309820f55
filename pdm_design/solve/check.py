"""Independent re-checks of an optimizer answer (no simulator: solving never imports it).

* closed_form_check: the fixed-design analysis (`pdm_design.analysis`) of the returned design
  must meet the requirements (a different code path from the NLP's rows);
* sampled_offsets_check: the explicit-offset conditions (formulation/*_offsets.py: exact stage by
  stage, no worst-case bounds) evaluated at offsets sampled inside the robust box (uniform, random
  corners, alternating patterns) must all hold.
"""

from __future__ import annotations

import numpy as np

from ..analysis import analyse
from ..analysis.result import required

CHECK_TOL = 1e-6


def _design_point(spec, design: dict[str, float]):
    """The design object of an optimizer answer (values left None are derived by the analysis)."""
    cls = spec.design_class
    return cls(**{k: design[k] for k in cls.VARIABLES if design.get(k) is not None})


def closed_form_check(spec, design: dict[str, float], requirements: dict[str, float]) -> dict:
    try:
        analysis = analyse(spec.scene, _design_point(spec, design), spec.verification.stages)
    except (ValueError, TypeError) as exc:  # the design cannot even be built
        return {"passed": False, "failures": [f"design rejected: {exc}"], "analysis": None}
    failures = list(analysis.problems)
    for name, value in analysis.margins.items():
        need = required(name, requirements, spec.kind)
        if value < need - CHECK_TOL:
            failures.append(f"margin {name} = {value:.6g} is below the required {need:.6g}")
    return {"passed": not failures, "failures": failures, "analysis": analysis}


def offset_samples(names, groups, tau: float, count: int, seed: int = 0) -> np.ndarray:
    """Offsets inside the box |d| <= tau: alternating patterns, random corners, uniform."""
    n = len(names)
    rng = np.random.default_rng(seed)
    alt = np.array([1.0 if i % 2 else -1.0 for i in range(n)])
    patterns = [np.zeros(n), np.ones(n), -np.ones(n), alt, -alt]
    for g in groups.values():  # one group alternating, the other fixed at each end
        for sign in (1.0, -1.0):
            v = np.zeros(n)
            v[list(g)] = alt[list(g)] * sign
            patterns.append(v)
    count = max(count, len(patterns))
    corners = rng.choice([-1.0, 1.0], size=(count // 2, n))
    uniform = rng.uniform(-1.0, 1.0, size=(count - count // 2 - len(patterns), n))
    return tau * np.vstack([np.array(patterns), corners, uniform])


def sampled_offsets_check(form, x, p, tau: float, *, samples: int = 256, seed: int = 0) -> dict:
    if hasattr(form.scenario_source, "stream"):  # a row of stage maps: streamed
        return _streamed_check(form, x, p, tau, samples, seed)
    sc = form.scenario
    D = offset_samples(sc.offset_names, sc.groups, 1.0, samples, seed)
    widths = np.broadcast_to(np.asarray(tau, dtype=float), (len(sc.groups),))
    for width, columns in zip(widths, sc.groups.values()):  # each group's own half-width
        D[:, list(columns)] *= width
    fn = sc.function.map(D.shape[0])
    slack, scale = (np.asarray(v, dtype=float) for v in fn(np.tile(np.asarray(x)[:, None],
                                                                   (1, D.shape[0])), D.T))
    required = dict(zip(form.p_names, np.asarray(p, dtype=float).ravel()))
    r = np.array([max((required.get(k, 0.0) for k in info.keys), default=0.0)
                  if info.kind == "margin" else 0.0 for info in sc.conditions])
    with np.errstate(divide="ignore", invalid="ignore"):
        excess = slack / np.where(scale != 0, scale, 1.0) - r[:, None]
    excess = np.where(np.isfinite(excess), excess, -np.inf)
    i, j = np.unravel_index(np.argmin(excess), excess.shape)
    worst = float(excess[i, j])
    return {"passed": worst >= -CHECK_TOL, "samples": int(D.shape[0]),
            "tolerance": float(tau) if np.ndim(tau) == 0 else dict(zip(sc.groups, widths)),
            "worst_excess_margin": worst, "worst_condition": sc.conditions[i].label,
            "worst_offsets": dict(zip(sc.offset_names, D[j].tolist()))}


# The streamed check's fixed patterns, per pivot K (1-based): (name, dx sign, dy sign), a sign
# "alt" alternating along the row (+ on odd pivots).
PATTERNS = (("nominal", 0, 0), ("all +", 1, 1), ("all -", -1, -1), ("alternating", "alt", "alt"),
            ("alternating, opposite", "-alt", "-alt"), ("dx alternating", "alt", 0),
            ("dx alternating, opposite", "-alt", 0), ("dy alternating", 0, "alt"),
            ("dy alternating, opposite", 0, "-alt"), ("dy alternating, dx +", 1, "alt"),
            ("dy alternating, dx -", -1, "alt"))


def _pattern_value(sign, K: int) -> float:
    alt = 1.0 if K % 2 else -1.0
    return {"alt": alt, "-alt": -alt}.get(sign, sign)


def _streamed_check(form, x, p, tau, samples: int, seed: int) -> dict:
    """sampled_offsets_check of a scene whose scenario source streams its stage maps (the
    scene's formulation): the fixed patterns, random corners and uniform points, each stage's
    offsets drawn when the row reaches it. Memory flat in the stages.
    tau: the box's half-width, or (dx, dy) half-widths of an allocated box."""
    half = np.broadcast_to(np.asarray(tau, dtype=float), (2,))
    stages = form.scenario_source
    count = max(samples, len(PATTERNS))
    corners = count // 2
    uniform = count - corners - len(PATTERNS)
    rng = np.random.default_rng(seed)

    def offsets(K):
        pattern = np.array([[_pattern_value(sx, K), _pattern_value(sy, K)]
                            for _, sx, sy in PATTERNS])
        drawn = np.vstack([rng.choice([-1.0, 1.0], size=(corners, 2)),
                           rng.uniform(-1.0, 1.0, size=(uniform, 2))])
        both = half * np.vstack([pattern, drawn])
        return both[:, 0], both[:, 1]

    required = dict(zip(form.p_names, np.asarray(p, dtype=float).ravel()))
    worst = stages.stream(x, required, offsets, count, parked=_parked_reach(form, x))
    j = worst["sample"]
    which = (PATTERNS[j][0] if j < len(PATTERNS) else f"random corner {j - len(PATTERNS) + 1}"
             if j < len(PATTERNS) + corners else f"uniform point {j - len(PATTERNS) - corners + 1}")
    return {"passed": worst["value"] >= -CHECK_TOL, "samples": count,
            "tolerance": float(tau) if np.ndim(tau) == 0 else dict(zip(form.tolerance_axes, half)),
            "worst_excess_margin": worst["value"], "worst_condition": worst["label"],
            "worst_sample": which, "worst_stage": worst["stage"]}


def _parked_reach(form, x) -> int:
    """The parts behind the object that can still reach it at design x (the stage maps' `reach`
    at the design's values): those further back never can."""
    return form.scenario_source.reach(form.design_values(x))
