"""`pdm-design yield`: the spec's design, its tolerances, the Monte Carlo yield, and its
report (text, JSON, plots). Also the `simulate --build SEED:INDEX` reproduction of one build."""

from __future__ import annotations

import json

from ..errors import PdmError, SpecError
from .model import QUANTITIES
from .yield_ import YieldResult, yield_of

SHOWN_IN_TEXT = 5  # failing builds whose simulate command the text report prints


def spec_tolerances(spec, source: str):
    """The spec's tolerances, each with a value (else SpecError, exit 2)."""
    if not spec.tolerances:
        raise SpecError(source, "tolerances", "a [tolerances] table with at least one quantity "
                        "and its value (docs/tolerances.md)", "none")
    sized = spec.tolerances.yield_target is not None
    for tol in spec.tolerances:
        if tol.value is None and not sized:
            raise SpecError(source, f"tolerances.{tol.quantity}.value", "a value (+-, SI) for "
                            "a yield: allocate = true asks the optimizer for one, or "
                            "tolerances.yield_target",
                            "allocate = true")
        if spec.kind == "stairs" and tol.quantity == "friction" and spec.scene.ball.radius == 0:
            raise SpecError(source, "tolerances.friction", "no friction tolerance for a point "
                            "ball (a ball of radius 0 cannot roll: give scene.ball a radius)",
                            "scene.ball.radius = 0")
        _refuse_zero_nominal(spec, source, tol.quantity)
    return spec.tolerances


# Quantities whose nominal may be 0, where a +- tolerance around it means nothing (half the
# parts below a physical limit): (scene kind, quantity) -> (the nominal, the key that sets it)
_ZERO_NOMINALS = {
    ("manipulators", "link_mass"): (lambda s: s.scene.links.mass, "a [scene.links] mass"),
    ("manipulators", "pivot_friction"): (lambda s: s.scene.pivots.friction_torque,
                                         "a [scene.pivots] friction_torque"),
    ("manipulators", "friction"): (lambda s: s.scene.palm.friction, "a scene.palm.friction"),
    ("stairs", "friction"): (lambda s: s.scene.friction, "a scene.friction"),
}


def _refuse_zero_nominal(spec, source, quantity):
    """A tolerance on a quantity whose nominal is 0 (exit 2): links of no mass, pivots with no
    friction, a frictionless material; every part drawn from it would be below 0 or at 0."""
    found = _ZERO_NOMINALS.get((spec.kind, quantity))
    if found is None or found[0](spec) > 0.0:
        return
    name = quantity.replace("_", " ")
    raise SpecError(source, f"tolerances.{quantity}", f"{found[1]} > 0: the nominal {name} is "
                    "0, and a tolerance around 0 draws half the parts below it (give the "
                    "nominal, or drop the tolerance)", f"nominal {name} = 0")


def design_point(spec, source: str):
    """The fixed design, or the optimizer's (exit 1 in words when it finds none)."""
    if not spec.free_variables:
        return spec.design_at()
    from ..api import design

    found = design(spec, verify=False)
    if not found.status.is_success:
        raise PdmError(f"{source}: no design to build: the optimizer found none that meets "
                       f"every requirement (status {found.status.value})")
    return spec.design_at(found.analysis.design)


def sized_tolerances(spec, source, point, stages):
    """The spec's tolerances, those to allocate sized for tolerances.yield_target by the
    linearised yield at `point` (solve/yield_allocation.py; exit 1 in words when no size
    meets it): the same values for the yield run, `check` and `simulate --build`."""
    tolerances = spec_tolerances(spec, source)
    if not any(t.allocate for t in tolerances):
        return tolerances
    from ..solve.yield_allocation import allocate_for_yield

    try:
        return allocate_for_yield(spec.scene, point, tolerances, stages=stages).tolerances
    except ValueError as error:
        raise PdmError(f"{source}: {error}") from None


