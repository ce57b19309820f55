"""`pdm-design report SPEC`: the report page of a design (report/html.py), written whole."""

from __future__ import annotations

from pathlib import Path

PAGE = "report.html"


def report_for(source, *, count: int | None = None, tolerance: bool = True,
               yield_result=None, compute_yield: bool = True) -> tuple[str, object]:
    """(the page, its build sheet) of a spec (solved first) or a saved design JSON. Without a
    yield_result, the yield of the spec's [tolerances] is computed when it gives them all a
    value and compute_yield is true (docs/report.md)."""
    from ..analysis import analyse
    from ..sheet import sheet_for
    from ..sheet.drawing import draw
    from ..sim.core import SimulationRefused
    from ..verify import simulate_spec
    from .html import report_page
    from .render import render_figure

    sheet = sheet_for(source, count=count, tolerance=tolerance)
    spec = sheet.spec
    point = spec.design_at()
    margins = analyse(spec.scene, point, spec.verification.stages).margins
    run, refused = None, ""
    try:
        run = simulate_spec(spec, point, record_trajectory=True)
    except SimulationRefused as refusal:
        refused = f"the simulator refuses this design: {refusal}"
    if yield_result is None and compute_yield and spec.tolerances:
        yield_result = _own_yield(spec, str(source))
    drawing = render_figure(draw(sheet), "png", dpi=90)
    page = report_page(sheet, margins=margins, run=run, refused=refused, drawing_png=drawing,
                       yield_result=yield_result)
    return page, sheet


def _own_yield(spec, source: str):
    """The yield document of the spec's design, or why there is none (a string)."""
    from ..errors import PdmError
    from .yield_section import spec_yield

    try:
        found, why = spec_yield(spec, source)
    except PdmError as exc:
        return str(exc)
    return found if found is not None else why


def write_report(source, folder, **options) -> tuple[Path, object]:
    """Write FOLDER/report.html (whole or not at all); (its path, the build sheet)."""
    from ..io import write_all

    page, sheet = report_for(source, **options)
    path = Path(folder) / PAGE
    write_all({path: page.encode("utf-8")})
    return path, sheet


def read_yield(path) -> dict:
    """A yield analysis saved as JSON (a table of numbers and curves: docs/report.md)."""
    import json

    from ..errors import SpecError

    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError("command line", "--yield", "an existing JSON file", str(path)) from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise SpecError(str(path), "", "a JSON document (a yield analysis)", str(exc)) from None
    if not isinstance(data, dict):
        raise SpecError(str(path), "", "a JSON table (a yield analysis)", type(data).__name__)
    return data


def report_command(source, out, count, no_tolerance, echo, yield_path=None,
                   no_yield=False) -> bool:
    """The body of `pdm-design report`: write the page, say where; True when the design works
    (else its failures go to stderr: the page is written with them at its top)."""
    folder = out or f"{Path(source).stem}-report"
    analysis = read_yield(yield_path) if yield_path else None
    if analysis is not None:
        check_yield_made_for(analysis, yield_path, source)
    path, sheet = write_report(source, folder, count=count, tolerance=not no_tolerance,
                               yield_result=analysis, compute_yield=not no_yield)
    echo(f"report of {sheet.spec.name or source} (status {sheet.status}): {path}")
    for failure in sheet.failures:
        echo(f"warning: {failure}", err=True)
    return not sheet.failures


def check_yield_made_for(data: dict, path, source) -> None:
    """Refuse (exit 2, naming the file and what differs) a `pdm-design yield` document made
    for another spec than the report's source (a spec, or a saved optimize JSON naming one):
    its schema and spec_sha256 (spec.loader.content_digest) must be those of the source's
    spec. A table that is not a yield document (curves, numbers) is shown as it is."""
    from ..commands.yield_ import YIELD_SCHEMA
    from ..errors import SpecError
    from .yield_section import is_yield_document

    if not is_yield_document(data):
        return
    if data.get("schema") != YIELD_SCHEMA:
        raise SpecError(str(path), "schema", f"'{YIELD_SCHEMA}' (a yield saved by `pdm-design "
                        "yield --format json` or --out, which names the spec it was run on: "
                        "run it again)", repr(data.get("schema")))
    wanted = _source_spec(source)
    if wanted is None or data.get("spec_sha256") == wanted[1]:
        return
    spec, digest, kind = wanted
    what = f"a yield of {data.get('spec')!r}"
    if data.get("scene") != kind:
        what += f" (a {data.get('scene')} scene; this report's is {kind})"
    what += " as it was then" if data.get("spec") == spec else \
        f"; this report's spec is {spec!r}"
    raise SpecError(str(path), "spec_sha256", f"the digest of {spec} as it is now, "
                    f"{digest[:12]}... (the yield of another spec, or of this one before it "
                    f"changed: run `pdm-design yield {spec} --out DIR` again)",
                    f"{str(data.get('spec_sha256'))[:12]}...: {what}")

def _source_spec(source) -> tuple[str, str, str] | None:
    """(spec path, digest, scene kind) of the report's source: a spec, or the spec a saved
    optimize JSON names (its spec_sha256: the sheet refuses one whose spec has changed);
    None when the source cannot be read (the sheet then says why)."""
    import json

    from ..errors import SpecError
    from ..spec import load_spec

    if Path(source).suffix.lower() == ".json":
        try:
            doc = json.loads(Path(source).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError):
            return None
        if not isinstance(doc, dict) or not isinstance(doc.get("spec_sha256"), str):
            return None
        return str(doc.get("spec")), doc["spec_sha256"], str(doc.get("scene"))
    try:
        spec = load_spec(source)
    except SpecError:
        return None
    return str(source), spec.digest, spec.kind
