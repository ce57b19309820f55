"""`formulate(spec)`: the scene's NLP, built once per spec and cached."""

from __future__ import annotations

import functools
import threading
import time
from dataclasses import replace

from ..analysis.result import required
from ..lru import Bounded
from . import manipulator_offsets, manipulators, stairs, stairs_errors
from .common import Formulation, assemble, spec_key

_CACHE: Bounded = Bounded()  # the specs formulated last
FULL = " +deferred rows"  # cache key suffix of a spec's NLP with its deferred rows
_LOCK = threading.Lock()


def formulate(spec, *, cache: bool = True, full: bool = False) -> Formulation:
    """The NLP of `spec` (cached by everything it depends on; requirements are parameters).
    full: with the deferred rows in the NLP (the same Formulation when there are none)."""
    key = spec_key(spec) + (FULL if full else "")
    with _LOCK:
        if cache and key in _CACHE:
            return _CACHE[key]
    if full:
        core = formulate(spec, cache=cache)
        if core.deferred is None:
            return core
    start = time.perf_counter()
    module = stairs if spec.kind == "stairs" else manipulators
    model, bounds, closed_forms = module.build(spec)
    # the explicit-offset scenario grows with the row: built when first asked for (the
    # manipulators' stage maps also stream samples through the row: solve/check.py)
    if spec.kind == "stairs":
        source = functools.partial(stairs_errors.scenario, spec, model, closed_forms)
    else:
        source = manipulator_offsets.Stages(spec, model, closed_forms)
    model = replace(model, scenario=source)
    form = assemble(spec, model, key=key, bounds=bounds, defer=not full)
    form = replace(form, build_time=time.perf_counter() - start)
    if cache:
        with _LOCK:
            _CACHE[key] = form
    return form


def min_margin_term(kind: str, margins: dict[str, float],
                    requirements: dict[str, float]) -> float | None:
    """The max_min_margin objective's value at a design from its reported margins (the
    closed-form analysis'): the smallest of the margins the objective covers, each less the
    requirement the NLP holds it to (`analysis.result.required`; the plain smallest margin when
    nothing is required). None when the design has none of them."""
    module = manipulators if kind == "manipulators" else stairs
    covered = [n for n in margins if n not in module.OUTSIDE_MIN_MARGIN]
    need = {n: required(n, requirements) for n in covered}
    return min((margins[n] - need[n] for n in covered), default=None)
