"""What every scene's formulation shares: named conditions, the NLP assembly, the inverse map.

A scene's formulation (Scene.formulate, scenes/<kind>/formulation) writes each physical
condition once, as CasADi SX expressions built from the scene's closed forms:

    slack >= required_margin * scale        (capacity - demand >= r * capacity)

so that slack / scale is the normalised margin reported by `analysis.result.margin` whenever the
condition holds. `assemble` turns those conditions into one NLP

    minimise  f(x)   subject to   lbx <= x <= ubx,   lbg <= g(x, p) <= ubg

with x = [free design variables, auxiliary variables], p = the required margins (parameters, so one
built NLP is re-solved for other requirements), and returns a frozen `Formulation`: the
nlpsol-ready dict, bounds, the named condition list (for diagnosis) and the inverse map from a
solution vector back to named design values.

Condition kinds:
* "margin": a physical condition the spec may put a required margin on (key = margin name). With
  the `max_min_margin` objective the epigraph variable t enters as slack >= (required + t) scale,
  so t is the smallest margin above its requirement, maximised.
* "validity": must hold for the closed forms to describe the motion (e.g. the object lands moving
  forward); slack >= 0, no margin, no epigraph.
* "model": definitions of auxiliary variables (fixed point, invariant interval); never relaxed.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from ..spec.model import Bounds

OBJECTIVE_SENSE = {  # +1: larger is better, -1: smaller is better
    "max_offset_tolerance": 1.0,
    "max_min_margin": 1.0,
    "min_drop": -1.0,
    "fastest_convergence": -1.0,
    "max_yield": 1.0,
}

MARGIN, VALIDITY, MODEL = "margin", "validity", "model"
# Every physical inequality row asks for a little more than its requirement: `backoff` (the last
# NLP parameter) in the normalised row's units. IPOPT meets a row only to its tolerance (and
# relaxes it by bound_relax_factor): optima on a limit came back 1e-8 past it, and the simulator,
# run at the claimed box's corners and at the nominal design, failed 71 of 386 answers to 900
# random specs of one shipped scene on such ties (lift-off, tip, a stall at the top), and 36
# boxes of another's (a point object on a step's nose).
# The solver sets it to BACKOFF_FACTOR times its tolerance (1e-6 at the default 1e-8).
BACKOFF_FACTOR = 100.0
DEFAULT_BACKOFF = 1e-6


@dataclass(frozen=True)
class Condition:
    """One condition slack >= required * scale (or slack == 0 when equality)."""

    keys: tuple[str, ...]  # requirement keys (margin names); the largest requirement applies
    where: str  # where / in which scenario, in words
    slack: object
    scale: object = 1.0
    kind: str = MARGIN
    equality: bool = False
    epigraph: bool = True  # counts in max_min_margin
    # a model inequality whose slack has this unit keeps the backoff in it (a physical row keeps
    # it in the normalised row's units); None: a model row without backoff
    backoff_unit: object = None
    # a row that seldom binds and costs IPOPT iterations when present: left out of the NLP
    # first and added only if the answer without it breaks it (solve/optimize.py)
    deferred: bool = False
    # the toleranced quantities the row depends on, when the spec allocates tolerances
    # (formulation/allocation.py): the rows that can limit each quantity
    quantities: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        return self.keys[0] if self.keys else "model"

    @property
    def label(self) -> str:
        return f"{self.name} ({self.where})" if self.where else self.name


@dataclass(frozen=True)
class ConditionInfo:
    """What the solve layer needs to know about row `index` of g (no symbols)."""

    index: int
    name: str
    keys: tuple[str, ...]
    where: str
    kind: str
    equality: bool
    quantities: tuple[str, ...] = ()  # Condition.quantities

    @property
    def label(self) -> str:
        return f"{self.name} ({self.where})" if self.where else self.name


@dataclass(frozen=True)
class Scenario:
    """Conditions as explicit functions of the offsets / construction errors d (not worst cases):
    slack(x, d) and scale(x, d) per condition, for linearisation (cvxpy) and for sampling checks."""

    function: object  # casadi Function (x, d) -> (slack, scale)
    offset_names: tuple[str, ...]
    groups: dict[str, tuple[int, ...]]  # e.g. {"dx": (...), "dy": (...)}: columns of d per group
    conditions: tuple[ConditionInfo, ...]


@dataclass(frozen=True)
class SceneModel:
    """What a scene module hands to `assemble`."""

    kind: str
    design_symbols: dict[str, object]  # free design variable -> SX symbol
    aux: tuple[tuple[str, object, float, float], ...]  # (name, SX, lower, upper)
    conditions: tuple[Condition, ...]
    objective_terms: dict[str, object]  # objective name -> SX (natural value)
    margin_symbol: object | None  # SX of the epigraph variable t when max_min_margin, else None
    aux_init: object  # casadi Function design -> aux start values (aux order)
    derived: dict[str, object]  # named design quantities (SX) reported with the design
    tolerance_axes: tuple[str, ...]  # ("dx", "dy") or ("rise", "tread")
    # the Scenario, or a function of no arguments that builds it (built when first asked for:
    # it grows with the row, 0.37 s at 100 stages, and only the linearised sets use it)
    scenario: object = None
    # The NLP minimises f / objective_scale (the optimum is the same; the reported terms are in
    # natural units). IPOPT's dual and complementarity tolerances are absolute in f's units, so
    # f in metres on a centimetre scene stopped it short of the optimum (a scene sets it).
    objective_scale: float = 1.0
    # Whether optimize solves the multistart points together as one stacked NLP (solve/stacked.py).
    # Stacking shares IPOPT's per-iteration overhead, so it pays only where that overhead, not the
    # rows' evaluation, is an iteration's cost, and where the starts need alike iteration counts.
    stack_starts: bool = True
    # Whether optimize screens the multistart (solve/screen.py): IPOPT runs from the guess and
    # from only those sampled designs no better sample lies near, for an objective whose every
    # iteration costs a long walk (a row's yield), not from every start.
    screened_starts: bool = False
    # a term maximised besides the [objective] table's (None: none): the allocated scale's
    # log s of a yield target (formulation/yield_target.py)
    extra_objective: object = None


@dataclass(frozen=True)
class Formulation:
    """A spec's NLP, built once: hand `nlp` to casadi.nlpsol and solve many times."""

    kind: str
    key: str
    nlp: dict
    x_names: tuple[str, ...]
    design_names: tuple[str, ...]  # free design variables (first entries of x)
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    p_names: tuple[str, ...]  # requirement keys
    p_default: np.ndarray  # the spec's required margins, then DEFAULT_BACKOFF
    conditions: tuple[ConditionInfo, ...]
    objective_names: tuple[str, ...]
    weights: dict[str, float]
    evaluate: object  # casadi Function (x, p) -> (slack, scale, objective terms, derived)
    aux_init: object
    tolerance_axes: tuple[str, ...]
    tolerance_index: int | None  # index of the tolerance variable in x, if robust
    margin_index: int | None
    fixed: dict[str, float]  # design variables fixed by the spec
    derived_names: tuple[str, ...]
    norms: np.ndarray  # row normalisers of g (constants; a bound Formulation's at its numbers)
    scenario_source: object  # SceneModel.scenario: a Scenario, a builder of one, or None
    build_time: float = 0.0
    # rows left out of this NLP (Condition.deferred): Function (x, p) -> (slack, scale, row),
    # row >= 0 where the NLP's row would hold; None when every row is in the NLP
    deferred: object = None
    deferred_conditions: tuple[ConditionInfo, ...] = ()
    stack_starts: bool = True  # SceneModel.stack_starts
    screened_starts: bool = False  # SceneModel.screened_starts
    # scene numbers taken as parameters (formulation/parametric.py), after the backoff in p;
    # a generic Formulation (aux_init of (design, numbers), norms_of) until `bind`
    parameter_names: tuple[str, ...] = ()
    norms_of: object = None  # casadi Function numbers -> row normalisers, generic only
    scene_values: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @functools.cached_property
    def scenario(self) -> Scenario | None:
        """The conditions as explicit functions of every offset (built on first use)."""
        source = self.scenario_source
        return source() if callable(source) else source

    def deferred_broken(self, x, p) -> bool:
        """Whether x breaks a row this NLP leaves out."""
        if self.deferred is None:
            return False
        rows = np.asarray(self.deferred(x, p)[2], dtype=float).ravel()
        return bool(np.any(~(rows >= 0.0)))

    @property
    def n_design(self) -> int:
        return len(self.design_names)

    def parameters(self, requirements: dict[str, float] | None = None, *,
                   backoff: float = DEFAULT_BACKOFF) -> np.ndarray:
        """The parameter vector p: the required margins by key (the spec's by default), then
        the rows' backoff (see DEFAULT_BACKOFF)."""
        if requirements is None:
            required = self.p_default[: len(self.p_names)]
        else:
            required = [float(requirements.get(n, 0.0)) for n in self.p_names]
        return np.concatenate([np.asarray(required, dtype=float), [backoff], self.scene_values])

    def bind(self, spec) -> Formulation:
        """This generic NLP at one spec's scene numbers (formulation/parametric.py): the same
        solvers, its p, start values, normalisers, fixed values and stage maps at them."""
        from .parametric import values

        numbers = values(spec, self.parameter_names)
        xd = ca.SX.sym("design", self.n_design)
        required = [float(spec.requirements.get(n, 0.0)) for n in self.p_names]
        return replace(
            self, p_default=np.concatenate([required, [DEFAULT_BACKOFF], numbers]),
            aux_init=ca.Function("aux_init", [xd], [self.aux_init(xd, numbers)]),
            fixed=_fixed_values(spec), norms=np.asarray(self.norms_of(numbers)).ravel(),
            scenario_source=self.scenario_source.bind(numbers, spec), scene_values=numbers,
            norms_of=None)

    def requirement(self, info: ConditionInfo, p) -> float:
        """The required margin of one condition under parameters p (0 for non-margin kinds)."""
        if info.kind != MARGIN or info.equality:
            return 0.0
        values = dict(zip(self.p_names, np.asarray(p, dtype=float).ravel()))
        return max((values[k] for k in info.keys), default=0.0)

    def design_values(self, x) -> dict[str, float]:
        """Inverse map: the named design (free and fixed variables, and derived quantities)."""
        x = np.asarray(x, dtype=float).ravel()
        out = dict(self.fixed)
        out.update({n: float(v) for n, v in zip(self.design_names, x[: self.n_design])})
        derived = np.asarray(self.evaluate(x, self.p_default)[3]).ravel()
        for name, value in zip(self.derived_names, derived):
            out.setdefault(name, float(value))
        return out

    def start_vector(self, design: dict[str, float]) -> np.ndarray:
        """A full start vector from free design values: auxiliaries from `aux_init`."""
        xd = np.array([float(design[n]) for n in self.design_names])
        aux = np.asarray(self.aux_init(xd)).ravel() if self.aux_init is not None else np.zeros(0)
        x = np.concatenate([xd, aux])
        return np.clip(x, self.lbx, self.ubx)

    def defined_start(self, design: dict[str, float], anchor: dict[str, float],
                      p, halvings: int = 12, *, checked: bool = False) -> np.ndarray:
        """start_vector(design), moved toward `anchor` (the spec's guess) until every row is a
        number. A start where a closed form is undefined (beta below alpha: no handover, a
        square root of a negative speed) ends IPOPT at once with Invalid_Number_Detected, and
        one at the edge of where they are defined soon after; halfway from that edge to the
        guess is a start worth a run. Unchanged when the anchor is undefined too. checked: the
        design is known undefined and the anchor defined (not evaluated again)."""
        def defined(values):
            x = self.start_vector(values)
            return x, self.is_defined(x, p)

        if not checked:
            x, ok = defined(design)
            if ok or not defined(anchor)[1]:
                return x
        lo, hi = 0.0, 1.0  # fractions of the way from the anchor to the design: defined, not
        for _ in range(halvings):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if defined(_between(anchor, design, mid))[1] else (lo, mid)
        return self.start_vector(_between(anchor, design, lo / 2))

    def defined_anchor(self, anchor: dict[str, float], candidates, p) -> dict[str, float]:
        """`anchor` where every row is a number there, else the first of `candidates` (a
        callable giving designs, drawn only then) where they are: the spec's guess may lie
        where a closed form is undefined (beta below a fixed alpha), and starts moved toward
        it stay there. The anchor itself when no candidate is defined either."""
        def defined(values):
            return self.is_defined(self.start_vector(values), p)

        if defined(anchor):
            return anchor
        return next((d for d in candidates() if defined(d)), anchor)

    def is_defined(self, x, p) -> bool:
        """Whether every row and objective term is a number at the start vector x."""
        rows, _, terms, _ = self.evaluate(x, p)
        return bool(np.isfinite(np.asarray(rows)).all() and np.isfinite(np.asarray(terms)).all())

    def defined_starts(self, designs: list[dict[str, float]], anchor: dict[str, float],
                       p) -> list[np.ndarray]:
        """defined_start of each design; those already defined are found in one evaluation
        of all of them (one call per start was 4 % of an 8-start optimize)."""
        xd = np.array([[float(d[n]) for n in self.design_names] for d in designs]).T
        aux = (np.asarray(self.aux_init.map(len(designs))(xd)) if self.aux_init is not None
               else np.zeros((0, len(designs))))
        xs = np.clip(np.vstack([xd, aux]), self.lbx[:, None], self.ubx[:, None])
        rows, _, terms, _ = self.evaluate.map(len(designs))(xs, p)
        finite = (np.isfinite(np.asarray(rows)).all(axis=0)
                  & np.isfinite(np.asarray(terms)).all(axis=0))
        # none moves where all are defined, or toward an anchor that is not (defined_start)
        if finite.all() or not self.is_defined(self.start_vector(anchor), p):
            return [xs[:, k].copy() for k in range(len(designs))]
        return [xs[:, k].copy() if finite[k] else self.defined_start(d, anchor, p, checked=True)
                for k, d in enumerate(designs)]


