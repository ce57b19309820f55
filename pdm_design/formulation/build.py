"""`formulate(spec)`: the scene's NLP, built once per spec and cached."""

from __future__ import annotations

import threading
import time
from dataclasses import replace

import casadi as ca

from ..analysis.result import required
from ..lru import Bounded
from ..plugin import of
from . import parametric
from .common import Formulation, assemble, spec_key

_CACHE: Bounded = Bounded()  # the specs formulated last
FULL = " +deferred rows"  # cache key suffix of a spec's NLP with its deferred rows
_LOCK = threading.Lock()
_UNUSABLE: set[str] = set()  # parametric keys whose symbolic build failed: one NLP per spec
_BOUND: Bounded = Bounded()  # generic NLPs bound to the specs formulated last


def formulate(spec, *, cache: bool = True, full: bool = False) -> Formulation:
    """The NLP of `spec` (cached by everything it depends on; requirements are parameters).
    full: with the deferred rows in the NLP (the same Formulation when there are none).
    A spec whose nlp_parameters name numbers the NLP can take as parameters gets the generic
    NLP of every spec that differs from it only there, bound to its numbers (parametric.py)."""
    key, chosen = _key(spec)
    if not chosen:
        return _formulated(spec, key, (), cache, full)
    bound_key = (key, full, tuple(parametric.values(spec, chosen)),
                 tuple(sorted((n, float(v)) for n, v in spec.requirements.items())))
    found = _BOUND.get(bound_key) if cache else None
    if found is not None:
        return found
    try:
        generic = _formulated(spec, key, chosen, cache, full)
    except (RuntimeError, TypeError, NotImplementedError):
        # the build read a parameter as a number (a comparison, a float()): this spec needs
        # its own NLP, as every spec with this key does
        _UNUSABLE.add(key)
        return formulate(spec, cache=cache, full=full)
    form = generic.bind(spec)
    if cache:
        _BOUND[bound_key] = form
    return form


def is_cached(spec, full: bool = False) -> bool:
    """Whether formulate(spec, full=full) finds its NLP built."""
    return _key(spec)[0] + (FULL if full else "") in _CACHE


def _key(spec) -> tuple[str, tuple[str, ...]]:
    """(the cache key of the spec's NLP, the scene numbers it takes as parameters): the
    generic NLP's key (parametric.py), or the spec's own when it takes none or its generic
    build failed."""
    chosen = parametric.names(spec)
    if chosen:
        key = spec_key(parametric.key_spec(spec, chosen)) + f" parameters {chosen}"
        if key not in _UNUSABLE:
            return key, chosen
    return spec_key(spec), ()


def _formulated(spec, key: str, chosen: tuple[str, ...], cache: bool, full: bool) -> Formulation:
    """The NLP of `spec` under `key`, built on symbols for the `chosen` scene numbers."""
    base, key = key, key + (FULL if full else "")
    with _LOCK:
        if cache and key in _CACHE:
            return _CACHE[key]
    if full:
        core = _formulated(spec, base, chosen, cache, False)
        if core.deferred is None:
            return core
    start = time.perf_counter()
    parameters = None
    if chosen:
        symbols = ca.SX.sym("scene", len(chosen))
        spec, parameters = parametric.symbolic_spec(spec, chosen, symbols), (chosen, symbols)
    # the scene's rows, and the source of its explicit-offset scenarios (solve/check.py)
    model, bounds, source = of(spec).formulate(
        spec, None if parameters is None else parameters[1])
    model = replace(model, scenario=source)
    form = assemble(spec, model, key=key, bounds=bounds, defer=not full, parameters=parameters)
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
    from ..plugin import scene_kind

    covered = [n for n in margins if n not in scene_kind(kind).outside_min_margin]
    need = {n: required(n, requirements, kind) for n in covered}
    return min((margins[n] - need[n] for n in covered), default=None)
