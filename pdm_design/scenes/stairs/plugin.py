"""The stairs scene behind the scene interface (pdm_design.plugin.Scene)."""

from __future__ import annotations

from ...plugin import Scene, StageErrors

# A stairs NLP has rows for every bounce, and IPOPT needs ever more iterations for them (23 at
# 100 bounces, 327 at 300, one start), so a design with free variables is optimised over at
# most 200.
MAX_OPTIMISED_BOUNCES = 200
MARGINS = ("first_impact_friction", "nose_clearance", "first_nose_clearance", "riser_clearance")


class Stairs(Scene):
    kind = "stairs"
    title = "a ball bouncing down a flight of stairs"
    stage_noun = ("step", "steps")
    margins = MARGINS
    verification_hints = {"offsets": "offsets are for manipulators scenes; stairs take "
                                     "step_errors"}

    # ------------------------------------------------------------------ the spec
    def scene_class(self):
        from .model import StairsScene

        return StairsScene

    def design_class(self):
        from .model import StairsDesign

        return StairsDesign

    def stage_limit(self, free):
        if free:
            return MAX_OPTIMISED_BOUNCES, (
                "when the design has free variables (the NLP has rows for every bounce; a "
                "fixed design may be simulated for up to 10 000 000)")
        return super().stage_limit(free)

    def quantities(self):
        from .quantities import QUANTITIES

        return QUANTITIES

    def max_yield_refusal(self, scene):
        return None

    def template(self):
        from .template import stairs_template

        return stairs_template()

    # ------------------------------------------------------------------ closed forms
    def analyse(self, scene, design, stages=None):
        from .analysis import analyse_stairs

        return analyse_stairs(scene, design, stages)

    # ------------------------------------------------------------------ the simulator
    def simulate(self, spec, design, *, stages, accuracy, errors=None, record_trajectory=False):
        from .sim import simulate_stairs

        errors = spec.verification.step_errors if errors is None else errors
        return simulate_stairs(spec.scene, design, stages=stages, accuracy=accuracy,
                               step_errors=errors, record_trajectory=record_trajectory)

    # ------------------------------------------------------------------ the NLP
    objectives = ("max_offset_tolerance", "max_min_margin", "min_drop", "fastest_convergence",
                  "max_yield")
    def formulate(self, spec, parameters=None):
        import functools

        from .formulation import build
        from .formulation.errors import scenario

        model, bounds, closed_forms = build(spec)
        # the explicit-offset scenario grows with the row: built when first asked for
        return model, bounds, functools.partial(scenario, spec, model, closed_forms)

    # ------------------------------------------------------------------ tolerances, yield, verification

    # ------------------------------------------------------------------ sheets, drawings, reports

    # ------------------------------------------------------------------ command line, tables, API
    table_geometry = ("nose_clearance",)
    table_periodic = ("impact_speed", "vertical_impact_speed", "horizontal_speed",
                      "spin", "flight_time", "drift_per_bounce")
    tolerance_axes = ("rise", "tread")
    stage_errors = StageErrors("--step-error", "K:DRISE,DTREAD", "step_errors", "step",
                               lambda k, a, b: _step_error(step=k, rise=a, tread=b))


def _step_error(**fields):
    from ...spec.model import StepError

    return StepError(**fields)
