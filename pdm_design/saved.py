"""A design saved by an earlier run, read back for `simulate --from FILE`: a `pdm-design yield`
document (its JSON, or the --out folder holding yield.json) or a saved `pdm-design optimize
--format json` document. The file must be of the spec given (its spec_sha256, the digest of
the spec's content: spec.loader.content_digest); its design is then used as it is, without
solving again, and a yield document's tolerances are the ones its builds were drawn with."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from .errors import SpecError

SCHEMAS = ("pdm-design/yield/1", "pdm-design/optimize/1")


@dataclass(frozen=True)
class SavedDesign:
    """What a saved document gives: the design point, the status it was found with, and for a
    yield document the tolerances its builds were drawn with and its stages (else None)."""

    source: str
    point: object
    status: str
    success: bool
    tolerances: object = None
    stages: int | None = None


def read_saved_design(path: str, spec, spec_source: str) -> SavedDesign:
    """The design saved in `path` for `spec` (named spec_source in messages); SpecError (exit 2)
    naming the file and the key for a file that is not such a document or is of another spec."""
    file = Path(path)
    if file.is_dir():
        file = file / "yield.json"
    source = str(file)
    doc = _read(file)
    schema = doc.get("schema")
    if schema not in SCHEMAS:
        raise SpecError(source, "schema", " or ".join(repr(s) for s in SCHEMAS) + " (a document "
                        "of `pdm-design yield` or `pdm-design optimize --format json`)",
                        repr(schema))
    if doc.get("spec_sha256") != spec.digest:
        raise SpecError(source, "spec_sha256", f"the digest of {spec_source} as it is now, "
                        f"{spec.digest[:12]}... (the file must be made from this spec)",
                        f"{str(doc.get('spec_sha256'))[:12]}...: a document of "
                        f"{doc.get('spec')!r} ({doc.get('scene')}), or of this spec before "
                        "it changed")
    point = _point(doc.get("design"), spec, source)
    if schema == SCHEMAS[1]:
        from .status import Status

        status = str(doc.get("status"))
        success = status in {s.value for s in Status if s.is_success}
        return SavedDesign(source, point, status, success)
    return SavedDesign(source, point, "yield run", True, _tolerances(doc, spec, source),
                       _stages(doc, source))


def _read(file: Path) -> dict:
    try:
        doc = json.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError("command line", "--from", "a yield.json, its --out folder or a saved "
                        "optimize JSON", f"{str(file)!r} (no such file)") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise SpecError(str(file), "", "a JSON document of `pdm-design yield` or `pdm-design "
                        "optimize --format json`", str(exc)) from None
    if not isinstance(doc, dict):
        raise SpecError(str(file), "", "a JSON table", type(doc).__name__)
    return doc


def _point(values, spec, source: str):
    """The design point: the spec's fixed values and the document's for the free ones."""
    from .sheet.build import fixed_spec

    if not isinstance(values, dict):
        raise SpecError(source, "design", "a table of design values", repr(values))
    return fixed_spec(spec, values, source).design_at()


def _tolerances(doc: dict, spec, source: str):
    """The yield document's tolerances (values as its builds were drawn, those sized for a
    yield target included), in the spec's order, with the spec's other settings."""
    from dataclasses import replace

    from .tolerance_model import Tolerance

    entries = doc.get("tolerances")
    given = {e.get("quantity"): e for e in entries if isinstance(e, dict)} \
        if isinstance(entries, list) else {}
    items = []
    for tol in spec.tolerances:
        value = (given.get(tol.quantity) or {}).get("value")
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not (math.isfinite(value) and value > 0):
            raise SpecError(source, f"tolerances[{tol.quantity}].value", "a number > 0 (SI), "
                            "the tolerance the builds were drawn with", repr(value))
        items.append(Tolerance(tol.quantity, tol.applies_to, float(value), tol.weight,
                               tol.distribution))
    return replace(spec.tolerances, items=tuple(items))


def _stages(doc: dict, source: str) -> int:
    stages = (doc.get("yield") or {}).get("stages") if isinstance(doc.get("yield"), dict) \
        else None
    if isinstance(stages, bool) or not isinstance(stages, int) or stages < 1:
        raise SpecError(source, "yield.stages", "an integer >= 1", repr(stages))
    return stages
