"""Typed tolerances: which quantities of a build vary, by how much, and how.

A tolerance is a +- value in SI units (or a request to allocate one, with a relative weight:
how cheap it is to hold tight; allocated tolerances share one scale s, t_q = s * w_min / w_q,
so a quantity twice as cheap to hold tight gets half the tolerance: `allocation_shares`),
applied to every part on its own ("each": every stage's own pivot, link or step) or once to
the whole build ("lot": one friction for a material batch, one mass for an object batch).

Distributions, for the statistical analysis:
  normal   (the default) mean 0, sigma = t / 3, the mechanical engineering convention: 99.73 %
           of parts within +-t; not truncated;
  uniform  uniform in [-t, t].

Each scene lists (Scene.quantities) every quantity that may vary, with its SI unit, the unit a
build sheet shows it in (and the factor from SI to that unit), and how it may apply. A new
quantity is one more entry of its scene's list; its random stream follows from its name
(tolerances/draw.py; Scene.stream_keys keeps the first quantities' older ones), so the other
quantities keep theirs.

This is the vocabulary every layer speaks (the spec, the formulation, the yield, the sheets):
it imports nothing of theirs.
"""

from __future__ import annotations

from dataclasses import dataclass

from .units import WORKSHOP

DISTRIBUTIONS = ("normal", "uniform")
APPLIES_TO = ("each", "lot")
SIGMAS_PER_TOLERANCE = 3.0  # normal: sigma = t / 3


@dataclass(frozen=True)
class Quantity:
    """One quantity that may vary: name, SI unit, build unit and the factor from SI to it,
    the applies_to values it allows (the first is its default), and what it is."""

    name: str
    unit: str
    build_unit: str
    build_factor: float
    applies: tuple[str, ...]
    what: str

    @property
    def default_applies_to(self) -> str:
        return self.applies[0]


def quantity(name, unit, applies, what) -> Quantity:
    """A scene's toleranced quantity, with its workshop unit (units.py)."""
    build_unit, factor = WORKSHOP.get(unit, (unit, 1.0))  # units.py: one table for every layer
    return Quantity(name, unit, build_unit, factor, applies, what)


EACH_OR_LOT, LOT = ("each", "lot"), ("lot",)


@dataclass(frozen=True)
class Tolerance:
    """One toleranced quantity. value: +- t in SI units, or None when it is to be allocated
    (then weight says how cheap it is to hold tight, relative to the others)."""

    quantity: str
    applies_to: str = "each"
    value: float | None = None
    weight: float = 1.0
    distribution: str = "normal"

    def __post_init__(self):
        if not (isinstance(self.quantity, str) and self.quantity.isidentifier()):
            raise ValueError(f"unknown quantity {self.quantity!r}")
        if self.applies_to not in APPLIES_TO:
            raise ValueError(f"applies_to must be one of {APPLIES_TO}")
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"distribution must be one of {DISTRIBUTIONS}")
        if self.value is not None and not self.value > 0.0:
            raise ValueError("value must be > 0")

    @property
    def allocate(self) -> bool:
        return self.value is None

    @property
    def sigma(self) -> float:
        """Standard deviation of the deviation (SI)."""
        if self.value is None:
            raise ValueError(f"{self.quantity} has no value yet (it is to be allocated)")
        if self.distribution == "normal":
            return self.value / SIGMAS_PER_TOLERANCE
        return self.value / 3.0 ** 0.5

    def scaled(self, factor: float) -> Tolerance:
        """The same tolerance with its value times factor (yield against tolerance scale)."""
        return Tolerance(self.quantity, self.applies_to, self.value * factor, self.weight,
                         self.distribution)

    def to_json(self, kind: str) -> dict:
        q = quantities_of(kind)[self.quantity]
        return {"quantity": self.quantity, "applies_to": self.applies_to, "value": self.value,
                "unit": q.unit, "distribution": self.distribution,
                "allocate": self.allocate, "weight": self.weight}


@dataclass(frozen=True)
class Tolerances:
    """A spec's [tolerances]: the toleranced quantities and the yield run's settings (builds
    drawn, the random seed, and how many random builds the event simulator confirms)."""

    items: tuple[Tolerance, ...] = ()
    builds: int = 10_000
    seed: int = 0
    confirm: int = 20
    yield_target: float | None = None  # the yield allocated tolerances are sized for
    # local processes the event simulator runs a yield's builds on (None: one per core); the
    # builds' outcomes do not depend on it
    workers: int | None = None

    def __iter__(self):
        return iter(self.items)

    def __len__(self) -> int:
        return len(self.items)

    def __bool__(self) -> bool:
        return bool(self.items)

    def scaled(self, factor: float) -> Tolerances:
        return Tolerances(tuple(t.scaled(factor) for t in self.items), self.builds, self.seed,
                          self.confirm, self.yield_target, self.workers)


def allocation_shares(tolerances) -> dict[str, float]:
    """{quantity: w_min / w_q} of every tolerance to allocate: t_q = s * share for the one
    scale s that the worst-case allocation (formulation/allocation.py) or a yield target
    (solve/yield_allocation.py) chooses. A weight says how cheap the quantity is to hold tight:
    twice the weight, half the tolerance; the smallest weight gets s itself."""
    allocated = [t for t in tolerances if t.allocate]
    if not allocated:
        return {}
    w_min = min(t.weight for t in allocated)
    return {t.quantity: w_min / t.weight for t in allocated}



def zero_nominal(quantity: str, nominal: float, setter: str) -> tuple[str, str, str] | None:
    """(key, expected, found) refusing a tolerance on a quantity whose nominal is 0 (links of
    no mass, a frictionless material: every part drawn around it would be at or below 0);
    setter: what sets the nominal, in words ("a scene.friction"). None when nominal > 0."""
    if nominal > 0.0:
        return None
    name = quantity.replace("_", " ")
    return (f"tolerances.{quantity}", f"{setter} > 0: the nominal {name} is 0, and a "
            "tolerance around 0 draws half the parts below it (give the nominal, or drop the "
            "tolerance)", f"nominal {name} = 0")


def quantities_of(kind: str) -> dict[str, Quantity]:
    """The toleranced quantities of the scene `kind` (its Scene.quantities)."""
    from .plugin import scene_kind

    return scene_kind(kind).quantities()
