"""Continuation of the gait over the slope, and where its multipliers leave the unit circle.

`sweep` follows the period-1 gait from slope to slope (Newton's method from the secant
prediction of the last two gaits) and watches three test functions of the return map's 4 x 4
Jacobian J (its trivial zero eigenvalue contributes a factor 1 or -1 to each):
    det(J + I)        changes sign where a real multiplier passes -1: period doubling
    det(J - I)        changes sign where a real multiplier passes +1: fold
    |complex pair|-1  changes sign where a complex pair leaves the circle: Neimark-Sacker
Each crossing is refined by Brent's method on the slope to REFINE_TOL. Where the branch ends
(Newton's method no longer converges from its continuation) between two slopes, the end is
found by bisection, to the same tolerance, and reported as a fold when det(J - I) is near 0 there
(a multiplier near +1: the branch turns back). Past a period doubling the period-2 gait is found
at every slope (the two-step map's root) and followed.
"""

from __future__ import annotations

import math

import numpy as np

from ...sim.numerics import RootError, brentq
from . import physics as phys
from . import stepmap
from .gait import _step_time, _two_step_gait, find_gait, period_two
from .ground import ground_of, params_for

REFINE_TOL = 1e-6  # rad: bifurcations are reported to better than 1e-5
FOLD_NEAR = 0.05  # |det(J - I)| below this where a branch ends: a fold


def _design_at(design, slope):
    from dataclasses import replace

    return replace(design, slope=float(slope))


def _tests(gait) -> dict[str, float]:
    J = gait.jacobian
    eye = np.eye(4)
    pairs = [abs(m) for m in gait.multipliers if abs(m.imag) > 1e-12]
    return {"period_doubling": float(np.linalg.det(J + eye)),
            "fold": float(np.linalg.det(J - eye)),
            "neimark_sacker": (max(pairs) - 1.0) if pairs else math.nan}


class _Branch:
    """Solves the period-1 gait at any slope by continuation from the nearest solved one."""

    def __init__(self, scene, design):
        self.scene, self.design = scene, design
        self.solved: dict[float, stepmap.Gait] = {}

    def at(self, slope, guess=None) -> stepmap.Gait | None:
        if slope in self.solved:
            return self.solved[slope]
        d = _design_at(self.design, slope)
        params = params_for(self.scene, d)
        ground = ground_of(d, params)
        start = guess or self._predict(slope)
        try:
            if start is None:
                gait = find_gait(self.scene, d)
            else:
                gait = stepmap.gait_at(params, ground,
                                       *stepmap.solve_periodic(params, ground, *start))
        except stepmap.GaitNotFound:
            return None
        self.solved[slope] = gait
        return gait

    def _predict(self, slope):
        """(state, step time): linear through the two solved slopes nearest to `slope`."""
        near = sorted(self.solved, key=lambda s: abs(s - slope))[:2]
        if not near:
            return None
        vec = {s: np.array([*self.solved[s].state, self.solved[s].step_period]) for s in near}
        if len(near) == 1 or near[0] == near[1]:
            z = vec[near[0]]
        else:
            a, b = near
            z = vec[a] + (vec[b] - vec[a]) * (slope - a) / (b - a)
        return z[:4], float(z[4])


def sweep(scene, design, slopes, *, guess=None, period_two_gaits: bool = True) -> dict:
    """Continue the period-1 gait over `slopes` (rad, in the order given). Returns
    {"parameter": "slope", "points": [...], "bifurcations": [{parameter, value, kind}],
    "period_two": [...]}: each point the gait's JSON (stepmap.Gait.to_json) with its slope and
    "stable", or {"slope", "gait": None} where the branch does not reach."""
    slopes = [float(s) for s in slopes]
    branch = _Branch(scene, design)
    points, found, last = [], [], None
    first = guess
    for slope in slopes:
        gait = branch.at(slope, None if first is None else (np.asarray(first, dtype=float),
                                                            _first_time(scene, design, slope,
                                                                        first)))
        first = None
        if gait is None:
            points.append({"slope": slope, "gait": None})
            if last is not None:
                found.extend(_branch_end(branch, last, slope))
                last = None
            continue
        points.append({"slope": slope, "stable": gait.stable, **gait.to_json()})
        if last is not None:
            found.extend(_crossings(branch, last, slope))
        last = slope
    result = {"parameter": "slope", "points": points,
              "bifurcations": sorted(found, key=lambda b: b["value"]), "period_two": []}
    if period_two_gaits:
        result["period_two"] = _period_two_branch(scene, design, branch, slopes)
    return result


def _first_time(scene, design, slope, state):
    d = _design_at(design, slope)
    params = params_for(scene, d)
    return _step_time(scene, params, ground_of(d, params), np.asarray(state, dtype=float))