def run_yield(spec, source: str, *, builds=None, stages=None, seed=None, accuracy=None,
              scales=None) -> YieldResult:
    """The yield of the spec's design (the Python API of `pdm-design yield`)."""
    from ..accuracy import accuracy as resolve

    spec_tolerances(spec, source)
    point = design_point(spec, source)
    stages = stages or spec.verification.stages
    tolerances = sized_tolerances(spec, source, point, stages)
    builds = builds or tolerances.builds
    seed = tolerances.seed if seed is None else seed
    acc = resolve(accuracy or spec.verification.accuracy)
    kwargs = {} if scales is None else {"scales": scales}
    return yield_of(spec.scene, point, tolerances, builds=builds, stages=stages, seed=seed,
                    confirm=tolerances.confirm, accuracy=acc, source=source,
                    allow_skips=spec.verification.allow_skips, **kwargs)


def unmet_min_yield(outcome) -> list[str]:
    """`check`'s [expect] min_yield: the 95 % interval's lower end must reach it (the builds,
    seed and stages are the spec's, so the verdict is reproducible)."""
    spec, wanted = outcome.spec, outcome.spec.expect.min_yield
    if not outcome.status.is_success:
        return [f"expected a yield of at least {_pct(wanted)}, got none (no design: status "
                f"{outcome.status.value})"]
    point = spec.design_at(outcome.analysis.design)
    tolerances = sized_tolerances(spec, spec.source, point, spec.verification.stages)
    r = yield_of(spec.scene, point, tolerances, builds=tolerances.builds,
                 stages=spec.verification.stages, seed=tolerances.seed,
                 confirm=tolerances.confirm, accuracy=outcome.accuracy or "default",
                 source=spec.source, scales=(), sensitivity_samples=0,
                 allow_skips=spec.verification.allow_skips)
    if r.ci_low >= wanted:
        return []
    return [f"yield {_pct(r.estimate)} (95 % interval from {_pct(r.ci_low)}) over "
            f"{r.stages} stages is not surely at least the expected {_pct(wanted)}"
            + (f"; failures: {', '.join(f'{k} {v}' for k, v in r.failures.items())}"
               if r.failures else f"; more builds than {r.builds} narrow the interval")]


def simulate_build_of_spec(spec, source, design, build: str, stages, *, accuracy,
                           record_trajectory=False):
    """`simulate --build SEED:INDEX`: build INDEX of a yield run with SEED and `stages`."""
    from ..accuracy import accuracy as resolve
    from .yield_ import simulate_one

    seed, index = parse_build(build)
    accuracy = resolve(accuracy or spec.verification.accuracy)
    tolerances = sized_tolerances(spec, source, design, stages)
    return simulate_one(spec.scene, design, tolerances, seed, index, stages,
                        accuracy=accuracy, record_trajectory=record_trajectory,
                        allow_skips=spec.verification.allow_skips)


def parse_build(text: str) -> tuple[int, int]:
    try:
        seed, index = (int(v) for v in text.split(":"))
        if seed < 0 or index < 0:
            raise ValueError
    except ValueError:
        raise SpecError("command line", "--build", "SEED:INDEX, two integers >= 0 (as "
                        "`pdm-design yield` prints them), e.g. 0:17", repr(text)) from None
    return seed, index


# ------------------------------------------------------------------------------ output

def yield_json(result: YieldResult) -> str:
    return json.dumps(result.to_json(), indent=2)


def _pct(x: float) -> str:
    return f"{100.0 * x:.2f} %"


NEGLIGIBLE_INDEX = 1e-3  # a Sobol' index below this, or below its confidence, prints as ~0


def _index_text(row: dict) -> str:
    """A Sobol' total index as text: "~0" where it cannot be told from 0 (below its 95 %
    confidence half width or below NEGLIGIBLE_INDEX: sampling and rounding noise)."""
    index = row["index"]
    if not index >= max(NEGLIGIBLE_INDEX, row.get("confidence", 0.0) or 0.0):
        return "~0"
    return f"{index:.3g}"


