"""The compass gait behind the scene interface (pdm_design.plugin.Scene). Heavy modules (numpy,
scipy, casadi) are imported only when a method is called."""

from __future__ import annotations

from ...plugin import Scene, StageList, lazily
from ..common import SlopeError, first_stream_keys

MARGINS = ("stance_contact", "no_slip", "stability", "hip_limit")


def box_start(scene, design):
    """Where a build of the slope box starts: the design's period-1 gait just after a heel
    strike (the box holds the gait's rows against every step's slope error, the walker on its
    gait: docs/compass_gait.md, section 5); the scene's initial state where it has none."""
    from .gait import find_gait
    from .stepmap import GaitNotFound

    try:
        return tuple(find_gait(scene, design).state)
    except GaitNotFound:
        return scene.initial.state()


class CompassGait(Scene):
    kind = "compass_gait"
    title = "a compass-gait walker on a ramp or stairs"
    stage_noun = ("step", "steps")
    margins = MARGINS
    requirement_keys = (*MARGINS, "max_spectral_radius")
    verification_hints = {"allow_skips": "allow_skips is for manipulators scenes (a palm flown "
                                         "over)",
                          "offsets": "offsets are for manipulators scenes; a compass gait "
                                     "takes step_errors"}

    def stage_lists(self):
        return {"step_errors": StageList(SlopeError, "step")}

    # ------------------------------------------------------------------ the spec
    def scene_class(self):
        from .scene import CompassGaitScene

        return CompassGaitScene

    def design_class(self):
        from .scene import CompassGaitDesign

        return CompassGaitDesign

    template = lazily(".template:compass_gait_template")

    def bound_violations(self, spec, analysis):
        """The gait's spectral radius above the spec's max_spectral_radius."""
        bound = spec.requirements.get("max_spectral_radius")
        radius = analysis.periodic.get("spectral_radius")
        if bound is None or radius is None or radius <= bound:
            return []
        return [f"the gait's spectral radius {radius:.4g} is above the required "
                f"max_spectral_radius {bound:.4g}"]

    # ------------------------------------------------------------------ closed forms
    def analyse(self, scene, design, stages=None, requirements=None):
        from .analysis import analyse_compass_gait

        bound = (requirements or {}).get("max_spectral_radius", 1.0)
        return analyse_compass_gait(scene, design, stages, max_spectral_radius=bound)

    # ------------------------------------------------------------------ the simulator
    def simulate(self, spec, design, *, stages, accuracy, errors=None, record_trajectory=False):
        from .simulate import simulate_compass_gait

        errors = spec.verification.stage_list("step_errors") if errors is None else errors
        slopes = [0.0] * stages
        for item in errors:
            if 1 <= item.step <= stages:
                slopes[item.step - 1] = getattr(item, "slope", 0.0)
        return simulate_compass_gait(spec.scene, design, stages=stages, accuracy=accuracy,
                                     step_errors=slopes, record_trajectory=record_trajectory)

    # ------------------------------------------------------------------ the NLP
    objectives = ("max_min_margin", "min_spectral_radius", "max_slope_tolerance")
    objective_aliases = {"min_spectral_radius": "fastest_convergence",
                         "max_slope_tolerance": "max_offset_tolerance"}

    def formulate(self, spec, parameters=None):
        from .formulation import build

        model, bounds, _ = build(spec)
        return model, bounds, None

    # ------------------------------------------------------ tolerances, yield, verification
    def quantities(self):
        from .quantities import QUANTITIES

        return QUANTITIES

    stream_keys = first_stream_keys("rise")

    tolerance_refusal = lazily(".quantities:tolerance_refusal")
    run_builds = lazily(".builds:build_outcome")
    simulate_build = lazily(".builds:simulate_build")

    def yield_extras(self, scene, design, tolerances, stages):
        """The mean steps before a fall on rough ground by forward flux sampling (rough.mfpt),
        when every step's own ground varies (its slope, or its rise on stairs) and nothing else
        but the start state: a ground that is off once for a whole build (a lot) makes each
        build a walker of its own, whose mean steps this does not average."""
        from .quantities import START

        each = [t for t in tolerances if t.applies_to == "each"]
        if not each or any(t.applies_to != "each" and t.quantity not in START
                           for t in tolerances):
            return {}
        from .rough import mfpt

        found = mfpt(scene, design, tolerances, seed=tolerances.seed)
        return {"mfpt": {k: found[k] for k in ("estimate", "ci_low", "ci_high", "method")}}

    def box_axes_of(self, spec):
        """Every step's own slope (the NLP's max_slope_tolerance box)."""
        from ...plugin_tolerances import BoxAxes

        return BoxAxes((("slope", "slope"),))

    def simulate_box_build(self, spec, design, errors, deviations, accuracy):
        """One build of the box: every step's slope error (the first of each pair), walked from
        the design's periodic gait, the state the box is about (`box_start`)."""
        from .simulate import simulate_compass_gait

        return simulate_compass_gait(spec.scene, design, stages=spec.verification.stages,
                                     accuracy=accuracy, step_errors=[e[0] for e in errors],
                                     start=box_start(spec.scene, design))

    # ------------------------------------------------------ sheets, drawings, reports
    dxf_layers = {"GROUND": 7, "WALKER": 5}  # scenes/compass_gait/dxf.py
    stage_columns = ("step", "time", "step_period", "step_length", "foot_x", "foot_y",
                     "stance", "swing", "stance_rate", "swing_rate")
    quantity_units = {
        "slope": "rad", "leg_length": "m", "step_length": "m", "step_period": "s",
        "spectral_radius": "", "rise": "m", "tread": "m",
    }

    @property
    def part_words(self):
        from .sheet import PART_WORDS

        return PART_WORDS

    sheet_rows = lazily(".sheet:sheet_rows")

    def sheet_words(self):
        from .sheet import WORDS

        return WORDS

    def box_tolerances(self, sheet, why):
        from .sheet import box_tolerances

        return box_tolerances(self, sheet, why)

    parts = lazily(".sheet:parts")
    table_rows = lazily(".sheet:table_rows")

    draw_sheet = lazily(".drawing:draw_walker")

    draw_dxf = lazily(".dxf:draw_dxf")

    def document_keys(self):
        from .analysis import PERIODIC_KEYS
        from .scene import CompassGaitDesign

        return {"design": CompassGaitDesign.VARIABLES, "geometry": ("scuff_depth",),
                "periodic": PERIODIC_KEYS, "approach": ()}

    def plot_run(self, spec, design, result, path, *, offsets=(), stages=None, title=""):
        from .plot import plot_compass_gait_run

        plot_compass_gait_run(result, path, title=title)

    animation = lazily(".animation:animation")

    # ------------------------------------------------------ command line, tables, API
    def table_extras(self, spec, axes, *, plots):
        """A slope swept alone on a fixed walker: the gait continued along it, where a
        multiplier leaves the unit circle (bifurcations.json) and the classic figure of step
        length against slope (bifurcation.png)."""
        from .bifurcation import table_files

        return table_files(spec, axes, plots=plots)

    tolerance_axes = ("slope",)
    table_periodic = ("step_length", "step_period", "spectral_radius")
    column_labels = {"rise": ("rise", "m"), "tread": ("tread", "m")}
