"""The stairs scene behind the scene interface (pdm_design.plugin.Scene)."""

from __future__ import annotations

from ...plugin import Scene
from ...plugin_tolerances import BoxAxes

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
    def formulate(self, spec, parameters=None):
        import functools

        from .formulation import build
        from .formulation.errors import scenario

        model, bounds, closed_forms = build(spec)
        # the explicit-offset scenario grows with the row: built when first asked for
        return model, bounds, closed_forms, functools.partial(scenario, spec, model,
                                                              closed_forms)

    def nlp_key(self, spec):
        """Whether a nose_clearance requirement adds its rows."""
        from .formulation import requires_rows

        return (requires_rows(spec),)

    # ------------------------------------------------------------------ tolerances, yield, verification
    allocatable = ("rise", "tread", "launch_x", "restitution", "friction", "launch_speed")
    sizes_for_yield_target = True
    box_axes = BoxAxes((("rise", "rise"), ("tread", "tread")))

    def length_scale(self, spec, design):
        """Its tread (the drop height while the tread is not known)."""
        return float(design.get("tread") or spec.scene.initial.drop_height)

    def simulate_build(self, scene, design, deviations, stages, *, accuracy="default",
                       record_trajectory=False):
        from .tolerances import simulate_build

        # one build's values: K for each step, a number for a lot
        return simulate_build(scene, design, {q: d[0] for q, d in deviations.items()}, stages,
                              accuracy=accuracy, record_trajectory=record_trajectory)

    def run_builds(self, scene, design, deviations, stages):
        from .tolerances import run_builds

        return run_builds(scene, design, deviations, stages)

    def linearised_yield(self, scene, design, tolerances, stages):
        from .formulation.statistical import linearised_yield

        return linearised_yield(scene, design, tolerances, stages)

    def linearised_rows(self, scene, design, tolerances, stages):
        from .formulation.statistical import placed_rows

        return placed_rows(scene, design, tolerances, stages)

    def simulate_box_build(self, spec, design, errors, deviations, accuracy):
        from .verification import simulate_box_build

        return simulate_box_build(self, spec, design, errors, deviations, accuracy)

    def closed_form_agreement(self, spec, analysis, result):
        from .verification import closed_form_agreement

        return closed_form_agreement(spec, analysis, result)

    def condition_words(self):
        from .words import CONDITIONS, PHASE_HINTS

        return {name: (what, advice, PHASE_HINTS.get(name, ()))
                for name, (what, advice) in CONDITIONS.items()}

    def tolerance_refusal(self, spec, quantity):
        from .refusals import tolerance_refusal

        return tolerance_refusal(spec, quantity)

    # ------------------------------------------------------------------ sheets, drawings, reports

    # ------------------------------------------------------------------ command line, tables, API