def _between(a: dict[str, float], b: dict[str, float], t: float) -> dict[str, float]:
    return {n: a[n] + t * (b[n] - a[n]) for n in a}


def design_inputs(spec, names: tuple[str, ...], defaults: dict[str, float]):
    """SX symbols for the free design variables, floats for the fixed ones.

    Returns (values: name -> SX or float, symbols: name -> SX, bounds: name -> (lo, hi, guess)).
    `defaults` gives the value of a variable the spec leaves out (None: derived by the scene).
    """
    values, symbols, bounds = {}, {}, {}
    for name in names:
        entry = spec.design.get(name, defaults.get(name))
        if isinstance(entry, Bounds):
            sym = ca.SX.sym(name)
            values[name] = symbols[name] = sym
            bounds[name] = (entry.min, entry.max, entry.guess)
        else:
            # a number, or a parameter's symbol (formulation/parametric.py)
            values[name] = (None if entry is None else entry if isinstance(entry, ca.SX)
                            else float(entry))
    return values, symbols, bounds


def assemble(spec, model: SceneModel, *, key: str, bounds: dict,
             defer: bool = True, parameters=None) -> Formulation:
    """The NLP of a scene model, with requirements as parameters; defer: leave the deferred
    conditions out of it (Formulation.deferred evaluates them). parameters: (names, SX
    symbols) of the scene numbers the model was built on as symbols (formulation/parametric.py):
    they follow the requirements and the backoff in p, and the Formulation is generic until
    bound to a spec's numbers (Formulation.bind)."""
    design_names = tuple(model.design_symbols)
    aux_names = tuple(a[0] for a in model.aux)
    x = ca.vertcat(*model.design_symbols.values(), *(a[1] for a in model.aux))
    lbx = [bounds[n][0] for n in design_names] + [a[2] for a in model.aux]
    ubx = [bounds[n][1] for n in design_names] + [a[3] for a in model.aux]

    p_names = tuple(sorted({k for c in model.conditions if c.kind == MARGIN for k in c.keys}))
    scene_names, scene = parameters if parameters is not None else ((), ca.SX(0, 1))
    p = ca.SX.sym("required", len(p_names) + 1)  # the last: the rows' backoff
    if parameters is not None:
        p = ca.vertcat(p, scene)
    p_of = {n: p[i] for i, n in enumerate(p_names)}
    backoff = p[len(p_names)]
    norms_of = _row_norms(model, x, bounds, design_names, scene, parameters is not None)
    norms = norms_of(np.zeros(0)) if parameters is None else norms_of(scene)
    norms = [norms[i] for i in range(len(model.conditions))]

    rows, lbg, ubg, infos, later = _rows(model, norms, p_of, backoff, defer)
    conditions = [c for c in model.conditions if not (c.deferred and defer)]
    kept = [n for c, n in zip(model.conditions, norms) if not (c.deferred and defer)]
    if parameters is not None:  # a generic NLP's normalisers: Formulation.bind
        norms_of = ca.Function("norms", [scene], [ca.vertcat(*kept)])
    norms = np.array(kept) if parameters is None else np.zeros(0)
    deferred = None
    if later:
        deferred = ca.Function("deferred", [x, p], [ca.vertcat(*[c.slack for c, _, _ in later]),
                                                    ca.vertcat(*[c.scale for c, _, _ in later]),
                                                    ca.vertcat(*[r for _, _, r in later])])
    deferred_infos = tuple(ConditionInfo(i, c.name, c.keys, c.where, c.kind, c.equality)
                           for i, (c, _, _) in enumerate(later))

    weights, f = _objective(spec, model)
    # an objective the scene does not give (Scene.objectives) is never asked for: 0 there
    terms = ca.vertcat(*[model.objective_terms.get(n, ca.SX(0.0)) for n in OBJECTIVE_SENSE])
    derived_names = tuple(model.derived)
    evaluate = ca.Function(
        "evaluate", [x, p],
        [ca.vertcat(*[c.slack for c in conditions]),
         ca.vertcat(*[c.scale for c in conditions]), terms,
         ca.vertcat(*model.derived.values()) if model.derived else ca.SX(0, 1)],
    )
    x_names = design_names + aux_names
    n_d = len(design_names)
    tol_index = aux_names.index("tolerance") + n_d if "tolerance" in aux_names else None
    m_index = aux_names.index("min_margin") + n_d if "min_margin" in aux_names else None
    p_default = np.array([float(spec.requirements.get(n, 0.0)) for n in p_names]
                         + [DEFAULT_BACKOFF] + [0.0] * len(scene_names))
    fixed = _fixed_values(spec)
    return Formulation(
        kind=model.kind, key=key,
        # Rows repeat subexpressions built separately (cos beta, the fall speeds...): merging
        # them cuts the derivatives CasADi generates by a third and a solve by 5-8 %
        # (results/bench_ipopt_cost.md).
        nlp={"x": x, "p": p, "f": ca.cse(f), "g": ca.cse(ca.vertcat(*rows))},
        x_names=x_names, design_names=design_names,
        lbx=np.array(lbx, dtype=float), ubx=np.array(ubx, dtype=float),
        lbg=np.array(lbg), ubg=np.array(ubg),
        p_names=p_names, p_default=p_default, conditions=tuple(infos),
        objective_names=tuple(OBJECTIVE_SENSE), weights=weights, evaluate=evaluate,
        aux_init=model.aux_init, tolerance_axes=model.tolerance_axes,
        tolerance_index=tol_index, margin_index=m_index, fixed=fixed,
        derived_names=derived_names, norms=norms, scenario_source=model.scenario,
        deferred=deferred, deferred_conditions=deferred_infos, stack_starts=model.stack_starts,
        screened_starts=model.screened_starts,
        parameter_names=scene_names, norms_of=norms_of if parameters is not None else None,
    )


