"""Which tolerance matters most: variance-based (Sobol') sensitivity indices of a build map.

The output Y of a batch of builds (their smallest margin, or whether they passed) is a function
of every deviation drawn. Sobol' indices split its variance among the tolerances: the first-order
index S1 of a quantity is the share of Var(Y) its deviations explain alone, the total-order index
ST the share they take part in, interactions included (SALib: Saltelli's sampling on a scrambled
Sobol' sequence, the estimators of Saltelli et al. 2010, bootstrap confidence intervals). A
quantity toleranced per part (every step's rise, every stage's pivot) is one group: its
index is that of all its parts together, which is what a workshop tightens. The build map is
any callable run(deviations, stages) -> BuildOutcome (`pdm_design.tolerances.run_builds` with
its scene and design bound: the yield passes the scene's map, Scene.run_builds), so the same
code serves every scene.

Distributions, as the tolerance convention states them: "normal" draws N(0, (t/3)^2), "uniform"
draws U(-t, t). A quantity with tolerance 0 does not vary and its indices are 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from ..tolerance_model import APPLIES_TO, DISTRIBUTIONS

OUTPUTS = ("min_margin", "pass")


def sobol_indices(run: Callable, tolerances: Iterable, *, stages: int, parts: int | None = None,
                  samples: int = 1024, seed: int = 0, output: str = "min_margin",
                  resamples: int = 100) -> list[dict]:
    """Sobol' indices of each toleranced quantity, largest total-order index first.

    tolerances: (quantity, applies_to, value, distribution) tuples, or objects with those
    attributes; applies_to "each" (one value per part) or "lot" (one per build); value t >= 0
    (SI). parts: how many parts an "each" quantity has (default: stages). samples: base sample
    size, rounded up to a power of two (the Sobol' sequence's balance); the map runs
    samples x (quantities + 2) builds. output: "min_margin" (BuildOutcome.min_margin) or "pass"
    (1 where the build passed). Returns [{quantity, index (ST), first (S1), confidence (half
    width of ST's 95 % bootstrap interval)}]. When the output does not vary at all every index is
    0: no tolerance moves it.
    """
    if output not in OUTPUTS:
        raise ValueError(f"output must be one of {', '.join(OUTPUTS)}, not {output!r}")
    if samples < 2:
        raise ValueError(f"samples must be >= 2, not {samples}")
    items = _tolerances(tolerances)
    parts = int(stages if parts is None else parts)
    active = [t for t in items if t[2] > 0.0]
    zero = {t[0]: (0.0, 0.0, 0.0) for t in items}
    if not active:
        return _table(zero)
    problem = _problem(active, parts)
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample

    base = 1 << max(1, math.ceil(math.log2(samples)))
    if len(active) == 1:
        # one quantity explains all the variance there is: S1 = ST = 1 by definition, once it
        # moves the output at all (SALib reads one group as none: its sample would take every
        # part as its own variable, and its analysis expects another sample's size); the
        # builds of the 3-group sample's size, drawn as the yield draws them
        x = _drawn(problem, 3 * base, seed)
    else:
        x = sample.sample(problem, base, calc_second_order=False, seed=seed)
    outcome = run(_deviations(x, active, parts), stages)
    y = np.asarray(outcome.min_margin if output == "min_margin" else outcome.passed,
                   dtype=float)
    if not np.all(np.isfinite(y)):
        raise ValueError("the build map returned a non-finite output: no variance to split")
    if np.ptp(y) == 0.0:
        return _table(zero)
    if len(active) == 1:
        return _table({**zero, active[0][0]: (1.0, 1.0, 0.0)})
    # SALib's analysis seeds its bootstrap only with a true seed (0 would leave it unseeded)
    si = analyze.analyze(problem, y, calc_second_order=False, num_resamples=resamples,
                         seed=seed + 1)
    found = {t[0]: (float(si["ST"][i]), float(si["S1"][i]), float(si["ST_conf"][i]))
             for i, t in enumerate(active)}
    return _table({**zero, **found})


def _tolerances(tolerances) -> list[tuple[str, str, float, str]]:
    out, seen = [], set()
    for t in tolerances:
        if isinstance(t, (tuple, list)):
            q, applies, value, dist = t
        else:
            q, applies, value, dist = t.quantity, t.applies_to, t.value, t.distribution
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"tolerance of {q}: value must be a finite number >= 0, not "
                             f"{value!r}") from None
        if applies not in APPLIES_TO:
            raise ValueError(f"tolerance of {q}: applies_to must be one of "
                             f"{', '.join(APPLIES_TO)}, not {applies!r}")
        if dist not in DISTRIBUTIONS:
            raise ValueError(f"tolerance of {q}: distribution must be one of "
                             f"{', '.join(DISTRIBUTIONS)}, not {dist!r}")
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"tolerance of {q}: value must be a finite number >= 0, not {value}")
        if q in seen:
            raise ValueError(f"tolerance of {q} is given twice")
        seen.add(q)
        out.append((str(q), applies, value, dist))
    return out


def _problem(active, parts) -> dict:
    names, groups, bounds, dists = [], [], [], []
    for q, applies, t, dist in active:
        count = parts if applies == "each" else 1
        for i in range(count):
            names.append(f"{q}[{i + 1}]" if applies == "each" else q)
            groups.append(q)
            # SALib: "norm" takes [mean, standard deviation], "unif" [low, high]
            bounds.append([0.0, t / 3.0] if dist == "normal" else [-t, t])
            dists.append("norm" if dist == "normal" else "unif")
    return {"num_vars": len(names), "names": names, "groups": groups, "bounds": bounds,
            "dists": dists}


def _drawn(problem: dict, builds: int, seed: int) -> np.ndarray:
    """`builds` rows of the problem's variables drawn from their distributions."""
    rng = np.random.default_rng(seed)
    columns = [rng.normal(a, b, builds) if d == "norm" else rng.uniform(a, b, builds)
               for (a, b), d in zip(problem["bounds"], problem["dists"])]
    return np.column_stack(columns)


def _deviations(x, active, parts) -> dict[str, np.ndarray]:
    out, col = {}, 0
    for q, applies, _, _ in active:
        if applies == "each":
            out[q] = np.ascontiguousarray(x[:, col:col + parts])
            col += parts
        else:
            out[q] = x[:, col].copy()
            col += 1
    return out


def _table(values: dict) -> list[dict]:
    rows = [{"quantity": q, "index": st, "first": s1, "confidence": conf}
            for q, (st, s1, conf) in values.items()]
    return sorted(rows, key=lambda row: -row["index"])


def sensitivity_figure(indices: list[dict], *, title: str | None = None):
    """Bar chart of the indices (`sobol_indices`' list): total-order index with its confidence
    interval, first-order beside it, largest on top (a matplotlib Figure)."""
    from matplotlib.figure import Figure

    rows = list(reversed(indices))
    fig = Figure(figsize=(7, 1.2 + 0.45 * max(len(rows), 1)), layout="constrained")
    ax = fig.subplots()
    y = np.arange(len(rows))
    ax.barh(y + 0.2, [r["index"] for r in rows], height=0.4, xerr=[r["confidence"] for r in rows],
            color="tab:blue", label="total order (ST)", capsize=3)
    ax.barh(y - 0.2, [r["first"] for r in rows], height=0.4, color="tab:orange",
            label="first order (S1)")
    ax.set_yticks(y, [r["quantity"] for r in rows])
    right = max([1.0] + [r["index"] + r["confidence"] for r in rows]) + 0.05
    ax.set(xlabel="share of the output's variance", xlim=(0.0, right),
           title=title or "which tolerance matters most (Sobol' indices)")
    ax.grid(axis="x", alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    return fig


def plot_sensitivity(indices: list[dict], path, *, title: str | None = None,
                     dpi: int = 120) -> Path:
    """`sensitivity_figure` as a PNG at `path`, whole or not at all."""
    from ..io import write_atomic
    from ..report.render import render_figure

    path = Path(path)
    write_atomic(path, render_figure(sensitivity_figure(indices, title=title), "png", dpi=dpi))
    return path
