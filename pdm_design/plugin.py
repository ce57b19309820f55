"""The scene interface, and the registry that finds scenes.

A scene (a device and the object it moves) is one package that gives one `Scene` object.
Everything the scene knows is a method or an attribute of it: its spec tables, its design
variables, its closed forms, its simulator, its NLP rows, its tolerance quantities and build
maps, its drawing and its animation, its `init` template. The shared machinery (spec loading,
solving, verifying, yield, tables, sheets, reports, the CI gate, the CLI) asks the scene object
and never which scene it has.

Scenes are found through the entry-point group `pdm_design.scenes` (docs/scenes.md): the scenes
that ship with pdm-design are registered in its pyproject.toml exactly as a scene in another
installed package is in that package's. Discovery is lazy: listing the installed kinds reads
package metadata only, and a command imports the one scene its spec names.

This module imports nothing heavy: the CLI's start-up path reaches it.
"""

from __future__ import annotations

import functools
import importlib
from dataclasses import dataclass
from importlib import metadata

GROUP = "pdm_design.scenes"


class SceneUnavailable(LookupError):
    """No installed scene has the kind asked for, or its package failed to load."""


@dataclass(frozen=True)
class StageErrors:
    """A scene's per-stage build errors as `simulate` takes them from the command line and the
    spec: option "--offset", metavar "K:DX,DY", the spec's `[verification]` list they extend
    ("offsets"), the field of its items that numbers their stage ("step"), and `make(k, a, b)`
    the item."""

    option: str
    metavar: str
    key: str
    index: str
    make: object

    def item(self, k: int, a: float, b: float):
        return self.make(k, a, b)


@dataclass(frozen=True)
class StageList:
    """A per-stage list of the spec's `[verification]` table (`[[verification.KEY]]`): `item`
    the frozen, self-validating dataclass of one item, `index` its field that numbers the
    item's stage (an integer from 1). The loader builds the items and refuses two of one stage
    and one beyond `verification.stages`, each at its key."""

    item: type
    index: str


class lazily:
    """A Scene method that is `module:function` of the scene's own package (a relative module,
    ".sheet:parts", resolved against the package of the class that names it), imported when
    first called and called with the method's arguments: the scene object stays light, its
    heavy parts load with the command that needs them."""

    def __init__(self, target: str):
        self.module, self.name = target.split(":")
        self.package = None
        self.__doc__ = f"`{target}` of the scene's package (imported when called)."

    def __set_name__(self, owner, name):
        self.package = owner.__module__.rpartition(".")[0]

    def __get__(self, instance, owner=None):
        # the function itself: it takes the method's arguments, not the scene object
        return getattr(importlib.import_module(self.module, self.package), self.name)


