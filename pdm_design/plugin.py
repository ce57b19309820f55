"""The scene interface, and the registry that finds scenes.

A scene (a device and the object it moves: stairs and a ball, a row of manipulators and a box, a
ramp and a walker) is one package that gives one `Scene` object. Everything the scene knows is a
method or an attribute of it: its spec tables, its design variables, its closed forms, its
simulator, its NLP rows, its tolerance quantities and build maps, its drawing and its animation,
its `init` template. The shared machinery (spec loading, solving, verifying, yield, tables,
sheets, reports, the CI gate, the CLI) asks the scene object and never which scene it has.

Scenes are found through the entry-point group `pdm_design.scenes` (docs/scenes.md): the scenes
that ship with pdm-design are registered in its pyproject.toml exactly as a scene in another
installed package is in that package's. Discovery is lazy: listing the installed kinds reads
package metadata only, and a command imports the one scene its spec names.

This module imports nothing heavy: the CLI's start-up path reaches it.
"""

from __future__ import annotations

import functools
from importlib import metadata

GROUP = "pdm_design.scenes"


class SceneUnavailable(LookupError):
    """No installed scene has the kind asked for, or its package failed to load."""


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
    """A few words for listings: "a ball bouncing down stairs"."""
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
    verification_hints: dict[str, str] = {}
    """`[verification]` keys this scene does not take, each with the reason shown to the user."""

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

    def max_yield_refusal(self, scene) -> tuple[str, str] | None:
        """(expected, found) when objective.max_yield cannot be modelled for this scene (its
        linearised yield is not derived for it); None when it can."""
        return ("a scene whose linearised yield is derived", f"a {self.kind} scene")

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
    outside_min_margin: tuple[str, ...] = ()
    """Margins the max_min_margin objective does not cover."""

    def formulate(self, spec, parameters=None):
        """The scene's NLP rows: (SceneModel, bounds, closed_forms, scenario) as
        `formulation.common.assemble` takes them. parameters: the CasADi symbols of the scene
        numbers a table sweeps (formulation/parametric.py), or None."""
        raise NotImplementedError

    def nlp_key(self, spec) -> tuple:
        """What else of a spec shapes the scene's NLP, beyond its scene, design, objective,
        stages and tolerances: requirements that add rows, accuracy settings its rows follow
        (a part of the NLP's cache key, formulation.common.spec_key). () by default."""
        return ()

    # ------------------------------------------------------------------ tolerances, yield, verification
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
    """Spec paths ("design.mass_ratio", "scene.palm.friction") whose numbers `formulate` can
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
                       accuracy="default", record_trajectory: bool = False):
        """The event simulator's run (sim.core.SimulationResult) of one build, deviations as
        `run_builds` takes them for one build (1-row arrays)."""
        raise NotImplementedError(f"a {self.kind} scene cannot simulate a toleranced build")

    def simulate_box_build(self, spec, design, errors, deviations: dict, accuracy):
        """The event simulator's run of one build of the explicit-offset box: errors the
        (a, b) pair of each stage along `box_axes` (m), deviations {quantity: a number, or a
        list of one per part} of the other quantities of an allocated box; the spec's own
        initial state and stages, accuracy an accuracy.Accuracy."""
        raise NotImplementedError(f"a {self.kind} scene has no explicit-offset box")

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

    def left_closed_forms(self, result) -> str:
        """Words appended to a nominal run's summary when the run left the closed forms'
        regime (an object that lifted off and flew on), so they are not compared with it
        ("; ..."); "" (the default) when it did not."""
        return ""

    def disagreement_note(self, spec) -> str:
        """What the closed forms leave out that the simulator models, where the spec has it,
        as words appended to a disagreement (" (...)"); "" by default."""
        return ""

    # ------------------------------------------------------------------ sheets, drawings, reports

    # ------------------------------------------------------------------ command line, tables, API


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