def _rows(model, norms, p_of, backoff, defer: bool):
    """(rows, lbg, ubg, infos, later) of the NLP: each condition less its requirement (and the
    margin epigraph), normalised, less the backoff; `later` the deferred ones (condition,
    normaliser, row) when defer."""
    t = model.margin_symbol if model.margin_symbol is not None else 0.0
    rows, lbg, ubg, infos = [], [], [], []
    later = []  # (condition, normaliser, row) of the deferred conditions
    for i, c in enumerate(model.conditions):
        if c.kind == MARGIN and not c.equality:
            need = fmax_all([p_of[k] for k in c.keys])
            expr = c.slack - (need + (t if c.epigraph else 0.0)) * c.scale
        else:
            expr = c.slack
        # in the normalised row's units, those IPOPT's tolerances are measured in
        if c.equality:
            rows.append(expr / norms[i])
        elif c.kind != MODEL:
            rows.append(expr / norms[i] - backoff)
        else:
            unit = 0.0 if c.backoff_unit is None else ca.fabs(c.backoff_unit)
            rows.append((expr - backoff * unit) / norms[i])
        if c.deferred and defer:
            later.append((c, norms[i], rows.pop()))
            continue
        lbg.append(0.0)
        ubg.append(0.0 if c.equality else math.inf)
        infos.append(ConditionInfo(len(infos), c.name, c.keys, c.where, c.kind, c.equality,
                                   c.quantities))
    return rows, lbg, ubg, infos, later