class Scene:
    """One kind of scene. Subclasses set the class attributes and implement the methods; the
    defaults here are what a scene without that capability does (documented per method).

    Every method takes typed objects (a `Spec`, a scene and a design of the scene's own
    classes); none reads TOML. Heavy imports belong inside the methods, so that loading the
    scene object costs only its own small module.
    """

    # ------------------------------------------------------------------ identity
    kind: str = ""
    """The spec's `[scene] kind`, and the entry point's name."""
    title: str = ""
    """A few words for listings: "an object passed along a row of pendulums"."""
    stage_noun: tuple[str, str] = ("stage", "stages")
    """What one stage of a run is called, singular and plural: ("step", "steps")."""

    # ------------------------------------------------------------------ the spec
    def scene_class(self) -> type:
        """The frozen, self-validating dataclass of the scene (`[scene]` and `[initial]`)."""
        raise NotImplementedError

    def design_class(self) -> type:
        """The frozen dataclass of one design point; its VARIABLES name the `[design]` keys."""
        raise NotImplementedError

    margins: tuple[str, ...] = ()
    """Every margin the analysis reports, by name: the `[requirements]` a spec may set."""

    covered_by: dict[str, tuple[str, ...]] = {}
    """{margin: the other requirements that hold it too}, where one NLP row measures two
    margins and takes the largest requirement of either (analysis.result.required judges a
    fixed design the same way); none by default."""

    @property
    def requirement_keys(self) -> tuple[str, ...]:
        """The `[requirements]` a spec may set: its margins (and any bound its NLP holds)."""
        return self.margins

    def bound_violations(self, spec, analysis) -> list[str]:
        """A fixed design's violations, in words, of the `[requirements]` that are bounds
        rather than margins (a largest spectral radius of the stage map); none by default."""
        return []
    verification_hints: dict[str, str] = {}
    """`[verification]` keys this scene does not take, each with the reason shown to the user."""

    def stage_lists(self) -> dict[str, StageList]:
        """The per-stage lists the spec's `[verification]` table may hold, by key, in the order
        its keys are listed in errors: the build errors of single stages that every
        verification run applies. A spec holds them in `verification.stage_lists`, read as
        `spec.verification.stage_list(key)` (() when none is given). None by default."""
        return {}

    def check_spec(self, scene, design: dict) -> tuple[str, str, str] | None:
        """A contradiction between the scene and the `[design]` table (fixed values and
        Bounds by name) of a spec that is valid key by key, as (key, expected, found); the
        loader reports it as bad input. None when there is none."""
        return None

    def stage_limit(self, free: bool) -> tuple[int, str]:
        """The most `[verification] stages` a spec may ask for (free: the design has free
        variables), and why, in words that follow "an integer <= N"."""
        return 10_000_000, ""

    def quantities(self) -> dict:
        """The quantities a `[tolerances]` table may name (tolerance_model.Quantity by name);
        none by default."""
        return {}

    stream_keys: dict[str, int] = {}
    """{quantity: the spawn key of its random stream} of the quantities whose builds were drawn
    before the streams were keyed by name (tolerances/draw.py): closed, so that their draws stay
    the same. None by default: every quantity's stream is keyed by its name."""

    def max_yield_refusal(self, scene) -> tuple[str, str] | None:
        """(expected, found) when objective.max_yield cannot be modelled for this scene (its
        linearised yield is not derived for it); None when it can."""
        return ("a scene whose linearised yield is derived", f"a {self.kind} scene")

    def variants(self, spec) -> tuple:
        """The specs to solve for `spec`, one per value of a discrete design variable the NLP
        cannot take (the best answer is kept); (spec,) by default."""
        return (spec,)

    def template(self) -> str:
        """The commented spec `pdm-design init KIND` prints, which optimizes as written."""
        raise NotImplementedError

    # ------------------------------------------------------------------ closed forms
    def analyse(self, scene, design, stages: int | None = None):
        """The closed-form analysis of one design (an `analysis.Analysis`)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ the simulator
    def simulate(self, spec, design, *, stages: int, accuracy, errors=None,
                 record_trajectory: bool = False):
        """The event simulator's run (a `sim.core.SimulationResult`) from the spec's initial
        state. errors: the per-stage build errors the scene takes (None: the spec's own)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ the NLP
    objectives: tuple[str, ...] = ("max_min_margin",)
    """The `[objective]` terms the scene's NLP gives (SceneModel.objective_terms)."""
    search_objectives: tuple[str, ...] = ()
    """Objectives no NLP states, which the scene's own `search` optimises (a rough ramp's
    mean steps before failure: max_mfpt)."""

    def search(self, spec) -> tuple[dict, float]:
        """(the free variables' values, the objective's value) that a search objective of the
        spec chooses; the answer is then evaluated and verified as a fixed design."""
        raise NotImplementedError(f"a {self.kind} scene has no search objective")

    objective_aliases: dict[str, str] = {}
    """The scene's own names of shared objective terms (formulation.common.OBJECTIVE_SENSE):
    a scene's max_slope_tolerance is the shared max_offset_tolerance. The loader stores the
    spec's objective under the shared names."""
    outside_min_margin: tuple[str, ...] = ()
    """Margins the max_min_margin objective does not cover."""

    def formulate(self, spec, parameters=None):
        """The scene's NLP: (SceneModel, bounds, scenario) — the model and the free variables'
        bounds {name: (min, max, guess)} as `formulation.common.assemble` takes them, and the
        source of its explicit-error scenarios (a `formulation.common.Scenario`, a function of
        no arguments that builds one, or None). parameters: the CasADi symbols of the scene
        numbers a table sweeps (Scene.parametric; formulation/parametric.py), or None."""
        raise NotImplementedError

    def nlp_key(self, spec) -> tuple:
        """What else of a spec shapes the scene's NLP, beyond its scene, design, objective,
        stages and tolerances: requirements that add rows, accuracy settings its rows follow
        (a part of the NLP's cache key, formulation.common.spec_key). () by default."""
        return ()

    # ------------------------------------------------------ tolerances, yield, verification
    allocatable: tuple[str, ...] = ()
    """The quantities whose worst-case tolerance the robust NLP allocates, or takes as given
    half-widths while allocating: those over whose box a sound outer bound of every row is
    derived (docs/optimizer.md section 4a). None by default: any allocation is refused."""

    def allocation_refusal(self, spec) -> tuple[str, str, str] | None:
        """(key, expected, found) when the spec's worst-case allocation, of allocatable
        quantities, needs what the scene's robust rows do not bound (a sloped start, a nominal
        of 0); None (the default) when the rows bound it."""
        return None

    nlp_parameters: tuple[str, ...] = ()
    """Spec paths ("design.mass_ratio", "scene.body.width") whose numbers `formulate` can
    take as CasADi parameters (formulation/parametric.py): read only in the rows' expressions,
    never to shape the NLP. None by default: a table builds each point's own NLP."""

    sizes_for_yield_target: bool = False
    """Whether `formulate` sizes the allocated tolerances for tolerances.yield_target (the
    nines row of formulation/yield_target.py). False by default: such a spec is treated as a
    worst-case allocation."""

    box_axes = None
    """The explicit-offset box (a plugin_tolerances.BoxAxes): the two errors each stage takes
    in the scenario (`formulate`) and in `simulate`, with their quantities, and the quantities
    every part holds. None by default: the scene has no per-stage box."""

    def box_axes_of(self, spec):
        """The explicit-offset box of this spec (a scene whose box depends on the spec, a slope
        on a ramp or rise and tread on steps, says so here); `box_axes`."""
        return self.box_axes

    def length_scale(self, spec, design: dict) -> float:
        """The device's size (m) at a design (values by name): the unit the linearised
        tolerance regions are solved in. 1 m by default."""
        return 1.0

    def tolerance_refusal(self, spec, quantity: str) -> tuple[str, str, str] | None:
        """(key, expected, found) when a yield cannot draw builds of this toleranced quantity
        of the spec (a nominal of 0 that half the parts would fall below; a quantity the
        scene's spec leaves out of its physics); None (the default) when it can."""
        return None

    def run_builds(self, scene, design, deviations: dict, stages: int):
        """The closed-form outcome (tolerances.outcome.BuildOutcome) of many builds of one
        design: deviations {quantity: (builds, stages) array for each part, (builds,) for a
        lot} in SI units, added to the nominal values."""
        raise NotImplementedError(f"a {self.kind} scene has no closed-form map of its builds")

    def simulate_build(self, scene, design, deviations: dict, stages: int, *,
                       accuracy="default", record_trajectory: bool = False,
                       allow_skips: bool = False):
        """The event simulator's run (sim.core.SimulationResult) of one build, deviations as
        `run_builds` takes them for one build (1-row arrays); allow_skips: the spec's
        [verification] allow_skips (a run that comes onto a stage beyond the next goes on)."""
        raise NotImplementedError(f"a {self.kind} scene cannot simulate a toleranced build")

    def simulate_box_build(self, spec, design, errors, deviations: dict, accuracy):
        """The event simulator's run of one build of the explicit-offset box: errors the
        (a, b) pair of each stage along `box_axes` (m), deviations {quantity: a number, or a
        list of one per part} of the other quantities of an allocated box; the spec's own
        initial state and stages, accuracy an accuracy.Accuracy."""
        raise NotImplementedError(f"a {self.kind} scene has no explicit-offset box")

    def yield_extras(self, scene, design, tolerances, stages: int) -> dict:
        """Entries the scene adds to a yield's JSON (a rough ramp's `mfpt`: the mean steps
        before failure by a method made for rare failures); none by default."""
        return {}

    def linearised_yield(self, scene, design, tolerances, stages: int) -> dict:
        """The linearised yield of a fixed design under valued tolerances: a dict whose
        "yield" is a lower bound on the fraction of builds that pass `stages` stages."""
        raise NotImplementedError(f"no linearised yield is derived for a {self.kind} scene")

    def linearised_rows(self, scene, design, tolerances, stages: int):
        """The rows of the linearised yield, placed along the run
        (plugin_tolerances.PlacedRows): what limits tolerances sized for a yield."""
        raise NotImplementedError(f"no linearised yield is derived for a {self.kind} scene")

    def closed_form_agreement(self, spec, analysis, result) -> dict | None:
        """How far a nominal run's simulated stage quantities are from the closed forms':
        {"quantity": what, in words, "relative_error": the largest, "compared": how many
        stages}; None (the default) when nothing is compared."""
        return None

    def condition_words(self) -> dict[str, tuple[str, str, tuple[tuple[str, str], ...]]]:
        """Each NLP condition in a designer's words, by name: (what it asks, what to change,
        ((a phrase of the row's `where`, what to change there instead), ...)) for the elastic
        diagnosis (solve/words.py). None by default: a condition is shown by its name."""
        return {}

    place_nouns: tuple[str, ...] = ()
    """The nouns that number a place along the run in an NLP row's `where` ("flight" of
    "flight 3, ..."): the diagnosis writes the rows of one condition that differ only in that
    number as one line ("flights 1-3, 5"). None by default: each row is its own line."""

    def left_closed_forms(self, result) -> str:
        """Words appended to a nominal run's summary when the run left the closed forms'
        regime (an object that lifted off and flew on), so they are not compared with it
        ("; ..."); "" (the default) when it did not."""
        return ""

    def disagreement_note(self, spec) -> str:
        """What the closed forms leave out that the simulator models, where the spec has it,
        as words appended to a disagreement (" (...)"); "" by default."""
        return ""

    # ------------------------------------------------------ sheets, drawings, reports
    # A build sheet lists one item (a CSV row) per stage: whatever a workshop places for that
    # stage (a pivot, a step). The defaults give a scene that implements only the
    # core above a usable sheet and report: its design values, one row per stage, the simulated
    # path drawn, no parts.
    tolerance_axes: tuple[str, ...] = ()
    """The axes of the optimizer's robust placement box (the keys of its `tolerance`, each a
    half-width in m): ("dx", "dy"); () (default): the scene has no box."""

    def sheet_rows(self, spec, analysis, tolerance: dict | None, count: int):
        """(summary, items) of the build sheet of a fixed-design spec: summary rows (quantity,
        value, unit SI or "", box half-width or None), items one dict per stage 1..count (CSV
        columns, SI units in the names: "_m", "_rad"). Default: the design values, and items
        numbered by the stage noun."""
        from .sheet.generic import sheet_rows

        return sheet_rows(self, spec, analysis, tolerance, count)

    def sheet_words(self):
        """The sheet's words (sheet.generic.SheetWords): what an item's coordinates are of
        ("pivot"), the drawing's legend and its units ("millimetres, degrees")."""
        from .sheet.generic import SheetWords

        return SheetWords(item=self.stage_noun[0],
                          legend="dotted: the object's path (simulated); dots: the place each "
                                 "stage record gives, numbered", units="millimetres")

    def box_shift(self, spec):
        """A sheet.generic.BoxShift when the robust box of a fixed design is solved for
        another spec (a design value the NLP holds to its periodic orbit left free) and one
        axis's half-width shrinks by the design's offset from it; None (default): solved
        for the spec as it is."""
        return None

    def box_tolerances(self, sheet, why: str) -> tuple:
        """The sheet's own tolerances (sheet.parts.ToleranceEntry) from its box
        `sheet.tolerance`, `why` their limited_by. Default: one "AXIS (box)" entry an axis
        (m), on the stages it covers."""
        from .sheet.generic import box_tolerances

        return box_tolerances(self, sheet, why)

    quantity_parts: dict[str, str] = {}
    """{toleranced quantity: the part it is built on, in words ("every step", "the feed (start
    place)")}, which sheet/parts.py files its tolerance under (part_words); a quantity not
    named is shown under its own name."""

    part_words: dict[str, tuple[str, ...]] = {}
    """{part name: words of a ToleranceEntry.applies_to that put it on that part}, first
    match wins; a tolerance matching none is listed under "other tolerances"."""

    def parts(self, sheet) -> list:
        """The parts list (sheet.parts.Part, dimensions in words in mm and degrees) without
        their tolerances (sheet/parts.py adds them by part_words). Default: none."""
        return []

    def table_rows(self, sheet) -> list[str]:
        """The PDF's table of every item: a heading and one fixed-width row an item, mm.
        Default: the items' columns, lengths in mm."""
        from .sheet.generic import table_rows

        return table_rows(sheet)

    def draw_sheet(self, ax, labels, sheet, items, detail: bool) -> None:
        """Draw `items` (a slice of sheet.items) on the matplotlib axes, mm; labels: the
        sheet.labels.Labels that keep words apart; detail: dimension them (few enough to read).
        Default: the simulated path, and the place each stage record gives (its x, y) marked
        and numbered."""
        from .sheet.generic import draw_path

        draw_path(ax, labels, sheet, items)

    dxf_layers: dict[str, int] = {}
    """The DXF layers the scene draws on besides DIMENSIONS and NOTES: {name: AutoCAD colour}."""

    def draw_dxf(self, msp, sheet) -> float:
        """Draw every item on the ezdxf modelspace (mm, full precision) on dxf_layers and
        DIMENSIONS; returns the text height (mm) the notes are written at. Default: the
        simulated path as a polyline on DIMENSIONS, a POINT at each stage record's x, y."""
        from .sheet.generic import draw_dxf

        return draw_dxf(msp, sheet)

    quantity_units: dict[str, str] = {}
    """{quantity: its SI unit ("m", "rad/s", "kg m^2"; "" for a ratio or a count)} of the
    design, geometry and periodic-orbit quantities the reports show, over the shared table
    (report/units.py UNITS); a quantity in neither is shown without a unit."""

    def shown_geometry(self, geometry: dict) -> dict:
        """The analysis' geometry the text report and the report page show (the JSON keeps
        every key): a scene leaves out the rows of parts a device has not built. Default:
        all of it."""
        return geometry

    def document_keys(self) -> dict[str, tuple[str, ...]]:
        """The keys the optimize JSON document (report/document.py) carries in "design",
        "geometry", "periodic" and "approach", null where the analysis has none (then any
        other the analysis gives). Default: the design class's VARIABLES, and the analysis'
        own keys for the rest."""
        return {"design": tuple(self.design_class().VARIABLES), "geometry": (),
                "periodic": (), "approach": ()}

    def scene_parameters(self, scene) -> dict:
        """The device-as-built keys of a scene for the JSON document's `scene_parameters`
        (docs/json-schema.md), every key even when the spec leaves it out; {} (default) when
        the scene has none."""
        return {}

    stage_columns: tuple[str, ...] = ()
    """The stage record keys `pdm-design simulate` prints a column each of; () (default): the
    first stage record's keys."""

    def plot_run(self, spec, design, result, path, *, offsets=(), stages=None,
                 title: str = "") -> None:
        """Draw a run recorded with its trajectory into an image file at `path`, whole or not
        at all (offsets, stages: those the run used). Default: the path and y(t)."""
        from .report.plots import plot_path

        plot_path(result, path, title=title)

    def animation(self, spec, result, timeline):
        """The report page's animation of a run (report.animation.Animation): `data`, the
        scene's part of the page's JSON (mm, y up; at least "window", the view's width when
        the run is longer, and "below", how far the view's centre is under the object), and
        `script`, a JavaScript object expression {extent, lift, build} the page's one player
        calls (report/animation.py documents them). timeline (report.animation.Timeline):
        the run's sample times, sorted, and the frame times. Default: the object as a dot on
        its path."""
        from .report.animation import generic_animation

        return generic_animation(result)

    # ------------------------------------------------------ command line, tables, API
    def infeasible_words(self, spec, design: dict) -> str | None:
        """Why an optimisation found no feasible design, in words, when the scene can tell
        from the spec and the least-violation `design` (values by name); None to say only
        what IPOPT's status says."""
        return None

    column_labels: dict[str, tuple[str, str]] = {}
    """{design table column: (its label on the table's plots, its SI unit)} over the shared
    ones (sweep/plots.py); a column in neither is labelled by its name, without a unit."""
    table_geometry: tuple[str, ...] = ()
    """The analysis' geometry a design table shows, by name (Analysis.geometry keys)."""
    table_periodic: tuple[str, ...] = ()
    """The analysis' periodic orbit a design table shows, by name (Analysis.periodic keys)."""

    def infeasible_cause(self, spec, design: dict) -> str | None:
        """A cause of an infeasible answer the rows' violations do not name (listed first among
        them), from the spec and the least-violation `design`; None by default."""
        return None

    def table_extras(self, spec, axes, *, plots: bool) -> dict[str, bytes]:
        """Files a design table adds for this scene, {name: content}, from its spec and its
        sweep axes (sweep.grid.SweepAxis): the bifurcations along a slope sweep. None by
        default."""
        return {}

    stage_errors: StageErrors | None = None
    """The per-stage build errors `simulate` takes (None: the scene takes none); they reach
    `simulate` as its `errors`."""


# ---------------------------------------------------------------------- the registry

def _entry_points() -> dict[str, metadata.EntryPoint]:
    found = {}
    for entry in metadata.entry_points(group=GROUP):
        found.setdefault(entry.name, entry)
    return found


def kinds() -> tuple[str, ...]:
    """The kinds of every installed scene, sorted (reads metadata; imports no scene)."""
    return tuple(sorted(_entry_points()))


@functools.cache
def scene_kind(kind: str) -> Scene:
    """The scene object of `kind`: its entry point loaded (only that scene's package imported).
    Raises SceneUnavailable naming the installed kinds when none has that name."""
    entry = _entry_points().get(kind)
    if entry is None:
        raise SceneUnavailable(f"no installed scene of kind {kind!r} (installed: "
                               f"{', '.join(kinds()) or 'none'})")
    try:
        loaded = entry.load()
    except Exception as exc:  # a third party's package: say which and why
        raise SceneUnavailable(f"the scene {kind!r} ({entry.value}) failed to load: "
                               f"{type(exc).__name__}: {exc}") from exc
    scene = loaded() if isinstance(loaded, type) else loaded
    if not isinstance(scene, Scene) or scene.kind != kind:
        raise SceneUnavailable(f"the entry point {kind!r} ({entry.value}) does not give a "
                               f"pdm_design.plugin.Scene of kind {kind!r}")
    return scene


def of(obj) -> Scene:
    """The scene object of a spec or a scene dataclass (anything with a `kind`)."""
    return scene_kind(obj.kind)
