"""The Python API. The CLI is a thin layer over these functions."""

from __future__ import annotations

from dataclasses import dataclass, field

from .accuracy import Accuracy, AccuracySetting
from .accuracy import accuracy as resolve_accuracy
from .analysis import Analysis, analyse
from .spec.model import Spec
from .status import Status


@dataclass(frozen=True)
class DesignOutcome:
    """The answer to `pdm-design optimize`: the design, what the closed forms say about it, and
    (when run) the solver's statistics and the simulator's verification, at `accuracy`."""

    spec: Spec
    status: Status
    analysis: Analysis
    violations: tuple[str, ...] = ()
    objective: dict | None = None
    tolerance: dict | None = None
    # allocated and given tolerances ([tolerances] with allocate = true): {quantity,
    # applies_to, value (SI), unit, allocated, limited_by}; None otherwise
    tolerances: tuple[dict, ...] | None = None
    # the Monte Carlo check of tolerances sized for a yield target (solve/yield_check.py):
    # {target, linearised, estimate, ci_low, ci_high, builds, ...}; None otherwise
    tolerances_yield: dict | None = None
    tolerances_yield_words: str = ""
    verification: dict | None = None
    solver: dict | None = None
    accuracy: Accuracy | None = None
    # the optimizer's distinct local optima (solve.optimize.optima): a table's next point
    # continues from them
    optima: tuple = field(default=(), repr=False, compare=False)

    @property
    def status_message(self) -> str:
        """The status in words; a fixed design has no bounds to widen."""
        if self.tolerances_yield_words:
            return self.tolerances_yield_words
        if self.status is Status.INFEASIBLE and not self.spec.free_variables:
            return ("The fixed design does not meet every requirement: relax the requirements "
                    "listed as violated, or change the design or the scene.")
        if self.status is Status.INFEASIBLE:
            from .plugin import of

            words = of(self.spec).infeasible_words(self.spec, self.analysis.design)
            if words:
                return words
        return self.status.message

    @property
    def at_bounds(self) -> dict[str, str]:
        """The free design variables at a bound of theirs ("min" or "max"), by name: within
        spec.model.AT_BOUND of their range (docs/json-schema.md)."""
        values = self.analysis.design
        return {name: side for name in self.spec.free_variables
                if values.get(name) is not None
                and (side := self.spec.design[name].side(values[name]))}

    @property
    def exit_code(self) -> int:
        verified = self.verification is None or self.verification.get("passed", False)
        return 0 if self.status.is_success and verified else 1


def evaluate(spec: Spec, *, verify: bool = True,
             accuracy: AccuracySetting | None = None) -> DesignOutcome:
    """Evaluate a spec whose design is fully fixed: closed forms, then (unless verify=False)
    the event simulator from the spec's initial state."""
    if spec.free_variables:
        raise ValueError("evaluate() needs a fixed design; use design() for free variables")
    accuracy = resolve_accuracy(accuracy or spec.verification.accuracy)
    point = spec.design_at()
    analysis = analyse(spec.scene, point, spec.verification.stages)
    from .plugin import of

    violations = (tuple(analysis.problems) + tuple(analysis.violations(spec.requirements))
                  + tuple(of(spec).bound_violations(spec, analysis)))
    status = Status.EVALUATED if not violations else Status.INFEASIBLE
    verification = None
    if verify and not analysis.problems:
        from .verify import verify_nominal

        verification = verify_nominal(spec, point, analysis, accuracy=accuracy)
    return DesignOutcome(spec=spec, status=status, analysis=analysis, violations=violations,
                         verification=verification, accuracy=accuracy)


def design(spec: Spec, *, verify: bool = True, accuracy: AccuracySetting | None = None,
           linearise: bool = False, start_from: dict | None = None,
           continued: tuple = ()) -> DesignOutcome:
    """Solve the spec: evaluate a fixed design, or optimise the free variables; verify. A spec
    with a discrete design variable (Scene.variants: a count of parts) is solved
    at each of its values, and the best answer kept (the highest objective among the
    successes; the first variant's outcome when none succeeds)."""
    from .plugin import of

    variants = of(spec).variants(spec)
    if len(variants) > 1:
        outcomes = [design(v, verify=verify, accuracy=accuracy, linearise=linearise)
                    for v in variants]
        return max(outcomes, key=_rank)
    spec = variants[0]
    if spec.free_variables and set(spec.objective) & set(of(spec).search_objectives):
        return _searched(spec, verify=verify, accuracy=accuracy)
    if not spec.free_variables:
        return evaluate(spec, verify=verify, accuracy=accuracy)
    return optimize(spec, verify=verify, accuracy=accuracy, linearise=linearise,
                    start_from=start_from, continued=continued)