def _crossings(branch, a, b):
    """The bifurcations between two solved slopes a and b, refined."""
    ta, tb = _tests(branch.solved[a]), _tests(branch.solved[b])
    out = []
    for kind in ("period_doubling", "fold", "neimark_sacker"):
        fa, fb = ta[kind], tb[kind]
        if not (math.isfinite(fa) and math.isfinite(fb)) or (fa > 0) == (fb > 0):
            continue
        try:
            value = brentq(lambda s, kind=kind: _test_at(branch, s, kind), a, b,
                           xtol=REFINE_TOL)
        except RootError:
            continue
        out.append({"parameter": "slope", "value": value, "kind": kind})
    return out


def _test_at(branch, slope, kind):
    gait = branch.at(slope)
    if gait is None:
        return math.nan
    value = _tests(gait)[kind]
    return value


def _branch_end(branch, a, b):
    """Bisect between a (solved) and b (not) for the branch's end; a fold there when a
    multiplier is near +1."""
    while abs(b - a) > REFINE_TOL:
        mid = 0.5 * (a + b)
        if branch.at(mid) is not None:
            a = mid
        else:
            b = mid
    gait = branch.solved[a]
    if abs(_tests(gait)["fold"]) < FOLD_NEAR:
        return [{"parameter": "slope", "value": a, "kind": "fold"}]
    return [{"parameter": "slope", "value": a, "kind": "branch_end"}]


def _period_two_branch(scene, design, branch, slopes):
    """Period-2 gaits at every swept slope where the period-1 gait has a multiplier below -1,
    each continued from the last found."""
    out, previous = [], None
    for slope in slopes:
        gait = branch.solved.get(slope)
        if gait is None or min(m.real for m in gait.multipliers) > -1.0:
            previous = None
            continue
        d = _design_at(design, slope)
        params = params_for(scene, d)
        ground = ground_of(d, params)
        two = None
        if previous is not None:
            try:
                two = _two_step_gait(params, ground, *previous)
            except stepmap.GaitNotFound:
                two = None
        two = two or period_two(params, ground, gait)
        if two is None:
            previous = None
            continue
        previous = _two_guess(params, ground, two)
        lengths = [float(phys.step_length(s[1], s[0], params)) for s in previous[:2]]
        out.append({"slope": slope, "stable": two.stable, "step_lengths": lengths,
                    **two.to_json()})
    return out


def _two_guess(params, ground, two):
    """(x_a, x_b, T_a, T_b) of a solved period-2 gait, to start the next slope's Newton."""
    xa = np.asarray(two.state)
    Ta = _step_time(None, params, ground, xa)
    _, xb, _ = stepmap.step(params, ground, xa, Ta)
    return xa, xb, Ta, two.step_period - Ta


def plot_sweep(result: dict, path) -> None:
    """The classic picture: step length against slope, the period-1 branch solid where stable
    and dashed where not, the period-2 gaits' two step lengths as dots, bifurcations marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    pts = [p for p in result["points"] if p.get("gait", True) is not None]
    deg = [math.degrees(p["slope"]) for p in pts]
    length = [p["step_length"] for p in pts]
    stable = np.array([p["stable"] for p in pts])
    ax.plot(np.where(stable, deg, np.nan), np.where(stable, length, np.nan), "k-",
            label="period 1, stable")
    ax.plot(np.where(~stable, deg, np.nan), np.where(~stable, length, np.nan), "k--",
            label="period 1, unstable")
    two = result.get("period_two", [])
    if two:
        for key, mark in ((True, "o"), (False, "x")):
            sel = [p for p in two if p["stable"] == key]
            xs = [math.degrees(p["slope"]) for p in sel for _ in (0, 1)]
            ys = [v for p in sel for v in p["step_lengths"]]
            if xs:
                ax.plot(xs, ys, mark, ms=3, label=f"period 2, {'stable' if key else 'unstable'}")
    for b in result["bifurcations"]:
        ax.axvline(math.degrees(b["value"]), color="0.6", lw=0.8)
        ax.annotate(b["kind"].replace("_", " "), (math.degrees(b["value"]), ax.get_ylim()[1]),
                    rotation=90, va="top", ha="right", fontsize=8, color="0.4")
    ax.set_xlabel("slope (deg)")
    ax.set_ylabel("step length (m)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def table_files(spec, axes, *, plots: bool) -> dict[str, bytes]:
    """`pdm-design table SPEC --sweep slope=...` of a fixed walker: {"bifurcations.json": the
    continuation's {parameter, bifurcations [{parameter, value, kind}], period_two, points},
    "bifurcation.png": the classic figure}; nothing for another sweep."""
    import json
    import tempfile
    from pathlib import Path

    if len(axes) != 1 or axes[0].path != ("design", "slope") or spec.free_variables:
        return {}
    found = sweep(spec.scene, spec.design_at({}), list(axes[0].values))
    files = {"bifurcations.json": (json.dumps(found, indent=1, default=float) + "\n").encode()}
    if plots:
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "bifurcation.png"
            plot_sweep(found, path)
            files["bifurcation.png"] = path.read_bytes()
    return files
