"""One NLP for many specs that differ only in a few scene numbers: a table's axes.

A table sweeps numbers of the spec (`pdm-design table --sweep mass_ratio=... --sweep
friction=...`). Written as constants, each point's numbers make a new NLP: its CasADi
expressions, its IPOPT solvers and its stage maps built again, most of a point's time
(results/bench_scale.md). Written as CasADi parameters, the NLP of the first point serves
every point: a point binds its numbers (`Formulation.bind`) and reuses the built solvers.

Which numbers can be parameters (Scene.nlp_parameters): those the formulation uses only in
its rows' expressions, never to decide the NLP's shape (how many rows are checked, the
tolerance variable's bound, the objective's scale read some of the design's numbers, so those
stay constants). The symbolic build also checks this: a number compared or converted to a
float while the NLP is built raises there, and the spec falls back to its own NLP
(formulation/build.py). A spec asks for parameters with `Spec.nlp_parameters` (the table sets
it to its swept paths, sweep/run.py); `optimize` of one spec builds its NLP with constants, as
before. The parameters change the NLP's arithmetic, not its rows: a point's answer is the one
its own NLP gives, to IPOPT's tolerance (tests/test_parametric.py).
"""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np

PLACEHOLDER = 0.0  # the parameters' value in the cache key's spec (the key also names them)


def names(spec) -> tuple[str, ...]:
    """The spec's nlp_parameters that its NLP can take as parameters: a fixed number at one of
    its scene's Scene.nlp_parameters paths, and no linearised yield in the NLP (max_yield, a
    yield target: its chain of stage maps reads the scene as numbers)."""
    from ..plugin import of
    from .yield_target import active

    asked = getattr(spec, "nlp_parameters", ())
    if not asked or spec.objective.get("max_yield") or active(spec):
        return ()
    allowed = of(spec).nlp_parameters
    out = []
    for name in asked:
        if name not in allowed:
            continue
        if name.startswith("design.") and not isinstance(
                spec.design.get(name.split(".", 1)[1]), (int, float)):
            continue  # free (Bounds) or left to its default: not a number of the spec
        out.append(name)
    return tuple(sorted(out))


def values(spec, chosen: tuple[str, ...]) -> np.ndarray:
    """The spec's numbers at the chosen paths, in their order."""
    return np.array([float(_get(spec, name)) for name in chosen])


def key_spec(spec, chosen: tuple[str, ...]):
    """The spec with every chosen number at PLACEHOLDER: its spec_key is the key of every spec
    that differs from it only there."""
    return _with(spec, chosen, [PLACEHOLDER] * len(chosen), validate=True)


def symbolic_spec(spec, chosen: tuple[str, ...], symbols):
    """The spec with every chosen number a CasADi symbol (symbols[i]); built without
    validation (a symbol is no number): only the formulation reads it."""
    return _with(spec, chosen, [symbols[i] for i in range(len(chosen))], validate=False)


def _get(spec, name: str):
    head, *rest = name.split(".")
    if head == "design":
        return spec.design[rest[0]]
    value = spec.scene
    for part in rest:
        value = getattr(value, part)
    return value


def _with(spec, chosen, numbers, *, validate: bool):
    design = dict(spec.design)
    scene = spec.scene
    for name, number in zip(chosen, numbers):
        head, *rest = name.split(".")
        if head == "design":
            design[rest[0]] = number
        else:
            scene = _set(scene, rest, number, validate)
    return replace(spec, design=design, scene=scene)


def _set(obj, path, number, validate: bool):
    """obj with obj.path = number (a copy of every dataclass on the way)."""
    field, *rest = path
    value = number if not rest else _set(getattr(obj, field), rest, number, validate)
    if validate:
        return replace(obj, **{field: value})
    out = copy.copy(obj)
    object.__setattr__(out, field, value)
    return out

