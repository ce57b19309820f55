"""The stairs scene behind the scene interface (pdm_design.plugin.Scene)."""

from __future__ import annotations

from ...plugin import Scene, StageErrors, StageList, lazily
from ...plugin_tolerances import BoxAxes
from ..common import StepError, first_stream_keys

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
    # a nose_clearance requirement holds the launch over the top landing too
    covered_by = {"first_nose_clearance": ("nose_clearance",)}
    verification_hints = {"offsets": "offsets are for manipulators scenes; stairs take "
                                     "step_errors",
                          "allow_skips": "allow_skips is for manipulators scenes (a palm flown "
                                         "over)"}

    def stage_lists(self):
        return {"step_errors": StageList(StepError, "step")}

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

    stream_keys = first_stream_keys("friction", "rise", "tread", "restitution", "launch_speed",
                                    "launch_x")

    def max_yield_refusal(self, scene):
        return None

    template = lazily(".template:stairs_template")

    # ------------------------------------------------------------------ closed forms
    analyse = lazily(".analysis:analyse_stairs")

    # ------------------------------------------------------------------ the simulator
    def simulate(self, spec, design, *, stages, accuracy, errors=None, record_trajectory=False):
        from .sim import simulate_stairs

        errors = spec.verification.stage_list("step_errors") if errors is None else errors
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

    def nlp_key(self, spec):
        """Whether a nose_clearance requirement adds its rows."""
        from .formulation import requires_rows

        return (requires_rows(spec),)

    # ------------------------------------------------------ tolerances, yield, verification
    allocatable = ("rise", "tread", "launch_x", "restitution", "friction", "launch_speed")
    sizes_for_yield_target = True
    box_axes = BoxAxes((("rise", "rise"), ("tread", "tread")))

    def length_scale(self, spec, design):
        """Its tread (the drop height while the tread is not known)."""
        return float(design.get("tread") or spec.scene.initial.drop_height)

    def simulate_build(self, scene, design, deviations, stages, *, accuracy="default",
                       record_trajectory=False, allow_skips=False):
        from .tolerances import simulate_build

        # one build's values: K for each step, a number for a lot
        return simulate_build(scene, design, {q: d[0] for q, d in deviations.items()}, stages,
                              accuracy=accuracy, record_trajectory=record_trajectory)

    run_builds = lazily(".tolerances:run_builds")
    linearised_yield = lazily(".formulation.statistical:linearised_yield")
    linearised_rows = lazily(".formulation.statistical:placed_rows")

    def simulate_box_build(self, spec, design, errors, deviations, accuracy):
        from .verification import simulate_box_build

        return simulate_box_build(self, spec, design, errors, deviations, accuracy)

    closed_form_agreement = lazily(".verification:closed_form_agreement")

    def condition_words(self):
        from .words import CONDITIONS, PHASE_HINTS

        return {name: (what, advice, PHASE_HINTS.get(name, ()))
                for name, (what, advice) in CONDITIONS.items()}

    tolerance_refusal = lazily(".refusals:tolerance_refusal")
    place_nouns = ("flight", "landing")  # "flight 3, ...", "landing 4" (formulation/)

    # ------------------------------------------------------ sheets, drawings, reports
    tolerance_axes = ("rise", "tread")
    dxf_layers = {"STEPS": 7}  # scenes/stairs/dxf.py
    stage_columns = ("step", "impact_time", "landing_x", "impact_speed", "vx", "spin_after")
    quantity_parts = {"friction": "every tread's surface (the ball's grip)",
                      "launch_x": "the launcher (release place)", "rise": "every step",
                      "tread": "every step", "restitution": "every step's surface (the ball's "
                      "bounce)", "launch_speed": "the launcher (launch speed)"}
    quantity_units = {
        "restitution": "", "launch_speed": "m/s", "rise": "m", "tread": "m",
        "landing_offset": "m", "nose_clearance": "m", "impact_speed": "m/s",
        "vertical_impact_speed": "m/s", "horizontal_speed": "m/s", "spin": "rad/s",
        "flight_time": "s", "drift_per_bounce": "m",
    }

    @property
    def part_words(self):
        from .sheet import PART_WORDS

        return PART_WORDS

    sheet_rows = lazily(".sheet:sheet_rows")

    def sheet_words(self):
        from .sheet import WORDS

        return WORDS

    box_shift = lazily(".sheet:box_shift")
    parts = lazily(".sheet:parts")
    table_rows = lazily(".sheet:table_rows")

    draw_sheet = lazily(".drawing:draw_stairs")

    draw_dxf = lazily(".dxf:draw_dxf")

    def document_keys(self):
        from .model import StairsDesign

        return {"design": StairsDesign.VARIABLES,
                "geometry": ("rise", "tread", "landing_offset", "nose_clearance"),
                "periodic": ("impact_speed", "vertical_impact_speed", "horizontal_speed", "spin",
                             "flight_time", "drift_per_bounce"),
                "approach": ("first_vertical_impact_speed",)}

    def plot_run(self, spec, design, result, path, *, offsets=(), stages=None, title=""):
        from .sim.plot import plot_stairs_run

        plot_stairs_run(result, path, title=title)

    animation = lazily(".animation:animation")


    # ------------------------------------------------------ command line, tables, API
    infeasible_cause = lazily(".words:flat_floor")

    table_geometry = ("nose_clearance",)
    column_labels = {
        "rise": ("rise", "m"), "tread": ("tread", "m"), "impact_speed": ("impact speed", "m/s"),
        "landing_offset": ("landing offset", "m"), "nose_clearance": ("nose clearance", "m"),
        "flight_time": ("flight time", "s"), "launch_speed": ("launch speed", "m/s"),
        "horizontal_speed": ("horizontal speed", "m/s"),
        "vertical_impact_speed": ("vertical impact speed", "m/s"), "spin": ("spin", "rad/s"),
        "drift_per_bounce": ("drift per bounce", "m"),
        "tolerance.rise": ("tolerance rise", "m"), "tolerance.tread": ("tolerance tread", "m"),
    }
    table_periodic = ("impact_speed", "vertical_impact_speed", "horizontal_speed",
                      "spin", "flight_time", "drift_per_bounce")
    stage_errors = StageErrors("--step-error", "K:DRISE,DTREAD", "step_errors", "step",
                               lambda k, a, b: StepError(step=k, rise=a, tread=b))
