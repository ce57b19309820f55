"""The manipulators scene behind the scene interface (pdm_design.plugin.Scene)."""

from __future__ import annotations

from ...plugin import Scene, StageErrors, StageList, lazily
from ...plugin_tolerances import BoxAxes
from ..common import first_stream_keys

# A manipulator run keeps every stage's record and event (about 15 kB a stage).
MAX_MANIPULATOR_STAGES = 100_000
# An optimised row is verified by the simulator at the nominal build and the tolerance box's
# corners, and its box re-checked through every stage: 12 s at 10 000 stages
# (results/bench_scale.md), so longer rows are evaluated as fixed designs only.
MAX_OPTIMISED_MANIPULATORS = 10_000
MARGINS = (
    "landing", "over_the_top", "lift_off", "slip_carry", "tip_carry", "slip_impact", "tip_impact",
    "first_over_the_top", "first_lift_off", "first_slip_impact", "first_tip_impact",
    "parked_palms",
)
# the geometry of the links and pivots as built (shown only where the row has them)
MECHANISM = ("link_mass", "link_inertia", "link_count", "pivot_friction_torque", "pivot_damping")


class Manipulators(Scene):
    kind = "manipulators"
    title = "an object passed along a row of passive parallelogram manipulators"
    stage_noun = ("manipulator", "manipulators")
    margins = MARGINS
    # one row measures each pair (formulation.SHARED_ROWS): either's requirement holds both
    covered_by = {"over_the_top": ("first_over_the_top",), "first_over_the_top": ("over_the_top",),
                  "lift_off": ("first_lift_off",), "first_lift_off": ("lift_off",)}
    outside_min_margin = ("parked_palms",)  # formulation.OUTSIDE_MIN_MARGIN
    verification_hints = {"step_errors": "step_errors are for stairs scenes; manipulators "
                                         "take offsets"}

    def stage_lists(self):
        from .model import ManipulatorOffset

        return {"offsets": StageList(ManipulatorOffset, "manipulator")}

    # ------------------------------------------------------------------ the spec
    def scene_class(self):
        from .model import ManipulatorsScene

        return ManipulatorsScene

    def design_class(self):
        from .model import ManipulatorsDesign

        return ManipulatorsDesign

    def check_spec(self, scene, design):
        """No periodic handover in the design's bounds (handover.py), or a start below palm 1
        whatever the design (start.py)."""
        from .handover import no_handover
        from .start import unreachable_start

        return no_handover(design) or unreachable_start(scene.initial.position[1], design)

    def stage_limit(self, free):
        if free:
            return MAX_OPTIMISED_MANIPULATORS, (
                "when the design has free variables (the optimizer's verification simulates "
                "the row at every corner of the box; a fixed design may be run for up to "
                f"{MAX_MANIPULATOR_STAGES})")
        return MAX_MANIPULATOR_STAGES, "for a row of manipulators (the simulator keeps every " \
                                       "stage's record)"

    def quantities(self):
        from .quantities import QUANTITIES

        return QUANTITIES

    stream_keys = first_stream_keys("pivot_x", "pivot_y", "link_length", "back_stop", "palm_mass",
                                    "friction", "object_mass", "object_width", "feed_x",
                                    "feed_speed", "link_mass", "pivot_friction")

    def max_yield_refusal(self, scene):
        if scene.pivots.damping == 0.0:
            return None
        return ("undamped pivots (the linearised yield takes the closed-form carry, which "
                "damping has not; `pdm-design yield` judges a design on damped pivots)",
                "scene.pivots.damping")

    template = lazily(".template:manipulators_template")

    # ------------------------------------------------------------------ closed forms
    analyse = lazily(".analysis:analyse_manipulators")

    # ------------------------------------------------------------------ the simulator
    def simulate(self, spec, design, *, stages, accuracy, errors=None, record_trajectory=False):
        from .sim import simulate_manipulators

        offsets = spec.verification.stage_list("offsets") if errors is None else errors
        return simulate_manipulators(spec.scene, design, stages=stages, offsets=offsets,
                                     accuracy=accuracy, record_trajectory=record_trajectory,
                                     allow_skips=spec.verification.allow_skips)

    # ------------------------------------------------------------------ the NLP
    objectives = ("max_offset_tolerance", "max_min_margin", "min_drop", "fastest_convergence",
                  "max_yield")

    def formulate(self, spec, parameters=None):
        from .formulation import build
        from .formulation.offsets import Stages

        model, bounds, closed_forms = build(spec, parameters=parameters)
        # the stage maps also stream samples through the row: solve/check.py
        return model, bounds, Stages(spec, model, closed_forms, parameters)

    def nlp_key(self, spec):
        """The accuracy's agreement where the carry's integration steps follow it (damped
        pivots, or the carry integrated)."""
        forced = spec.verification.accuracy.carry == "integrated"
        damped = spec.scene.pivots.damping or forced
        return (spec.verification.accuracy.agreement if damped else None,)

    # ------------------------------------------------------ tolerances, yield, verification
    allocatable = ("pivot_x", "pivot_y", "feed_x", "friction", "object_width", "feed_speed",
                   "palm_mass", "object_mass", "back_stop", "link_length", "link_mass",
                   "pivot_friction")
    nlp_parameters = ("design.mass_ratio", "design.first_pivot_x", "design.first_pivot_y",
                      "scene.palm.friction")
    sizes_for_yield_target = True
    # the quantities of every manipulator: a corner takes them all high or all low
    box_axes = BoxAxes((("dx", "pivot_x"), ("dy", "pivot_y")),
                       per_part=("palm_mass", "link_length", "back_stop", "link_mass",
                                 "pivot_friction"),
                       alternating=("link_length",))

    allocation_refusal = lazily(".refusals:allocation_refusal")

    def length_scale(self, spec, design):
        """Its link length."""
        return float(design.get("link_length", 1.0))

    simulate_build = lazily(".tolerances:simulate_build")
    left_closed_forms = lazily(".verification:left_closed_forms")
    disagreement_note = lazily(".verification:disagreement_note")
    run_builds = lazily(".tolerances:run_builds")
    linearised_yield = lazily(".formulation.statistical:linearised_yield")
    linearised_rows = lazily(".formulation.statistical:placed_rows")

    def simulate_box_build(self, spec, design, errors, deviations, accuracy):
        from .verification import simulate_box_build

        return simulate_box_build(self, spec, design, errors, deviations, accuracy)

    closed_form_agreement = lazily(".verification:closed_form_agreement")

    def condition_words(self):
        from .words import CONDITIONS

        return {name: (what, advice, ()) for name, (what, advice) in CONDITIONS.items()}

    tolerance_refusal = lazily(".refusals:tolerance_refusal")
    place_nouns = ("palm",)  # "palm 3 back, at its front stop" (formulation/rows.py)

    # ------------------------------------------------------ sheets, drawings, reports
    tolerance_axes = ("dx", "dy")
    dxf_layers = {"PIVOTS": 7, "LINKS": 5, "PALMS": 8, "STOPS": 1}  # scenes/manipulators/dxf.py
    stage_columns = ("manipulator", "landing_time", "landing_offset", "landing_speed",
                     "handover_speed", "handover_angle")
    quantity_units = {
        "alpha": "rad", "beta": "rad", "link_length": "m", "mass_ratio": "", "first_pivot_x": "m",
        "first_pivot_y": "m", "landing_offset": "m", "pitch_x": "m", "pitch_y": "m",
        "palm_mass": "kg", "handover_speed": "m/s", "landing_speed": "m/s", "contraction": "",
        "drop_per_stage": "m", "effective_mass": "kg", "link_mass": "kg",
        "link_inertia": "kg m^2", "link_count": "", "pivot_friction_torque": "N m",
        "pivot_damping": "N m s/rad",
    }
    quantity_parts = {
        "pivot_x": "every pivot bracket", "pivot_y": "every pivot bracket",
        "feed_x": "the feed (start place)", "friction": "every palm's surface",
        "object_width": "the objects carried", "feed_speed": "the feed (start speed)",
        "palm_mass": "every palm", "object_mass": "the objects carried",
        "link_length": "every link", "back_stop": "every back stop", "link_mass": "every link",
        "pivot_friction": "every pivot bracket's joints",
    }

    def shown_geometry(self, geometry):
        """The links' and pivots' rows only where the row has links or pivots (massless links
        and free pivots show none)."""
        if any(geometry.get(k) for k in MECHANISM if k != "link_count"):
            return geometry
        return {k: v for k, v in geometry.items() if k not in MECHANISM}

    @property
    def part_words(self):
        from .sheet import PART_WORDS

        return PART_WORDS

    sheet_rows = lazily(".sheet:sheet_rows")

    def sheet_words(self):
        from .sheet import WORDS

        return WORDS

    box_tolerances = lazily(".sheet:box_tolerances")
    parts = lazily(".sheet:parts")
    table_rows = lazily(".sheet:table_rows")

    draw_sheet = lazily(".drawing:draw_manipulators")

    draw_dxf = lazily(".dxf:draw_dxf")

    def document_keys(self):
        from .model import ManipulatorsDesign

        return {"design": ManipulatorsDesign.VARIABLES,
                "geometry": ("pitch_x", "pitch_y", "palm_mass", "link_mass", "link_inertia",
                             "link_count", "pivot_friction_torque", "pivot_damping",
                             "landing_offset"),
                "periodic": ("handover_speed", "landing_speed", "contraction", "drop_per_stage",
                             "effective_mass"),
                "approach": ("landing_point", "landing_velocity", "handover_speeds")}

    def scene_parameters(self, scene):
        """`links` (mass of each link, inertia about its pivot or null for a uniform rod,
        count) and `pivots` (friction_torque, damping): the paper's zeros when left out."""
        links, pivots = scene.links, scene.pivots
        return {"links": {"mass": links.mass, "inertia": links.inertia, "count": links.count},
                "pivots": {"friction_torque": pivots.friction_torque,
                           "damping": pivots.damping}}

    def plot_run(self, spec, design, result, path, *, offsets=(), stages=None, title=""):
        from .sim.plot import plot_manipulators

        plot_manipulators(result, spec.scene, design, path, offsets=offsets, stages=stages,
                          title=title)

    def animation(self, spec, result, timeline):
        from .animation import animation

        return animation(spec, result)


    # ------------------------------------------------------ command line, tables, API
    table_geometry = ("pitch_x", "pitch_y", "palm_mass", "landing_offset")
    column_labels = {
        "handover_speed": ("handover speed", "m/s"), "pitch_x": ("pitch x", "m"),
        "pitch_y": ("pitch y, down", "m"), "alpha": ("alpha", "rad"), "beta": ("beta", "rad"),
        "link_length": ("link length", "m"), "palm_mass": ("palm mass", "kg"),
        "landing_offset": ("landing offset", "m"), "landing_speed": ("landing speed", "m/s"),
        "first_pivot_x": ("first pivot x", "m"), "first_pivot_y": ("first pivot y", "m"),
        "tolerance.dx": ("tolerance dx", "m"), "tolerance.dy": ("tolerance dy", "m"),
    }
    table_periodic = ("handover_speed", "landing_speed", "contraction",
                      "drop_per_stage")
    def infeasible_words(self, spec, design):
        """Where the start and palm 1 are, when the least-violation design puts it below."""
        from .start import start_words

        return start_words(spec.scene.initial.position[1], spec.design, design)

    stage_errors = StageErrors("--offset", "K:DX,DY", "offsets", "manipulator",
                               lambda k, a, b: _offset(manipulator=k, dx=a, dy=b))


def _offset(**fields):
    from .model import ManipulatorOffset

    return ManipulatorOffset(**fields)
