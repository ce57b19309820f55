"""The report page's yield section: the `pdm-design yield` document (docs/json-schema.md) as
numbers, failures by name and the yield command's own plots (survival with its 95 % band,
the Sobol' sensitivity bars, yield against tolerance scale); and the yield the report computes
itself from the spec's [tolerances] (docs/report.md)."""

from __future__ import annotations

import html
from types import SimpleNamespace


def is_yield_document(data) -> bool:
    """True for the document `pdm-design yield --format json` prints."""
    y = data.get("yield") if isinstance(data, dict) else None
    return isinstance(y, dict) and all(isinstance(y.get(k), (int, float))
                                       for k in ("estimate", "ci_low", "ci_high", "builds",
                                                 "stages"))


def spec_yield(spec, source: str):
    """The yield document of the design `spec` fixes, under its [tolerances] with the spec's
    builds, seed and stages (`pdm-design yield`'s run, which sizes the tolerances to allocate
    for a yield_target); (None, why) where the spec gives none or leaves a tolerance to the
    optimizer's worst-case allocation."""
    items = list(spec.tolerances or ())
    if not items:
        return None, "the spec has no [tolerances]"
    to_allocate = [t.quantity for t in items if t.value is None]
    sized = spec.tolerances.yield_target is not None  # sized for it by the yield run
    if to_allocate and not sized:
        return None, (f"{', '.join(to_allocate)} {'is' if len(to_allocate) == 1 else 'are'} "
                      "to be allocated (no value in the spec's [tolerances])")
    from ..commands.yield_ import run_yield

    return run_yield(spec, source).to_json(), ""


def yield_html(data: dict, data_uri) -> str:
    """The section's HTML of a `pdm-design yield` document; data_uri(png) -> an img src."""
    from ..commands.yield_ import yield_figures

    y = data["yield"]
    rows = [("yield (pass all stages)", f"{100 * y['estimate']:.2f} % (95 % interval "
             f"{100 * y['ci_low']:.2f} % to {100 * y['ci_high']:.2f} %)"),
            ("builds, stages, seed", f"{y['builds']}, {y['stages']}, {y.get('seed', '-')}")]
    if isinstance(data.get("mean_stages_before_failure"), (int, float)):
        rows.append(("mean stages before failure",
                     f"{data['mean_stages_before_failure']:.4g} of {y['stages']}"))
    confirmed = data.get("confirmed")
    if isinstance(confirmed, dict) and "agreed" in confirmed:
        rows.append(("event simulator", f"{confirmed['agreed']} of {confirmed.get('random')} "
                     "random builds agree with the closed forms; "
                     f"{confirmed.get('left_closed_form')} outside them simulated"))
    out = [_table(("quantity", "value"), rows)]
    failures = data.get("failures") or {}
    out.append(_table(("failure", "builds"), list(failures.items())) if failures else
               "<p>No build failed.</p>")
    if not data.get("sensitivity") and data.get("sensitivity_note"):
        out.append(f"<p class=note>Sensitivity: {html.escape(str(data['sensitivity_note']))}"
                   "</p>")
    for name, png in yield_figures(_result(data)).items():
        out.append(f'<img alt="{html.escape(name)}" src="{data_uri(png)}">')
    return "\n".join(out)


def _table(heads, rows) -> str:
    head = "".join(f"<th>{h}</th>" for h in heads)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _result(data: dict):
    """The fields `yield_figures` reads, from the JSON document."""
    y, survival = data["yield"], list(data.get("survival") or [])
    band = data.get("survival_band") or {}
    return SimpleNamespace(
        builds=y["builds"], stages=len(survival), survival=survival,
        survival_low=band.get("low", survival), survival_high=band.get("high", survival),
        scale_curve=list(data.get("yield_against_scale") or []),
        sensitivity=list(data.get("sensitivity") or []))