def _objective(spec, model):
    """(the objective's weights, the NLP's objective: minus the weighted terms, over the
    objective's scale)."""
    weights = {k: float(v) for k, v in spec.objective.items() if float(v) != 0.0}
    f = 0.0
    for name, w in weights.items():
        f = f - w * OBJECTIVE_SENSE[name] * model.objective_terms[name]
    if model.extra_objective is not None:
        f = f - model.extra_objective
    if model.objective_scale != 1.0:
        f = f / model.objective_scale
    return weights, f


def _row_norms(model, x, bounds, design_names, scene, symbolic: bool):
    """Row normalisers: |scale| of each condition at the spec's guess, 1 where that is not a
    number above 1e-9. A Function of the scene parameters when the model has them (symbolic),
    else a function that returns the constants."""
    guess = [bounds[n][2] for n in design_names]
    inputs = [x, scene] if symbolic else [x]
    scale_fn = ca.Function("s", inputs, [ca.vertcat(*[c.scale for c in model.conditions])])
    if not symbolic:
        aux = np.asarray(model.aux_init(guess)).ravel() if model.aux else []
        norms = np.abs(np.asarray(scale_fn(np.concatenate([guess, aux]))).ravel())
        norms = np.where(np.isfinite(norms) & (norms > 1e-9), norms, 1.0)
        return lambda _: norms
    aux = model.aux_init(ca.DM(guess), scene) if model.aux else ca.SX(0, 1)
    norms = ca.fabs(scale_fn(ca.vertcat(ca.DM(guess), aux), scene))
    norms = ca.if_else((norms > 1e-9) * (norms < math.inf), norms, 1.0)
    return ca.Function("norms", [scene], [norms])