def _searched(spec: Spec, *, verify: bool, accuracy) -> DesignOutcome:
    """The design a scene's own search chooses for an objective no NLP states
    (Scene.search_objectives: a rough ramp's mean steps before failure), evaluated and
    verified as a fixed design."""
    import dataclasses
    import time

    from .plugin import of

    start = time.perf_counter()
    values, value = of(spec).search(spec)
    fixed = dataclasses.replace(spec, design={**spec.design, **values})
    found = evaluate(fixed, verify=verify, accuracy=accuracy)
    status = Status.OPTIMAL if found.status is Status.EVALUATED else found.status
    name = next(n for n in spec.objective if n in of(spec).search_objectives)
    return dataclasses.replace(
        found, spec=spec, status=status,
        objective={"weights": dict(spec.objective), "value": value, "terms": {name: value},
                   "method": f"the scene's own search (Scene.search), "
                             f"{time.perf_counter() - start:.3g} s"})


def _rank(outcome: DesignOutcome) -> tuple:
    """Order of the answers of a spec's variants: successes first, then the higher objective
    (a fixed variant's: its smallest margin)."""
    value = (outcome.objective or {}).get("value")
    if value is None:
        value = min(outcome.analysis.margins.values(), default=0.0)
    return (outcome.status.is_success and outcome.exit_code == 0, float(value))


# What each accuracy preset asks of the optimizer and of the verification depth: IPOPT's
# tolerance, the number of starts, and the multiple of the spec's random verification samples.
# A custom accuracy takes its base preset's.
SOLVE_PRESETS = {
    "fast": {"tol": 1e-5, "starts": 4, "sample_factor": 0.25, "bound_relax_factor": 1e-8},
    "default": {"tol": 1e-8, "starts": 8, "sample_factor": 1.0, "bound_relax_factor": 1e-8},
    "precise": {"tol": 1e-11, "starts": 16, "sample_factor": 4.0, "bound_relax_factor": 0.0},
}


