"""The report page of a design: one self-contained HTML file (no network at view time: styles,
script and images inline, images as data URIs).

Sections: the verdict, the design (SI and workshop units), derived geometry and the periodic
orbit, every margin, the tolerances by part and the parts list, a yield analysis when one is
given (its numbers as a table, its curves as plots), the build sheet's drawing, and the
animated simulated run (report/animation.py).

A yield analysis is given as plain data (a mapping, or an object with `to_json()` or a
dataclass). The `pdm-design yield` document (docs/json-schema.md) is shown as that command
shows it (report/yield_section.py); of any other table the scalar entries are listed, and each
entry that is a curve, {"x": [...], "y": [...]} (optionally with "xlabel", "ylabel") or a list
of [x, y] pairs, is plotted. A string says why there is none.
"""

from __future__ import annotations

import base64
import html
import math

from .animation import animation, animation_html
from .units import built_parts, units_of

_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1200px;color:#222;
padding:0 1em}
h1{font-size:1.5em}h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}
td,th{border:1px solid #ddd;padding:.2em .6em;text-align:left}th{background:#f4f4f4}
td.num{text-align:right;font-variant-numeric:tabular-nums}
.bad{color:#b00;font-weight:bold}.ok{color:#070}
img{max-width:100%;border:1px solid #eee}
.anim svg{width:100%;height:460px;border:1px solid #ccc;background:#fff}
.controls{margin:.4em 0}.controls input{width:60%;vertical-align:middle}
.note{color:#555;font-size:.85em}
"""


def report_page(sheet, *, margins: dict, run=None, refused: str = "",
                drawing_png: bytes | None = None, yield_result=None) -> str:
    """The page as text. run: the simulator's nominal run with its trajectory (None, with
    `refused` saying why, when there is none)."""
    spec = sheet.spec
    name = html.escape(spec.name or str(spec.source))
    body = [f"<h1>{name} ({sheet.kind})</h1>", _verdict(sheet)]
    body += ["<h2>Simulated run</h2>", _animation(spec, run, refused)]
    units = units_of(sheet.kind)
    body += ["<h2>Design</h2>", _values(sheet.design, set(spec.free_variables), units)]
    body += ["<h2>Geometry and periodic orbit</h2>",
             _values({**built_parts(sheet.kind, sheet.geometry), **sheet.periodic}, set(), units)]
    body += ["<h2>Margins</h2>", _margins(margins, spec)]
    body += ["<h2>Tolerances and parts</h2>", _parts(sheet)]
    if yield_result is not None:
        body += ["<h2>Yield</h2>", _yield(yield_result)]
    if drawing_png:
        body += ["<h2>Drawing</h2>",
                 f'<img alt="build sheet drawing" src="{_data_uri(drawing_png)}">']
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{name}: pdm-design report</title><style>{_STYLE}</style></head>\n"
            "<body>\n" + "\n".join(body) + "\n</body></html>\n")


def _data_uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _verdict(sheet) -> str:
    status = html.escape(sheet.status)
    lines = [f"<p>Spec <code>{html.escape(str(sheet.spec.source))}</code>; status "
             f"<b>{status}</b>.</p>"]
    if sheet.failures:
        lines.append('<p class="bad">This design does not work. Do not build it.</p><ul>'
                     + "".join(f"<li>{html.escape(f)}</li>" for f in sheet.failures) + "</ul>")
    v = sheet.verification
    if v is not None:
        verdict = ('<span class="ok">passed</span>' if v.get("passed")
                   else '<span class="bad">FAILED</span>')
        lines.append(f"<p>Verification (the event simulator): {verdict}: "
                     f"{html.escape(str(v.get('summary')))}</p>")
    return "\n".join(lines)


def _animation(spec, run, refused) -> str:
    if run is None:
        return f'<p class="bad">No run to animate: {html.escape(refused)}</p>'
    return animation_html(animation(spec, run))


def _cell(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else "-"
    return html.escape(str(value))




def _values(values: dict, free: set, units: dict) -> str:
    from ..sheet.parts import workshop_value

    rows = []
    for key, value in values.items():
        unit = units.get(key, "")
        shown = "-"
        if isinstance(value, (int, float)) and unit and math.isfinite(value):
            number, words = workshop_value(float(value), unit)
            shown = f"{number:.6g} {words}"
        mark = " (optimised)" if key in free else ""
        rows.append(f"<tr><td>{html.escape(key)}{mark}</td><td class=num>{_cell(value)}</td>"
                    f"<td>{unit}</td><td class=num>{shown}</td></tr>")
    return ("<table><tr><th>quantity</th><th>value (SI)</th><th>unit</th>"
            "<th>workshop units</th></tr>" + "".join(rows) + "</table>")


def _margins(margins: dict, spec) -> str:
    from ..analysis.result import required

    rows = []
    for key, value in margins.items():
        need = required(key, spec.requirements, spec.kind)
        ok = value >= need
        flag = '<span class="ok">ok</span>' if ok else (
            f'<span class="bad">VIOLATED (needs &ge; {need:g})</span>')
        rows.append(f"<tr><td>{html.escape(key)}</td><td class=num>{value:+.4f}</td>"
                    f"<td>{flag}</td></tr>")
    return ("<p class=note>1 - demand/capacity; &ge; 0 holds.</p><table><tr><th>margin</th>"
            "<th>value</th><th></th></tr>" + "".join(rows) + "</table>")


def _parts(sheet) -> str:
    from ..sheet.parts import parts_list, tolerance_entries, workshop_value

    entries = tolerance_entries(sheet)
    rows = []
    for e in entries:
        value, unit = workshop_value(e.value, e.unit)
        rows.append(f"<tr><td>{html.escape(e.quantity)}</td><td>{html.escape(e.applies_to)}"
                    f"</td><td class=num>&plusmn;{value:.4g} {unit}</td>"
                    f"<td>{html.escape(e.limited_by)}</td></tr>")
    table = ("<p class=note>(spec): the spec's statistical tolerances; (box): the worst-case "
             "box the optimizer computed.</p><table><tr><th>tolerance</th><th>applies to</th>"
             "<th>value</th><th>what it is</th></tr>" + "".join(rows) + "</table>" if rows else
             f"<p>No tolerance: {html.escape(sheet.tolerance_note)}.</p>")
    from ..sheet.build_to import build_to_sentence  # which of two tolerances on a part

    sentence = build_to_sentence(sheet)
    if sentence:
        table += f"<p class=note>{html.escape(sentence, quote=False)}</p>"
    parts, _ = parts_list(sheet)
    listed = "".join(
        f"<tr><td>{p.quantity}</td><td>{html.escape(p.name)}</td><td>{html.escape(p.dimensions)}"
        f"</td><td>{html.escape('; '.join(f'{e.quantity} {e.shown()}' for e in p.tolerances))}"
        "</td></tr>" for p in parts)
    return (table + "<table><tr><th>qty</th><th>part</th><th>dimensions (mm, degrees)</th>"
            "<th>tolerance</th></tr>" + listed + "</table>")


# --------------------------------------------------------------------------- yield

def _yield(result) -> str:
    from .jsonable import jsonable
    from .yield_section import is_yield_document, yield_html

    data = jsonable(result)
    if isinstance(data, str):  # why the report computed none
        return f"<p>Not computed: {html.escape(data)}.</p>"
    if is_yield_document(data):
        return yield_html(data, _data_uri)
    if not isinstance(data, dict):
        return f"<p>{_cell(data)}</p>"
    scalars = {k: v for k, v in data.items() if isinstance(v, (int, float, str, bool))}
    curves = {k: c for k, c in ((k, _curve(v)) for k, v in data.items()) if c}
    out = ["<table>" + "".join(f"<tr><td>{html.escape(k)}</td><td class=num>{_cell(v)}</td>"
                               "</tr>" for k, v in scalars.items()) + "</table>"]
    for key, (xs, ys, xlabel, ylabel) in curves.items():
        png = _plot(key, xs, ys, xlabel, ylabel)
        out.append(f'<img alt="{html.escape(key)}" src="{_data_uri(png)}">')
    return "\n".join(out)


def _curve(value):
    """(xs, ys, xlabel, ylabel) of a curve entry, or None."""
    if isinstance(value, dict) and isinstance(value.get("x"), list) and isinstance(
            value.get("y"), list) and len(value["x"]) == len(value["y"]) > 0:
        return value["x"], value["y"], value.get("xlabel", "x"), value.get("ylabel", "y")
    if isinstance(value, list) and value and all(
            isinstance(p, list) and len(p) == 2 for p in value):
        return [p[0] for p in value], [p[1] for p in value], "x", "y"
    return None


def _plot(title, xs, ys, xlabel, ylabel) -> bytes:
    from matplotlib.figure import Figure

    from .render import render_figure

    figure = Figure(figsize=(6, 3.2), layout="constrained")
    ax = figure.add_subplot()
    ax.plot(xs, ys, marker="o", markersize=3)
    ax.set(title=title, xlabel=xlabel, ylabel=ylabel)
    ax.grid(True, alpha=0.3)
    return render_figure(figure, "png", dpi=100)
