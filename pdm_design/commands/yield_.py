"""`pdm-design yield`: the spec's design, its tolerances, the Monte Carlo yield, and its
report (text, JSON, plots). Also the `simulate --build SEED:INDEX` reproduction of one build."""

from __future__ import annotations

import dataclasses
import json

from ..errors import PdmError, SpecError
from ..tolerance_model import quantities_of
from ..tolerances.yield_ import YieldResult, yield_of

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
        _refuse(spec, source, tol.quantity)
    return spec.tolerances


def _refuse(spec, source, quantity):
    """A tolerance the scene cannot draw builds of (Scene.tolerance_refusal; exit 2): a
    quantity its physics leaves out, a nominal of 0 that every part drawn around would fall
    below."""
    from ..plugin import of

    refusal = of(spec).tolerance_refusal(spec, quantity)
    if refusal is not None:
        key, expected, found = refusal
        raise SpecError(source, key, expected, found)


def design_point(spec, source: str):
    """The fixed design, or the optimizer's (exit 1 in words when it finds none)."""
    return design_answer(spec, source)[0]


def design_answer(spec, source: str):
    """(the fixed design, None), or (the optimizer's design, its DesignOutcome); exit 1 in
    words when it finds none."""
    if not spec.free_variables:
        return spec.design_at(), None
    from ..api import design

    found = design(spec, verify=False)
    if not found.status.is_success:
        raise PdmError(f"{source}: no design to build: the optimizer found none that meets "
                       f"every requirement (status {found.status.value}: "
                       f"{found.status_message})")
    return spec.design_at(found.analysis.design), found


def sized_tolerances(spec, source, point, stages, *, accuracy=None, answer=None):
    """The spec's tolerances, those to allocate sized for tolerances.yield_target and checked
    by Monte Carlo (solve/yield_check.py): optimize's own values when `answer` (its outcome at
    `point`) has them for these stages, else the linearised yield's size at `point`
    (solve/yield_allocation.py) shrunk until the Monte Carlo interval's lower end reaches the
    target; exit 1 in words when no size meets it. The same values for the yield run, `check`
    and `simulate --build`."""
    tolerances = spec_tolerances(spec, source)
    if not any(t.allocate for t in tolerances):
        return tolerances
    from ..solve.yield_check import check_allocation, valued

    if (answer is not None and answer.tolerances_yield is not None
            and stages == spec.verification.stages):
        return valued(spec, answer.tolerances)
    from ..accuracy import accuracy as resolve
    from ..solve.yield_allocation import allocate_for_yield

    try:
        allocation = allocate_for_yield(spec.scene, point, tolerances, stages=stages)
    except ValueError as error:
        raise PdmError(f"{source}: {error}") from None
    checked = check_allocation(spec.scene, point, allocation.tolerances,
                               {t.quantity for t in tolerances if t.allocate},
                               target=allocation.target, stages=stages,
                               accuracy=resolve(accuracy or spec.verification.accuracy))
    if not checked.met:
        raise PdmError(f"{source}: {checked.words}")
    return checked.tolerances


def run_yield(spec, source: str, *, builds=None, stages=None, seed=None, accuracy=None,
              scales=None, workers=None, scheduler=None) -> YieldResult:
    """The yield of the spec's design (the Python API of `pdm-design yield`); workers and
    scheduler: where the simulated builds run (tolerances.parallel), the result the same."""
    from ..accuracy import accuracy as resolve

    spec_tolerances(spec, source)
    point, answer = design_answer(spec, source)
    stages = stages or spec.verification.stages
    acc = resolve(accuracy or spec.verification.accuracy)
    tolerances = sized_tolerances(spec, source, point, stages, accuracy=acc, answer=answer)
    builds = builds or tolerances.builds
    seed = tolerances.seed if seed is None else seed
    kwargs = {} if scales is None else {"scales": scales}
    result = yield_of(spec.scene, point, tolerances, builds=builds, stages=stages, seed=seed,
                      confirm=tolerances.confirm, accuracy=acc, source=source,
                      allow_skips=spec.verification.allow_skips, workers=workers,
                      scheduler=scheduler, **kwargs)
    return dataclasses.replace(result, identity=yield_identity(spec, source, point))


YIELD_SCHEMA = "pdm-design/yield/1"


def yield_identity(spec, source: str, point) -> dict:
    """What a yield run was made from, for its JSON document (docs/json-schema.md): the
    schema, the spec's path and digest (spec.loader.content_digest), name and scene kind,
    and the design the builds were drawn around (every variable, SI; null for one the
    scene derives)."""
    return {"schema": YIELD_SCHEMA, "spec": source, "spec_sha256": spec.digest or None,
            "name": spec.name, "scene": spec.kind,
            "design": {v: getattr(point, v) for v in point.VARIABLES}}  # null: derived