def yield_text(result: YieldResult, name: str) -> str:
    r = result
    lines = [f"{name} ({r.kind}): {r.builds} builds of {r.stages} stages, seed {r.seed}",
             f"yield: {_pct(r.estimate)} pass all {r.stages} stages "
             f"(95 % interval {_pct(r.ci_low)} to {_pct(r.ci_high)})",
             f"mean stages before failure: {r.mean_stages_before_failure:.4g} of {r.stages}"]
    marks = sorted({1, max(1, r.stages // 4), max(1, r.stages // 2), r.stages})
    lines.append("still going after stage " + ", ".join(
        f"{k}: {_pct(r.survival[k - 1])}" for k in marks))
    if r.failures:
        lines.append("failures: " + ", ".join(f"{k} {v}" for k, v in r.failures.items()))
    lines.append("tolerances (build units):")
    for t in r.tolerances:
        q = QUANTITIES[r.kind][t["quantity"]]
        size = f"+-{t['value'] * q.build_factor:.4g}" + (
            "" if q.build_unit == "1" else f" {q.build_unit}")  # dimensionless: no unit
        lines.append(f"  {t['quantity']:<14} {size:<16} {t['applies_to']:<5} {t['distribution']}")
    c = r.confirmed
    curve = sum(p["simulated"] for p in r.scale_curve if p["scale"] != 1.0)
    lines.append(f"event simulator: {c['agreed']} of {c['random']} random builds agree with "
                 f"the closed forms; {c['left_closed_form']} builds outside the closed forms "
                 f"simulated; {c['simulated'] + curve} builds simulated in all"
                 + (f" ({curve} of them for the yield against tolerance scale)" if curve else ""))
    if r.sensitivity:
        lines.append("sensitivity (Sobol' total index of the smallest margin): " + ", ".join(
            f"{s['quantity']} {_index_text(s)}" for s in r.sensitivity))
    elif r.sensitivity_note:
        lines.append(f"sensitivity: {r.sensitivity_note}")
    if r.failing:
        lines.append("reproduce a failing build:")
        lines += [f"  {f['command']}   # {f['failure']} after {f['stages_passed']} stages"
                  for f in r.failing[:SHOWN_IN_TEXT]]
    return "\n".join(lines) + "\n"


def yield_figures(result: YieldResult) -> dict[str, bytes]:
    """survival.png (fraction still going after each stage, with its 95 % band),
    yield_scale.png (yield against a common scale of every tolerance) and sensitivity.png
    (the Sobol' indices as bars), each where the result has its data."""
    from matplotlib.figure import Figure

    from ..report.render import render_figure

    r = result
    out = {}
    fig = Figure(figsize=(6.0, 3.6), layout="constrained")
    ax = fig.subplots()
    stages = range(1, r.stages + 1)
    ax.fill_between(stages, r.survival_low, r.survival_high, color="C0", alpha=0.25,
                    label="95 % interval", step="mid")
    ax.step(stages, r.survival, where="mid", color="C0", label="still going")
    ax.set(xlabel="stage", ylabel="fraction of builds still going",
           title=f"survival of {r.builds} builds")
    ax.legend(loc="lower left")
    out["survival.png"] = render_figure(fig, "png")
    if r.scale_curve:
        fig = Figure(figsize=(6.0, 3.6), layout="constrained")
        ax = fig.subplots()
        xs = [s["scale"] for s in r.scale_curve]
        ys = [s["estimate"] for s in r.scale_curve]
        err = [[max(0.0, y - s["ci_low"]) for y, s in zip(ys, r.scale_curve)],
               [max(0.0, s["ci_high"] - y) for y, s in zip(ys, r.scale_curve)]]
        ax.errorbar(xs, ys, yerr=err, marker="o", capsize=3)
        counts = sorted({s["builds"] for s in r.scale_curve})
        ax.set(xlabel="tolerance scale (1 = the spec's)", ylabel=f"yield over {r.stages} stages",
               title="yield against tolerance scale ("
               + (f"{counts[0]} builds a point, {r.builds} at 1" if len(counts) > 1
                  else f"{counts[0]} builds a point") + ")")
        out["yield_scale.png"] = render_figure(fig, "png")
    if r.sensitivity:
        from .sensitivity import sensitivity_figure

        fig = sensitivity_figure(list(r.sensitivity), title="which tolerance matters most "
                                 f"(smallest margin over {r.stages} stages)")
        out["sensitivity.png"] = render_figure(fig, "png")
    return out


def write_outputs(result: YieldResult, folder: str) -> list[str]:
    """yield.json and the figures in `folder`, whole or not at all."""
    from pathlib import Path

    from ..io import write_all

    files = {Path(folder) / "yield.json": yield_json(result) + "\n"}
    files.update({Path(folder) / k: v for k, v in yield_figures(result).items()})
    write_all(files)
    return [str(p) for p in files]
