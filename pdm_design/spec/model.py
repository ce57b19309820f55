"""The typed form of a spec file. Only `loader.py` reads TOML; everything else takes a Spec."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Annotated, Any

from pydantic import Field, PlainValidator, Strict
from pydantic.dataclasses import dataclass as checked

from ..accuracy import ACCURACY_PRESETS, Accuracy, accuracy
from ..scenes.common import CONFIG, LARGEST, Number
from ..tolerance_model import Tolerances

Count = Annotated[int, Strict(), Field(ge=1, le=10_000_000)]
SampleCount = Annotated[int, Strict(), Field(ge=0, le=1_000_000)]
# Weights beyond a million (or their ratios) only scale IPOPT's objective out of range.
Weight = Annotated[float, Strict(), Field(ge=0, le=LARGEST)]

# A preset name or a mapping of tolerances becomes an Accuracy (the loader resolves it first, to
# report errors at their key).
AccuracyField = Annotated[Accuracy, PlainValidator(accuracy)]

OBJECTIVES = ("max_offset_tolerance", "max_min_margin", "min_drop", "fastest_convergence",
              "max_yield")

@checked(frozen=True, config=CONFIG)
class Bounds:
    """A free design variable: lower and upper bound and an optional initial guess."""

    min: Number
    max: Number
    initial: Number | None = None

    def __post_init__(self):
        if self.min > self.max:
            raise ValueError(f"min ({self.min:g}) must not exceed max ({self.max:g})")
        if self.initial is not None and not self.min <= self.initial <= self.max:
            raise ValueError(f"initial ({self.initial:g}) must lie in [min, max]")

    @property
    def guess(self) -> float:
        return self.initial if self.initial is not None else 0.5 * (self.min + self.max)

    def side(self, value: float) -> str | None:
        """"min" or "max" when `value` is at that bound (see at_bound), else None."""
        return at_bound(value, self.min, self.max)


# A free variable within this fraction of its range (max - min) of a bound is reported at it.
AT_BOUND = 1e-6


def at_bound(value: float, low: float, high: float) -> str | None:
    """"min" or "max" when value lies within AT_BOUND (high - low) of that bound; None inside,
    and for a pinned range (low = high: not free, so at no bound)."""
    span = high - low
    if not span > 0.0:
        return None
    if value - low <= AT_BOUND * span:
        return "min"
    return "max" if high - value <= AT_BOUND * span else None


@checked(frozen=True, config=CONFIG)
class Verification:
    """How designs are verified in the simulator. stages: the stages a run must pass (what a
    scene calls one: Scene.stage_noun). stage_lists: the scene's per-stage lists
    (Scene.stage_lists) as ((key, items), ...), every key the scene has, in its order; the
    spec's `[verification]` table holds them under those keys."""

    stages: Count = 6
    accuracy: AccuracyField = ACCURACY_PRESETS["default"]
    samples: SampleCount = 16
    stage_lists: tuple[tuple[str, tuple], ...] = ()
    # a run whose object skips a stage (lands on one further on) passes; by default it fails
    # (a scene whose runs cannot skip refuses the key: Scene.verification_hints)
    allow_skips: Annotated[bool, Strict()] = False

    def stage_list(self, key: str) -> tuple:
        """The items of the per-stage list `key`: () when the spec gives none, or when its
        scene has no such list."""
        return next((items for name, items in self.stage_lists if name == key), ())

    @property
    def has_stage_items(self) -> bool:
        """Whether any per-stage list has an item (the runs are of another build than the
        design's own)."""
        return any(items for _, items in self.stage_lists)

    def __getattr__(self, name: str):
        # a per-stage list read as an attribute (spec.verification.KEY) where the scene has it
        for key, items in self.__dict__.get("stage_lists", ()):
            if key == name:
                return items
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


@checked(frozen=True, config=CONFIG)
class Expectations:
    """What CI expects of a spec (`pdm-design check`); None means not checked."""

    feasible: Annotated[bool, Strict()] | None = None
    verified: Annotated[bool, Strict()] | None = None
    min_objective: Number | None = None
    min_tolerance: Annotated[float, Strict(), Field(ge=0)] | None = None
    min_margin: Number | None = None
    min_yield: Annotated[float, Strict(), Field(ge=0, le=1)] | None = None


@dataclass(frozen=True)
class Spec:
    """A whole spec: the scene, the design space and what is asked of the design.

    design maps each design variable (by its spec name) to a fixed value or to Bounds;
    variables left out take the scene's defaults (see docs/spec.md).
    """

    source: str
    scene: Any  # the scene's own frozen dataclass (plugin.Scene.scene_class)
    design: dict[str, float | Bounds]
    objective: dict[str, float] = field(default_factory=dict)
    requirements: dict[str, float] = field(default_factory=dict)
    verification: Verification = Verification()
    expect: Expectations = Expectations()
    tolerances: Tolerances = Tolerances()
    name: str = ""
    description: str = ""
    # sha256 of the spec's content (spec.loader.content_digest): a saved design names the spec
    # it was made from with it, so a sheet can refuse one whose spec has changed since
    digest: str = field(default="", compare=False)
    # spec paths ("design.mass_ratio", "scene.body.width") a table varies: the NLP takes
    # those it can as parameters, one NLP for every point (formulation/parametric.py)
    nlp_parameters: tuple[str, ...] = field(default=(), compare=False)

    @property
    def kind(self) -> str:
        return self.scene.kind

    @property
    def design_class(self):
        from ..plugin import of

        return of(self).design_class()

    @property
    def free_variables(self) -> tuple[str, ...]:
        return tuple(k for k, v in self.design.items() if isinstance(v, Bounds))

    def design_at(self, values: dict[str, float] | None = None):
        """The design point with the free variables set from `values` (default: their guesses)."""
        values = values or {}
        resolved = {
            k: (float(values.get(k, v.guess)) if isinstance(v, Bounds) else v)
            for k, v in self.design.items()
        }
        return self.design_class(**resolved)