def unmet_min_yield(outcome) -> list[str]:
    """`check`'s [expect] min_yield: the 95 % interval's lower end must reach it (the builds,
    seed and stages are the spec's, so the verdict is reproducible)."""
    spec, wanted = outcome.spec, outcome.spec.expect.min_yield
    if not outcome.status.is_success:
        return [f"expected a yield of at least {_pct(wanted)}, got none (no design: status "
                f"{outcome.status.value})"]
    point = spec.design_at(outcome.analysis.design)
    tolerances = sized_tolerances(spec, spec.source, point, spec.verification.stages,
                                  accuracy=outcome.accuracy, answer=outcome)
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
                           record_trajectory=False, tolerances=None, answer=None):
    """`simulate --build SEED:INDEX`: build INDEX of a yield run with SEED and `stages`;
    tolerances: those the run drew with (its yield.json's), else the spec's, sized (answer:
    the spec's optimize outcome, when it was solved for the build)."""
    from ..accuracy import accuracy as resolve
    from ..tolerances.yield_ import simulate_one

    seed, index = parse_build(build)
    accuracy = resolve(accuracy or spec.verification.accuracy)
    if tolerances is None:
        tolerances = sized_tolerances(spec, source, design, stages, accuracy=accuracy,
                                      answer=answer)
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


NEGLIGIBLE_INDEX = 1e-3  # a Sobol' index below this with no interval (noise, 5e-30) prints as 0
UNRESOLVED = "not resolved by the builds drawn: its 95 % interval includes 0"


def _index_text(row: dict) -> str:
    """A Sobol' total index as text: the index and its 95 % confidence half width, and in words
    when the builds drawn do not resolve it (the half width as large as the index: its interval
    includes 0); 0 for an index below NEGLIGIBLE_INDEX with no interval (rounding noise), the
    index alone where it has no interval (one quantity: 1 by definition)."""
    index, half = row["index"], row.get("confidence", 0.0) or 0.0
    if not half > 0.0:
        return "0" if not index >= NEGLIGIBLE_INDEX else f"{index:.3g}"
    shown = f"{index:.2g} +- {half:.2g}"
    return shown if index > half else f"{shown} ({UNRESOLVED})"


def _sensitivity_line(rows) -> str:
    """The text report's sensitivity line: every quantity, largest total index first."""
    ordered = sorted(rows, key=lambda row: -row["index"])
    return ("sensitivity (Sobol' total index of the smallest margin, largest first, +- its 95 % "
            "confidence half width): " + ", ".join(f"{s['quantity']} {_index_text(s)}"
                                                   for s in ordered))


def yield_text(result: YieldResult, name: str) -> str:
    r = result
    from ..units import counted

    lines = [f"{name} ({r.kind}): {counted(r.builds, 'build')} of {counted(r.stages, 'stage')}, "
             f"seed {r.seed}",
             f"yield: {_pct(r.estimate)} pass all {r.stages} stages "
             f"(95 % interval {_pct(r.ci_low)} to {_pct(r.ci_high)})",
             f"mean stages before failure: {r.mean_stages_before_failure:.4g} of {r.stages}"]
    if "mfpt" in r.extras:  # a rare-failure estimate of the scene's (Scene.yield_extras)
        m = r.extras["mfpt"]
        lines.append(f"mean steps before failure, unbounded: {m['estimate']:.4g} "
                     f"({m['ci_low']:.4g} to {m['ci_high']:.4g}; {m['method']})")
    marks = sorted({1, max(1, r.stages // 4), max(1, r.stages // 2), r.stages})
    lines.append("still going after stage " + ", ".join(
        f"{k}: {_pct(r.survival[k - 1])}" for k in marks))
    if r.failures:
        lines.append("failures: " + ", ".join(f"{k} {v}" for k, v in r.failures.items()))
    lines.append("tolerances (build units):")
    for t in r.tolerances:
        q = quantities_of(r.kind)[t["quantity"]]
        size = f"+-{t['value'] * q.build_factor:.4g}" + (
            "" if q.build_unit == "1" else f" {q.build_unit}")  # dimensionless: no unit
        lines.append(f"  {t['quantity']:<14} {size:<16} {t['applies_to']:<5} {t['distribution']}")
    c = r.confirmed
    curve = sum(p["simulated"] for p in r.scale_curve if p["scale"] != 1.0)
    lines.append(f"event simulator: {c['agreed']} of {counted(c['random'], 'random build')} "
                 f"agree{'s' if c['agreed'] == 1 else ''} with the closed forms; "
                 f"{counted(c['left_closed_form'], 'build')} outside the closed forms "
                 f"simulated; {counted(c['simulated'] + curve, 'build')} simulated in all"
                 + (f" ({curve} of them for the yield against tolerance scale)" if curve else ""))
    if r.sensitivity:
        lines.append(_sensitivity_line(r.sensitivity))
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
        from ..tolerances.sensitivity import sensitivity_figure

        fig = sensitivity_figure(list(r.sensitivity), title="which tolerance matters most "
                                 f"(smallest margin over {r.stages} stages)")
        out["sensitivity.png"] = render_figure(fig, "png")
    return out


def commands_from(result: YieldResult, folder: str) -> YieldResult:
    """The result with each failing build's command taking the design from `folder` (the
    run's --out: `simulate --from`), so that rerunning a build solves nothing again."""
    import shlex

    failing = tuple({**f, "command": f"{f['command']} --from {shlex.quote(str(folder))}"}
                    for f in result.failing)
    return dataclasses.replace(result, failing=failing)


def write_outputs(result: YieldResult, folder: str) -> list[str]:
    """yield.json and the figures in `folder`, whole or not at all."""
    from pathlib import Path

    from ..io import write_all

    files = {Path(folder) / "yield.json": yield_json(result) + "\n"}
    files.update({Path(folder) / k: v for k, v in yield_figures(result).items()})
    write_all(files)
    return [str(p) for p in files]