def optimize(spec: Spec, *, verify: bool = True, accuracy: AccuracySetting | None = None,
             linearise: bool = False, start_from: dict | None = None,
             continued: tuple = ()) -> DesignOutcome:
    """Choose the free design variables with IPOPT (multistart), then verify the answer and
    its claimed tolerance box in the simulator. accuracy (default: the spec's) sets the
    simulator's tolerances and, through its base preset, IPOPT's tolerance, the starts and how
    many random builds are run. linearise: also the cvxpy sets of a robust answer (docs/
    optimizer.md section 8; not computed unless asked). start_from: a design to start from
    besides the others (a table's neighbour); the answer is the same design without it
    (solve/tiebreak.py). continued: a neighbour's local optima (`DesignOutcome.optima`) to
    solve from instead of the starts (solve.optimize)."""
    from .plugin import of
    from .solve import optimize as solve
    from .solve.words import bounds_hint, summarise

    accuracy = resolve_accuracy(accuracy or spec.verification.accuracy)
    preset = SOLVE_PRESETS[accuracy.base]
    result = solve(spec, starts=preset["starts"], tol=preset["tol"],
                   bound_relax_factor=preset["bound_relax_factor"], linearise=linearise,
                   start_from=start_from, continued=continued)
    # IPOPT honours bounds only to its tolerance (e.g. -1e-8 for a bound at 0): clip to them.
    point = spec.design_at({name: min(max(result.design[name], spec.design[name].min),
                                      spec.design[name].max)
                            for name in spec.free_variables})
    analysis = analyse(spec.scene, point, spec.verification.stages)
    advice = bounds_hint(result.at_bounds)
    violations = (tuple(analysis.problems) + tuple(summarise(result.violations))
                  + ((advice,) if advice else ()))
    if result.status is Status.INFEASIBLE and (
            cause := of(spec).infeasible_cause(spec, analysis.design)):
        violations = (cause, *violations)
    reach = ""
    if result.status is Status.INFEASIBLE and _sized_for_yield(spec):
        from .solve.yield_allocation import out_of_reach_words

        reach = out_of_reach_words(spec, point)
        violations = (reach, *violations) if reach else violations
    verification = None
    if verify and result.status.is_success:
        samples = round(spec.verification.samples * preset["sample_factor"])
        verification = _verify_with_box(spec, point, analysis, result.tolerance, accuracy,
                                        samples, result.tolerances)
    solver = result.stats.to_json() | {"status": result.status.value, "message": result.message}
    objective = {"weights": dict(spec.objective), "value": result.objective,
                 "terms": _terms(spec, result.objectives, analysis.margins, result.tolerance)}
    tolerance = None
    if result.tolerance is not None:
        tolerance = dict(result.tolerance)
        if result.linearised is not None:
            tolerance["linearised"] = result.linearised.to_json()
        if result.solution is not None:
            from .solve.binding import limited_by

            tolerance["limited_by"] = limited_by(spec, result.solution)
    tolerances, status, checked = None, result.status, None
    if result.tolerances is not None and result.solution is not None:
        from .solve.binding import limits_of_quantities

        entries = result.tolerances
        if status.is_success and _sized_for_yield(spec):  # the Monte Carlo is the judge
            from .solve.yield_check import check_answer, entries_checked

            checked = check_answer(spec, point, entries, accuracy)
            entries = entries_checked(entries, checked)
            if not checked.met:
                status, violations = Status.INFEASIBLE, violations + (checked.words,)
        tolerances = tuple(limits_of_quantities(spec, result.solution, entries))
    return DesignOutcome(spec=spec, status=status, analysis=analysis,
                         violations=violations, objective=objective, tolerance=tolerance,
                         tolerances=tolerances, verification=verification, solver=solver,
                         accuracy=accuracy, optima=result.optima,
                         tolerances_yield=checked.record if checked else None,
                         tolerances_yield_words=checked.words if checked else reach)


def _sized_for_yield(spec: Spec) -> bool:
    """Whether optimize sizes the spec's allocated tolerances for a yield target."""
    from .formulation.yield_target import active

    return active(spec)


def _terms(spec: Spec, nlp_terms: dict, margins: dict, tolerance: dict | None) -> dict:
    """Every objective's value at the design: the NLP's for the closed forms of the design
    (min_drop, fastest_convergence) and for the box it found (max_offset_tolerance, None unless
    asked and found: finding a design's box is an optimisation of its own); max_min_margin from
    the analysis' margins (formulation.build.min_margin_term), weighted or not."""
    from .formulation.build import min_margin_term

    terms = dict(nlp_terms)
    if tolerance is None:
        terms["max_offset_tolerance"] = None
    terms["max_min_margin"] = min_margin_term(spec.kind, margins, spec.requirements)
    if not spec.objective.get("max_yield"):  # a yield needs its tolerances and the question
        terms["max_yield"] = None
    return terms


def _verify_with_box(spec, point, analysis, tolerance, accuracy, samples,
                     tolerances=None) -> dict:
    """Nominal run plus, when a tolerance is claimed, its corners and random samples."""
    from .verify import verify_nominal

    nominal = verify_nominal(spec, point, analysis, accuracy=accuracy)
    if not tolerance:
        return nominal
    from .verify.tolerance import verify_tolerance

    box = verify_tolerance(spec, point, tolerance, samples=samples, accuracy=accuracy,
                           lots=tolerances)
    failures = nominal["failures"] + [
        f"tolerance refuted: {f['build']} fails ({f['failure']})" for f in box["failures"]]
    summary = nominal["summary"] if nominal["passed"] else "; ".join(nominal["failures"])
    from .units import counted

    summary += (f"; tolerance box confirmed by {counted(box['samples'], 'simulated build')}"
                if box["passed"] else f"; {len(box['failures'])} of "
                f"{counted(box['samples'], 'build')} "
                "inside the claimed tolerance box fail")
    return nominal | {"passed": not failures, "summary": summary, "failures": failures,
                      "samples": 1 + box["samples"], "tolerance_failures": box["failures"]}
