"""The compass gait behind the scene interface (pdm_design.plugin.Scene). Heavy modules (numpy,
scipy, casadi) are imported only when a method is called."""

from __future__ import annotations

from ...plugin import Scene

MARGINS = ("stance_contact", "no_slip", "stability", "hip_limit")


class CompassGait(Scene):
    kind = "compass_gait"
    title = "a compass-gait walker on a ramp or stairs"
    stage_noun = ("step", "steps")
    margins = MARGINS
    requirement_keys = (*MARGINS, "max_spectral_radius")
    verification_hints = {"offsets": "offsets are for manipulators scenes; a compass gait "
                                     "takes step_errors"}

    # ------------------------------------------------------------------ the spec
    def scene_class(self):
        from .scene import CompassGaitScene

        return CompassGaitScene

    def design_class(self):
        from .scene import CompassGaitDesign

        return CompassGaitDesign

    def template(self):
        from .template import compass_gait_template

        return compass_gait_template()

    # ------------------------------------------------------------------ closed forms
    def analyse(self, scene, design, stages=None, requirements=None):
        from .analysis import analyse_compass_gait

        bound = (requirements or {}).get("max_spectral_radius", 1.0)
        return analyse_compass_gait(scene, design, stages, max_spectral_radius=bound)

    # ------------------------------------------------------------------ the simulator
    def simulate(self, spec, design, *, stages, accuracy, errors=None, record_trajectory=False):
        from .simulate import simulate_compass_gait

        errors = spec.verification.step_errors if errors is None else errors
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

    # ------------------------------------------------------------------ tolerances, yield, verification

    # ------------------------------------------------------------------ sheets, drawings, reports

    # ------------------------------------------------------------------ command line, tables, API
    tolerance_axes = ("slope",)
    table_periodic = ("step_length", "step_period", "spectral_radius")
