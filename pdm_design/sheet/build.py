"""Build sheets: the numbers a workshop builds a device from, with the tolerance of each.

What a scene's sheet lists, one item a stage (a pivot, a step), is the scene's:
Scene.sheet_rows (scenes/<kind>/sheet.py).

The design comes from solving the spec (`pdm_design.api.design`) or from a saved design JSON
(`pdm-design optimize --format json`). The tolerance is the optimizer's robust box
(`max_offset_tolerance`, half-widths on the axes Scene.tolerance_axes): the design's own when its
spec asks for it, otherwise solved for the finished design with that objective alone (which does
not move a fixed design). It was solved for the spec's `verification.stages` stages, so only
those rows carry it.

The simulator's verdict travels with the sheet: the design's verification (a saved JSON's, or
the nominal run simulated now when it carries none). A design whose status is not a success or
whose verification failed gets a warning on the sheet naming what failed (`BuildSheet.failures`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import PdmError, SpecError
from ..plugin import of
from ..spec import load_spec
from ..spec.model import Bounds, Spec
from ..status import Status

JSON_SCHEMA_PREFIX = "pdm-design/optimize/"
MARKDOWN_ROWS = 100


@dataclass(frozen=True)
class BuildSheet:
    """One design's build sheet. summary: (quantity, value, unit, tolerance or None) rows;
    items: one dict per stage (CSV columns, SI units in the names); the tolerance
    columns are None past the spec's verification.stages (`tolerance_covers`). violations and
    verification: why the design does not meet its requirements, and the simulator's verdict
    (`passed`, `summary`, `failures`; None when it was not run). tolerances: tolerances of
    further parts (a link's length, a part's mass, ...) a tolerance analysis found, shown
    on their parts (sheet/parts.py)."""

    spec: Spec
    status: str
    design: dict[str, float | None]
    geometry: dict[str, float | None]
    periodic: dict[str, float | None]
    tolerance: dict[str, float] | None
    tolerance_note: str
    summary: list[tuple[str, float | str, str, float | None]]
    items: list[dict[str, float | int]]
    source: str = ""
    notes: tuple[str, ...] = field(default=())
    violations: tuple[str, ...] = field(default=())
    verification: dict | None = None
    tolerances: tuple = field(default=())  # further ToleranceEntry (sheet/parts.py), by part
    statistical: bool = False  # tolerance: the placement's statistical tolerances, not a box

    @property
    def kind(self) -> str:
        return self.spec.kind

    @property
    def count(self) -> int:
        return len(self.items)

    @property
    def tolerance_covers(self) -> int:
        """How many of the listed items the tolerance holds for: the first
        verification.stages, the rows it was solved for (0 without a tolerance)."""
        return min(self.count, self.spec.verification.stages) if self.tolerance else 0

    @property
    def failures(self) -> tuple[str, ...]:
        """What makes the design not work, in words; empty when it works (a success status
        and a passed verification)."""
        found = []
        if not _is_success(self.status):
            found.append(f"status {self.status or '(none)'}: {_status_message(self.status)}")
            found += [f"requirement not met: {v}" for v in self.violations]
        if self.verification is not None and not self.verification.get("passed"):
            failed = self.verification.get("failures") or [self.verification.get("summary")]
            found += [f"the simulator's verification FAILED: {f}" for f in failed]
        return tuple(found)


# --------------------------------------------------------------------------- the design

def sheet_for(path: str | Path, *, count: int | None = None,
              tolerance: bool = True) -> BuildSheet:
    """The build sheet of a spec file (solved first) or of a saved design JSON (*.json).

    count: stages listed, one item each (default: the spec's verification.stages).
    tolerance: find the placement tolerance when the design does not carry one.
    """
    path = Path(path)
    if path.suffix.lower() == ".json":
        spec, values, status, tol, violations, verification = _from_json(path)
        extra, target = spec_entries(spec), None
    else:
        from ..api import design

        spec = load_spec(path)
        outcome = design(spec)
        values = dict(outcome.analysis.design)
        status, tol = outcome.status.value, outcome.tolerance
        violations, verification = tuple(outcome.violations), outcome.verification
        target = _yield_target(spec)
        sized = outcome.tolerances
        if target is not None and not sized and _is_success(status):  # a fixed design
            sized = _sized_at(spec, spec.design_at(values), str(path))
        extra = (allocated_entries(sized, target=target, kind=spec.kind) if sized
                 else spec_entries(spec))
    fixed = fixed_spec(spec, values, source=str(path))
    if verification is None and _is_success(status):  # saved with --no-verify: simulate it now
        verification = _verify_now(fixed)
    if target is not None:  # statistical tolerances, listed below: no box
        tol, note = _placement(spec.kind, sized), (
            f"no worst-case box: the tolerances are sized for a linearised yield of "
            f"{100 * target:.4g} % (listed below; check it with `pdm-design yield`)")
    elif _is_success(status) or tol:
        tol, note = _tolerance(fixed, tol, tolerance)
    else:  # a box around a design that does not work is no build tolerance
        tol, note = None, f"tolerance not computed: the design's status is {status}"
    count = spec.verification.stages if count is None else count
    try:
        sheet = make_sheet(fixed, status, tol, note, count, source=str(path),
                           violations=violations, verification=verification)
    except ValueError as exc:  # e.g. a device that cannot be built from this design
        raise PdmError(f"{path}: no build sheet: {exc}") from None
    if target is not None:
        sheet = dataclasses.replace(sheet, statistical=True)
    return dataclasses.replace(sheet, tolerances=(*sheet.tolerances, *extra)) if extra else sheet


def _placement(kind: str, entries) -> dict[str, float] | None:
    """The placement tolerance by axis (the scene's box axes) of statistical tolerance
    entries: 0 on an axis they leave untoleranced; None when they tolerance neither (or the
    scene has no per-stage box)."""
    from ..plugin import scene_kind

    box = scene_kind(kind).box_axes
    values = {e["quantity"]: e["value"] for e in entries or ()}
    if box is None or not any(q in values for q in box.quantities):
        return None
    return {axis: float(values.get(q) or 0.0) for axis, q in box.axes}


def _sized_at(spec, point, source: str) -> tuple:
    """optimize's tolerance list (`allocated_entries`' input) of a fixed design whose
    tolerances to allocate are sized for the spec's yield target: the sizes `pdm-design yield`
    builds with, each allocated one limited by the union bound's dominant rows."""
    from ..commands.yield_ import sized_tolerances
    from ..solve.yield_allocation import dominant_rows

    stages = spec.verification.stages
    sized = sized_tolerances(spec, source, point, stages)
    limits = dominant_rows(spec.scene, point, sized, stages)
    to_allocate = {t.quantity for t in spec.tolerances if t.allocate}
    return tuple(t.to_json(spec.kind) | {"allocated": t.quantity in to_allocate,
                                         "limited_by": limits if t.quantity in to_allocate
                                         else []}
                 for t in sized)


SPEC_WORDS = "the spec's statistical tolerance"


def part_words(kind: str, quantity: str) -> str:
    """The part a tolerance of `quantity` is built on, in the words of sheet/parts.py (the
    scene's: Scene.quantity_parts), or the quantity's own name where the scene gives none."""
    from ..plugin import scene_kind

    own = scene_kind(kind).quantity_parts if kind else {}
    return own.get(quantity, quantity)


def allocated_entries(entries, target: float | None = None, kind: str = "") -> tuple:
    """ToleranceEntry of every allocated or given tolerance of an optimize answer other than
    the pivots' (the sheet's own box lists those), on its part, with what limits it; with a
    yield `target` (tolerances sized for it, formulation/yield_target.py: no box) the
    pivots' too, statistical."""
    from ..solve.binding import SHARED, in_words
    from .parts import ToleranceEntry

    out = []
    sized = "" if target is None else f" for a linearised yield of {100 * target:.4g} %"
    for e in entries or ():
        if e["quantity"] in ("pivot_x", "pivot_y") and target is None:
            continue
        lot = " (one lot)" if e["applies_to"] == "lot" else ""
        why = (f"allocated{sized}; limited by " + (in_words(e["limited_by"]) or SHARED)
               if e["allocated"] else "given in the spec")
        out.append(ToleranceEntry(e["quantity"].replace("_", " "),
                                  part_words(kind, e["quantity"]) + lot, e["value"],
                                  "" if e["unit"] == "1" else e["unit"], why))
    return tuple(out)


def _yield_target(spec) -> float | None:
    """The yield target the answer's tolerances are sized for (None: a worst-case box)."""
    from ..formulation.yield_target import active

    return spec.tolerances.yield_target if active(spec) else None


def spec_entries(spec) -> tuple:
    """ToleranceEntry of every tolerance the spec's [tolerances] gives a value, pivots too,
    on its part: statistical tolerances (the yield draws each build's error from their
    distribution), not the worst-case box the optimizer computes (the sheet's own)."""
    from ..tolerance_model import SIGMAS_PER_TOLERANCE
    from .parts import ToleranceEntry

    out = []
    for t in spec.tolerances or ():
        if t.value is None:
            continue
        unit = t.to_json(spec.kind)["unit"]
        spread = (f"normal, +-t = {SIGMAS_PER_TOLERANCE:g} sigma" if t.distribution == "normal"
                  else "uniform over +-t")
        lot = " (one lot)" if t.applies_to == "lot" else ""
        out.append(ToleranceEntry(t.quantity.replace("_", " ") + " (spec)",
                                  part_words(spec.kind, t.quantity) + lot, t.value,
                                  "" if unit == "1" else unit,
                                  f"{SPEC_WORDS} ({spread})"))
    return tuple(out)


def _verify_now(spec: Spec) -> dict:
    """The simulator's nominal run of a fixed-design spec (as `optimize` verifies it)."""
    from ..analysis import analyse
    from ..verify import verify_nominal

    point = spec.design_at()
    verdict = verify_nominal(spec, point, analyse(spec.scene, point, spec.verification.stages))
    return verdict | {"summary": f"{verdict['summary']} (simulated for this sheet: the saved "
                                 "design carried no verification)"}


def _is_success(status: str) -> bool:
    return status in {s.value for s in Status if s.is_success}


def _status_message(status: str) -> str:
    try:
        return Status(status).message
    except ValueError:
        return "not a status pdm-design reports as a success."


def fixed_spec(spec: Spec, values: dict, source: str | None = None) -> Spec:
    """The spec with each free variable fixed at `values` (the design to build; a saved JSON
    document's, named `source` in errors): a number within the spec's bounds for each."""
    import pydantic

    source = source or spec.source
    design = {}
    for name, value in spec.design.items():
        if isinstance(value, Bounds):
            found = values.get(name)
            if not _finite(found) or not value.min <= found <= value.max:
                raise SpecError(source, f"design.{name}", f"a number from {value.min:g} to "
                                f"{value.max:g} (the spec's bounds)", repr(found))
            design[name] = float(found)
        else:
            design[name] = value
    try:
        spec.design_class(**design)  # validates the point as a whole
    except pydantic.ValidationError as exc:
        error = exc.errors()[0]
        raise SpecError(source, "design", "a design the scene can take",
                        error["msg"]) from None
    return dataclasses.replace(spec, design=design)


def _from_json(path: Path):
    """(spec, design values, status, tolerance, violations, verification) of a saved
    `optimize --format json` document."""
    source = str(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError(source, "", "an existing design JSON file", "no such file") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise SpecError(source, "", "a JSON document from `pdm-design optimize --format json`",
                        str(exc)) from None
    if not isinstance(doc, dict) or not str(doc.get("schema", "")).startswith(
            JSON_SCHEMA_PREFIX):
        raise SpecError(source, "schema", f"'{JSON_SCHEMA_PREFIX}1' (a document from "
                        "`pdm-design optimize --format json`)", repr(_get(doc, "schema")))
    spec_path = doc.get("spec")
    if not isinstance(spec_path, str):
        raise SpecError(source, "spec", "the path of the spec file", repr(spec_path))
    candidates = [Path(spec_path), path.parent / spec_path]
    found = next((p for p in candidates if p.is_file()), None)
    if found is None:
        raise SpecError(source, "spec", "the path of the spec file the design was made from "
                        "(as given, or relative to the JSON file)", f"'{spec_path}' (not found)")
    spec = load_spec(found)
    saved = doc.get("spec_sha256")  # absent from documents older than it
    if saved is not None and saved != spec.digest:
        raise SpecError(source, "spec_sha256", f"the digest of {found} as it is now (the spec "
                        "changed since this design was saved: run `pdm-design optimize` again)",
                        repr(saved))
    values = doc.get("design")
    if not isinstance(values, dict):
        raise SpecError(source, "design", "a table of design values", repr(values))
    tol = doc.get("tolerance")
    for axis, value in (tol.items() if isinstance(tol, dict) else ()):
        if axis in of(spec).tolerance_axes and not (_finite(value) and value >= 0):
            raise SpecError(source, f"tolerance.{axis}", "a number >= 0 (m)", repr(value))
    verification = doc.get("verification")
    if verification is not None and not (isinstance(verification, dict)
                                         and isinstance(verification.get("passed"), bool)):
        raise SpecError(source, "verification", "the simulator's verdict (a table with "
                        "`passed` true or false) or null", repr(verification))
    violations = doc.get("violations") or []
    violations = tuple(str(v) for v in (violations if isinstance(violations, list)
                                        else [violations]))
    return (spec, values, str(doc.get("status", "")), tol if isinstance(tol, dict) else None,
            violations, verification)


def _get(doc, key):
    return doc.get(key) if isinstance(doc, dict) else doc


def _tolerance(spec: Spec, tol: dict | None, wanted: bool) -> tuple[dict | None, str]:
    """The placement tolerance (half-widths by axis) and a note on where it comes from."""
    axes = of(spec).tolerance_axes
    if not axes:
        return None, f"tolerance not computed: a {spec.kind} scene has no placement box"
    if tol and all(_finite(tol.get(a)) for a in axes):
        return {a: float(tol[a]) for a in axes}, "robust tolerance of the optimised design"
    if not wanted:
        return None, "tolerance not computed (--no-tolerance)"
    most, why = of(spec).stage_limit(True)
    if spec.verification.stages > most:
        return None, (f"tolerance not computed: {spec.verification.stages} stages is more "
                      f"than {most} {why}")
    shift = of(spec).box_shift(spec)
    asked = spec if shift is None else shift.spec
    asked = dataclasses.replace(asked, objective={"max_offset_tolerance": 1.0})
    try:
        from ..api import design

        outcome = design(asked)
        found = outcome.tolerance
        if not (found and all(_finite(found.get(a)) for a in axes)):
            from ..solve.optimize import optimize

            result = optimize(asked, starts=1, check_samples=0, linearise=False)
            found = result.tolerance if result.status.is_success else None
    except Exception as exc:  # the sheet is still useful without it: say why it is missing
        return None, f"tolerance not found ({type(exc).__name__}: {exc})"
    if not (found and all(_finite(found.get(a)) for a in axes)):
        return None, "tolerance not found: the design has no robust margin to spare"
    drift = 0.0 if shift is None else shift.offset
    box = {a: float(found[a]) - (drift if shift and a == shift.axis else 0.0) for a in axes}
    if drift == 0.0:
        return box, "largest robust box for this design (objective max_offset_tolerance)"
    axis, noun = shift.axis, of(spec).stage_noun[0]
    if box[axis] <= 0.0:
        return None, (f"tolerance not found: the {axis} is {drift:.3g} m off "
                      f"{shift.reference}, more than the {found[axis]:.3g} m the periodic "
                      f"design allows a {noun}")
    return box, (f"largest robust box of the periodic design (objective max_offset_tolerance), "
                 f"its {axis} half-width less this {axis}'s {drift:.3g} m offset from "
                 f"{shift.reference}")


def _finite(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(
        value)


# --------------------------------------------------------------------------- the sheet

def make_sheet(spec: Spec, status: str, tol: dict | None, note: str, count: int, *,
               source: str = "", violations: tuple[str, ...] = (),
               verification: dict | None = None) -> BuildSheet:
    """The sheet of a fixed-design spec (every variable a number). The tolerance is listed for
    the first spec.verification.stages items only: it was solved for those."""
    from ..analysis import analyse

    if count < 1:
        raise SpecError("command line", "--count", "an integer >= 1", str(count))
    analysis = analyse(spec.scene, spec.design_at(), spec.verification.stages)
    summary, items = of(spec).sheet_rows(spec, analysis, tol, count)
    return BuildSheet(spec=spec, status=status, design=dict(analysis.design),
                      geometry=dict(analysis.geometry), periodic=dict(analysis.periodic),
                      tolerance=tol, tolerance_note=note, summary=summary, items=items,
                      source=source, notes=tuple(analysis.problems),
                      violations=tuple(violations), verification=verification)
