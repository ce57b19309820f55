"""Build sheets: the numbers a workshop builds a device from, with the tolerance of each.

Manipulators: the coordinates of every pivot (frame of the spec: origin at the first
manipulator's nominal pivot when first_pivot_x = first_pivot_y = 0, x along the row, y up), the
back-stop, handover and front-stop angles, link length, palm mass and size, and the box
(+-dx, +-dy) each pivot may be placed within. Stairs: every step's rise and tread with their
tolerance, and where each step's back, nose and tread surface are (frame: the ball is launched
at x = 0; nominal tread 1 is at y = 0).

The design comes from solving the spec (`pdm_design.api.design`) or from a saved design JSON
(`pdm-design optimize --format json`). The tolerance is the optimizer's robust box
(`max_offset_tolerance`): the design's own when its spec asks for it, otherwise solved for the
finished design with that objective alone (which does not move a fixed design). It was solved
for the spec's `verification.stages` manipulators or steps, so only those rows carry it.

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
from ..physics import manipulators as phys
from ..spec import load_spec
from ..spec.model import MAX_OPTIMISED_BOUNCES, Bounds, Spec
from ..status import Status

JSON_SCHEMA_PREFIX = "pdm-design/optimize/"
MARKDOWN_ROWS = 100
TOLERANCE_AXES = {"manipulators": ("dx", "dy"), "stairs": ("rise", "tread")}


@dataclass(frozen=True)
class BuildSheet:
    """One design's build sheet. summary: (quantity, value, unit, tolerance or None) rows;
    items: one dict per manipulator or step (CSV columns, SI units in the names); the tolerance
    columns are None past the spec's verification.stages (`tolerance_covers`). violations and
    verification: why the design does not meet its requirements, and the simulator's verdict
    (`passed`, `summary`, `failures`; None when it was not run). tolerances: tolerances of
    further parts (link length, back stop, palm mass, ...) a tolerance analysis found, shown
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

    count: manipulators or steps listed (default: the spec's verification.stages).
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
    except ValueError as exc:  # e.g. a staircase that cannot be built from this design
        raise PdmError(f"{path}: no build sheet: {exc}") from None
    if target is not None:
        sheet = dataclasses.replace(sheet, statistical=True)
    return dataclasses.replace(sheet, tolerances=(*sheet.tolerances, *extra)) if extra else sheet


# the quantities of the sheet's placement tolerance (TOLERANCE_AXES), by scene
PLACEMENT = {"manipulators": ("pivot_x", "pivot_y"), "stairs": ("rise", "tread")}


def _placement(kind: str, entries) -> dict[str, float] | None:
    """The placement tolerance by axis (TOLERANCE_AXES) of statistical tolerance entries: 0
    on an axis they leave untoleranced; None when they tolerance neither."""
    values = {e["quantity"]: e["value"] for e in entries or ()}
    if not any(q in values for q in PLACEMENT[kind]):
        return None
    return {axis: float(values.get(q) or 0.0)
            for axis, q in zip(TOLERANCE_AXES[kind], PLACEMENT[kind])}


def _sized_at(spec, point, source: str) -> tuple:
    """optimize's tolerance list (`allocated_entries`' input) of a fixed design whose
    tolerances to allocate are sized for the spec's yield target: the sizes `pdm-design yield`
    builds with, each allocated one limited by the union bound's dominant rows."""
    from ..solve.yield_allocation import dominant_rows
    from ..tolerances.command import sized_tolerances

    stages = spec.verification.stages
    sized = sized_tolerances(spec, source, point, stages)
    limits = dominant_rows(spec.scene, point, sized, stages)
    to_allocate = {t.quantity for t in spec.tolerances if t.allocate}
    return tuple(t.to_json(spec.kind) | {"allocated": t.quantity in to_allocate,
                                         "limited_by": limits if t.quantity in to_allocate
                                         else []}
                 for t in sized)


# the part each allocated quantity is built on, in the words sheet/parts.py puts on a part
ALLOCATED_PART = {"pivot_x": "every pivot bracket", "pivot_y": "every pivot bracket",
                  "feed_x": "the feed (start place)", "friction": "every palm's surface",
                  "object_width": "the objects carried", "feed_speed": "the feed (start speed)",
                  "palm_mass": "every palm", "object_mass": "the objects carried",
                  "launch_x": "the launcher (release place)", "link_length": "every link",
                  "back_stop": "every back stop", "link_mass": "every link",
                  "pivot_friction": "every pivot bracket's joints", "rise": "every step",
                  "tread": "every step", "restitution": "every step's surface (the ball's "
                  "bounce)", "launch_speed": "the launcher (launch speed)"}
# where a quantity's words differ by scene: the ball meets the treads, not palms
SCENE_PART = {("stairs", "friction"): "every tread's surface (the ball's grip)"}
SPEC_WORDS = "the spec's statistical tolerance"


def part_words(kind: str, quantity: str) -> str:
    """The part a tolerance of `quantity` is built on, in the words of sheet/parts.py."""
    return SCENE_PART.get((kind, quantity), ALLOCATED_PART.get(quantity, quantity))


def allocated_entries(entries, target: float | None = None,
                      kind: str = "manipulators") -> tuple:
    """ToleranceEntry of every allocated or given tolerance of an optimize answer other than
    the pivots' (the sheet's own box lists those), on its part, with what limits it; with a
    yield `target` (tolerances sized for it, formulation/manipulators/yield_target.py: no box) the
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
    from ..tolerances.model import SIGMAS_PER_TOLERANCE
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
        if axis in TOLERANCE_AXES[spec.kind] and not (_finite(value) and value >= 0):
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
    axes = TOLERANCE_AXES[spec.kind]
    if tol and all(_finite(tol.get(a)) for a in axes):
        return {a: float(tol[a]) for a in axes}, "robust tolerance of the optimised design"
    if not wanted:
        return None, "tolerance not computed (--no-tolerance)"
    if spec.kind == "stairs" and spec.verification.stages > MAX_OPTIMISED_BOUNCES:
        return None, (f"tolerance not computed: its NLP has rows for every bounce, and "
                      f"{spec.verification.stages} is more than {MAX_OPTIMISED_BOUNCES}")
    asked, drift = _orbit_design(spec)
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
    box = {a: float(found[a]) - (drift if a == "tread" else 0.0) for a in axes}
    if drift == 0.0:
        return box, "largest robust box for this design (objective max_offset_tolerance)"
    if box["tread"] <= 0.0:
        return None, (f"tolerance not found: the tread is {drift:.3g} m off the periodic "
                      f"flight's, more than the {found['tread']:.3g} m the periodic design "
                      "allows a step")
    return box, (f"largest robust box of the periodic design (objective max_offset_tolerance), "
                 f"its tread half-width less this tread's {drift:.3g} m offset from the periodic "
                 "flight's")


def _orbit_design(spec: Spec) -> tuple[Spec, float]:
    """(the spec with a given stairs tread left to the periodic flight, |tread - that tread|).

    The NLP holds a given tread to the periodic flight's (optimizer.md, section 9), which an
    optimizer's answer meets only to its tolerance (6e-8 m off found no box). Built with tread
    T + d, every step is the periodic design's with a tread error d, so the periodic design's
    box, its tread half-width less |d|, holds for it."""
    tread = spec.design.get("tread") if spec.kind == "stairs" else None
    if tread is None:
        return spec, 0.0
    from ..analysis import analyse

    periodic = analyse(spec.scene, spec.design_at(), spec.verification.stages).periodic
    drift = periodic.get("drift_per_bounce")
    if drift is None:
        return spec, 0.0
    design = {name: value for name, value in spec.design.items() if name != "tread"}
    return dataclasses.replace(spec, design=design), abs(float(drift))


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
    maker = _manipulators if spec.kind == "manipulators" else _stairs
    summary, items = maker(spec, analysis, tol, count)
    return BuildSheet(spec=spec, status=status, design=dict(analysis.design),
                      geometry=dict(analysis.geometry), periodic=dict(analysis.periodic),
                      tolerance=tol, tolerance_note=note, summary=summary, items=items,
                      source=source, notes=tuple(analysis.problems),
                      violations=tuple(violations), verification=verification)


def _manipulators(spec, analysis, tol, count):
    d, scene = analysis.design, spec.scene
    a, b, l = d["alpha"], d["beta"], d["link_length"]
    px, py = analysis.geometry["pitch_x"], analysis.geometry["pitch_y"]  # py: downward
    x0, y0 = d["first_pivot_x"], d["first_pivot_y"]
    palm_mass = scene.body.mass / d["mass_ratio"]
    tx, ty = (tol["dx"], tol["dy"]) if tol else (None, None)
    covered = spec.verification.stages
    items = []
    for k in range(1, count + 1):
        x, y = x0 + (k - 1) * px, y0 - (k - 1) * py
        back_x, back_y = (float(v) for v in phys.palm_centre(x, y, -a, l))
        hand_x, hand_y = (float(v) for v in phys.palm_centre(x, y, b, l))
        items.append({
            "manipulator": k, "pivot_x_m": x, "pivot_y_m": y,
            "pivot_x_tolerance_m": tx if k <= covered else None,
            "pivot_y_tolerance_m": ty if k <= covered else None,
            "back_stop_rad": -a, "handover_rad": b, "front_stop_rad": scene.palm.front_stop,
            "link_length_m": l, "palm_mass_kg": palm_mass,
            "palm_at_back_stop_x_m": back_x, "palm_at_back_stop_y_m": back_y,
            "handover_x_m": hand_x, "handover_y_m": hand_y,
        })
    summary = [
        ("manipulators", count, "", None),
        ("pitch x (pivot to pivot, along the row)", px, "m", None),
        ("pitch y (pivot to pivot, downward)", py, "m", None),
        ("pivot k x = first pivot x + (k - 1) pitch x", x0, "m", tx),
        ("pivot k y = first pivot y - (k - 1) pitch y", y0, "m", ty),
        ("link length l", l, "m", None),
        ("back stop -alpha (clockwise from vertical)", -a, "rad", None),
        ("handover angle beta", b, "rad", None),
        ("front stop", scene.palm.front_stop, "rad", None),
        ("palm mass M = m / mass_ratio", palm_mass, "kg", None),
        ("palm width x thickness", f"{scene.palm.width * 1e3:g} x "
         f"{scene.palm.thickness * 1e3:g}", "mm", None),
        ("object mass, width x height", f"{scene.body.mass:g} kg, {scene.body.width * 1e3:g} x "
         f"{scene.body.height * 1e3:g}", "mm", None),
        ("handover speed (periodic)", analysis.periodic.get("handover_speed"), "m/s", None),
    ]
    return summary, items


def _stairs(spec, analysis, tol, count):
    from ..sim.stairs import stairs_geometry

    geo = stairs_geometry(spec.scene, spec.design_at())
    tr, tt = (tol["rise"], tol["tread"]) if tol else (None, None)
    covered = spec.verification.stages
    items = []
    for k in range(1, count + 1):
        items.append({
            "step": k, "rise_m": geo.rise_height(k), "tread_m": geo.tread_length(k),
            "rise_tolerance_m": tr if k <= covered else None,
            "tread_tolerance_m": tt if k <= covered else None,
            "back_x_m": geo.back_x(k), "nose_x_m": geo.nose_x(k), "level_m": geo.level(k),
            "landing_from_back_m": geo.landing_offset,
        })
    d = analysis.design
    summary = [
        ("steps", count, "", None),
        ("rise (every step)", geo.rise, "m", tr),
        ("tread (every step)", geo.tread, "m", tt),
        ("landing point from the back of each tread", geo.landing_offset, "m", None),
        ("launch height above tread 1", geo.launch_height, "m", None),
        ("launch speed (horizontal)", d["launch_speed"], "m/s", None),
        ("back of tread 1 (launch at x = 0)", geo.x_back_1, "m", None),
        ("restitution", d["restitution"], "", None),
        ("ball radius", spec.scene.ball.radius, "m", None),
        ("impact speed (periodic)", analysis.periodic.get("impact_speed"), "m/s", None),
    ]
    return summary, items
