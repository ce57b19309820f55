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
from dataclasses import dataclass
from importlib import metadata

GROUP = "pdm_design.scenes"


class SceneUnavailable(LookupError):
    """No installed scene has the kind asked for, or its package failed to load."""


@dataclass(frozen=True)
class StageErrors:
    """A scene's per-stage build errors as `simulate` takes them from the command line and the
    spec: option "--offset", metavar "K:DX,DY", the spec's `[verification]` list they extend
    ("offsets"), the stage field of its items ("manipulator"), and `make(k, a, b)` the item."""

    option: str
    metavar: str
    key: str
    index: str
    make: object

    def item(self, k: int, a: float, b: float):
        return self.make(k, a, b)


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
        """The quantities a `[tolerances]` table may name (tolerances.model.Quantity by name);
        none by default."""
        return {}

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
    outside_min_margin: tuple[str, ...] = ()
    """Margins the max_min_margin objective does not cover."""

    def formulate(self, spec, parameters=None):
        """The scene's NLP: (SceneModel, bounds, scenario) — the model and the free variables'
        bounds {name: (min, max, guess)} as `formulation.common.assemble` takes them, and the
        source of its explicit-error scenarios (a `formulation.common.Scenario`, a function of
        no arguments that builds one, or None). parameters: the CasADi symbols of the scene
        numbers a table sweeps (Scene.parametric; formulation/parametric.py), or None."""
        raise NotImplementedError

    # ------------------------------------------------------------------ tolerances, yield, verification

    # ------------------------------------------------------------------ sheets, drawings, reports

    # ------------------------------------------------------------------ command line, tables, API
    def infeasible_words(self, spec, design: dict) -> str | None:
        """Why an optimisation found no feasible design, in words, when the scene can tell
        from the spec and the least-violation `design` (values by name); None to say only
        what IPOPT's status says."""
        return None

    table_geometry: tuple[str, ...] = ()
    """The analysis' geometry a design table shows, by name (Analysis.geometry keys)."""
    table_periodic: tuple[str, ...] = ()
    """The analysis' periodic orbit a design table shows, by name (Analysis.periodic keys)."""
    tolerance_axes: tuple[str, ...] = ()
    """The axes of the robust tolerance box of max_offset_tolerance (JSON `tolerance.<axis>`,
    metres): a pivot's ("dx", "dy") or a step's ("rise", "tread")."""

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
