"""`formulate(spec)`: the scene's NLP, built once per spec and cached."""

from __future__ import annotations

import threading
import time
from dataclasses import replace

from . import manipulator_offsets, manipulators, stairs, stairs_errors
from .common import Formulation, assemble, spec_key

_CACHE: dict[str, Formulation] = {}
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
    if spec.kind == "stairs":
        model = replace(model, scenario=stairs_errors.scenario(spec, model, closed_forms))
    else:
        model = replace(model, scenario=manipulator_offsets.scenario(spec, model, closed_forms))
    form = assemble(spec, model, key=key, bounds=bounds, defer=not full)
    form = replace(form, build_time=time.perf_counter() - start)
    if cache:
        with _LOCK:
            _CACHE[key] = form
    return form