def fmax_all(values):
    """The largest of CasADi expressions (0 for none)."""
    if not values:
        return 0.0
    out = values[0]
    for v in values[1:]:
        out = ca.fmax(out, v)
    return out


def fmin_all(values):
    """The smallest of CasADi expressions (at least one)."""
    out = values[0]
    for v in values[1:]:
        out = ca.fmin(out, v)
    return out


def _fixed_values(spec) -> dict[str, float]:
    """The spec's fixed design numbers (a parameter's symbol is not one: Formulation.bind)."""
    return {k: float(v) for k, v in spec.design.items()
            if not isinstance(v, (Bounds, ca.SX))}


# Requirements that add rows when above 0 (a scene's exact rows, which its formulation adds
# where they are asked for: Scene.nlp_key).
def spec_key(spec) -> str:
    """A canonical text of everything in a spec that the NLP depends on (the build cache key):
    the requirements' values are parameters, but some add rows when above 0."""
    design = sorted((k, repr(v)) for k, v in spec.design.items())
    objective = sorted((k, float(v)) for k, v in spec.objective.items())
    from ..plugin import of

    shaped = of(spec).nlp_key(spec)  # requirements that add rows, accuracy the rows follow
    tolerances = getattr(spec, "tolerances", ())
    allocated = tuple(tolerances) if any(t.allocate for t in tolerances) else ()  # allocation.py
    from .yield_target import active  # tolerances sized for a yield target

    stated = repr(tolerances) if spec.objective.get("max_yield") or active(spec) \
        else None  # statistical.py
    return repr((spec.kind, repr(spec.scene), design, objective, spec.verification.stages,
                 shaped, stated) + ((allocated,) if allocated else ()))


# objective terms measured in metres (the others are pure numbers)
LENGTH_TERMS = ("max_offset_tolerance", "min_drop")


def objective_scale(weights, length):
    """The size of the objective sum w * term: its weights' mean of the terms' sizes (`length`,
    the scene's size - the largest rise the box allows, the longest link - for a length; 1 for a
    ratio). The NLP divides its objective by it, so IPOPT's absolute tolerances are relative
    ones at any size of the scene."""
    sizes = {name: (length if name in LENGTH_TERMS else 1.0, abs(float(w)))
             for name, w in weights.items() if float(w) != 0.0}
    total = sum(w for _, w in sizes.values())
    return sum(size * w for size, w in sizes.values()) / total if total > 0 else 1.0
