"""The rimless wheel behind the scene interface (pdm_design.plugin.Scene). Heavy modules
(numpy, scipy, casadi) are imported only when a method is called."""

from __future__ import annotations

from ...plugin import Scene, StageList, lazily
from ..common import SlopeStepError, first_stream_keys

MARGINS = ("over_the_top", "no_flight", "no_slip", "impact_friction", "landing",
           "nose_clearance")
FAILURE_KINDS = ("stalled", "flight", "slip", "nose_hit", "missed_tread")


class RimlessWheel(Scene):
    kind = "rimless_wheel"
    title = "a rimless wheel rolling down a ramp or stairs"
    stage_noun = ("step", "steps")
    margins = MARGINS
    verification_hints = {"allow_skips": "allow_skips is for manipulators scenes (a palm flown "
                                         "over)",
                          "offsets": "offsets are for manipulators scenes; a rimless wheel "
                                     "takes step_errors (slope on a ramp, rise and tread on "
                                     "stairs)"}

    def stage_lists(self):
        return {"step_errors": StageList(SlopeStepError, "step")}

    # ------------------------------------------------------------------ the spec
    def scene_class(self):
        from .model import RimlessWheelScene

        return RimlessWheelScene

    def design_class(self):
        from .model import RimlessWheelDesign

        return RimlessWheelDesign

    template = lazily(".template:rimless_wheel_template")

    def variants(self, spec):
        """One spec per spoke count in the design's bounds (the count is an integer); the spec
        itself for a search objective (max_mfpt: the search looks at every count at once)."""
        from .counts import spoke_counts, with_spokes

        if set(spec.objective) & set(self.search_objectives):
            return (spec,)
        return tuple(with_spokes(spec, n) for n in spoke_counts(spec))

    def quantities(self):
        from .quantities import QUANTITIES

        return QUANTITIES

    stream_keys = first_stream_keys("rise", "tread")

    # ------------------------------------------------------------------ closed forms
    analyse = lazily(".analysis:analyse_rimless_wheel")

    # ------------------------------------------------------------------ the simulator
    def simulate(self, spec, design, *, stages, accuracy, errors=None, record_trajectory=False):
        from .sim import simulate_rimless_wheel

        errors = spec.verification.stage_list("step_errors") if errors is None else errors
        return simulate_rimless_wheel(spec.scene, design, stages=stages, accuracy=accuracy,
                                      step_errors=errors, record_trajectory=record_trajectory)

    # ------------------------------------------------------------------ the NLP
    objectives = ("max_offset_tolerance", "max_min_margin", "min_drop", "fastest_convergence",
                  "max_yield")

    def max_yield_refusal(self, scene):
        """The NLP's linearised yield is derived on a ramp and on stairs (nlp_yield.py); the
        quantities it does not take are refused when the NLP is built."""
        return None

    search_objectives = ("max_mfpt",)

    search = lazily(".search:longest_lasting_design")

    def formulate(self, spec, parameters=None):
        from .formulation import build

        model, bounds, _ = build(spec)
        return model, bounds, None

    # ------------------------------------------------------ tolerances, yield, verification
    run_builds = lazily(".builds:build_outcome")

    def simulate_build(self, scene, design, deviations, stages, *, accuracy="default",
                       record_trajectory=False, allow_skips=False):
        import dataclasses

        from .builds import spoke_lengths_of, step_errors_of
        from .sim import simulate_rimless_wheel

        start = float(deviations.get("start_speed", [0.0])[0])
        mass = float(deviations.get("mass", [0.0])[0])
        scene = dataclasses.replace(
            scene, initial=dataclasses.replace(scene.initial, speed=scene.initial.speed + start),
            wheel=dataclasses.replace(scene.wheel, mass=scene.wheel.mass + mass))
        lengths = (spoke_lengths_of(deviations, design, int(design.spokes))[0]
                   if "leg_length" in deviations else None)
        return simulate_rimless_wheel(scene, design, stages=stages, accuracy=accuracy,
                                      step_errors=step_errors_of(deviations, stages),
                                      record_trajectory=record_trajectory,
                                      spoke_lengths=lengths)

    def tolerance_refusal(self, spec, quantity):
        """leg_length on each spoke draws one length a spoke from the steps' stream: it needs
        [verification] stages >= the spoke count."""
        from .counts import spoke_counts

        tol = next((t for t in spec.tolerances if t.quantity == quantity), None)
        most = max(spoke_counts(spec))
        if (quantity == "leg_length" and tol is not None and tol.applies_to == "each"
                and spec.verification.stages < most):
            return ("verification.stages", f"an integer >= {most} (one leg length drawn a "
                    "spoke, from the steps' draws)", str(spec.verification.stages))
        return None

    def box_axes_of(self, spec):
        """Every step's own slope on a ramp; every step's rise and tread on stairs. Spokes of
        their own lengths (leg_length on each part): every spoke long or short, alternately
        long and short, and one length a spoke in a random build."""
        from ...plugin_tolerances import BoxAxes

        each = tuple(t.quantity for t in getattr(spec, "tolerances", ())
                     if t.quantity == "leg_length" and t.applies_to == "each")
        if spec.scene.ground == "ramp":
            return BoxAxes((("slope", "slope"),), each, each)
        return BoxAxes((("rise", "rise"), ("tread", "tread")), each, each)

    allocatable = ("slope", "rise", "tread", "start_speed", "leg_length", "mass")
    allocation_refusal = lazily(".refusals:allocation_refusal")

    def simulate_box_build(self, spec, design, errors, deviations, accuracy):
        """One build of the box: every step's slope error (a ramp) or rise and tread errors;
        deviations of an allocated box's other quantities: start_speed and mass (a number),
        leg_length (a number, or one a step of which spoke j takes step j + 1's)."""
        import numpy as np

        from .sim import simulate_rimless_wheel

        names = ("slope",) if spec.scene.ground == "ramp" else ("rise", "tread")
        if not deviations:
            steps = [{"step": k + 1, **dict(zip(names, e))} for k, e in enumerate(errors)]
            return simulate_rimless_wheel(spec.scene, design, stages=spec.verification.stages,
                                          accuracy=accuracy, step_errors=steps)
        built = {name: np.array([[e[i] for e in errors]]) for i, name in enumerate(names)}
        # a number: (1,), a lot; a list: (1, stages), one a step
        built.update({q: np.array([v], dtype=float) for q, v in deviations.items()})
        return self.simulate_build(spec.scene, design, built, spec.verification.stages,
                                   accuracy=accuracy)

    sizes_for_yield_target = True  # on a ramp and on stairs (nlp_yield.py)
    linearised_yield = lazily(".statistical:linearised_yield")
    linearised_rows = lazily(".statistical:placed_rows")

    def yield_extras(self, scene, design, tolerances, stages):
        """The mean steps before failure by the Markov chain: on a rough ramp (rough.mfpt) when
        the only toleranced quantity is every step's own slope, on stairs (rough_stairs) when
        they are every step's own rise and tread (normal)."""
        names = {t.quantity for t in tolerances}
        each = all(t.applies_to == "each" and t.distribution == "normal" for t in tolerances)
        if scene.ground == "stairs" and names == {"rise", "tread"} and each:
            from .rough_stairs import mfpt_interval

            value = {t.quantity: t.value for t in tolerances}
            return {"mfpt": mfpt_interval(scene, design, value["rise"], value["tread"])}
        if scene.ground != "ramp" or names != {"slope"}:
            return {}
        from .rough import mfpt

        found = mfpt(scene, design, next(t.value for t in tolerances))
        return {"mfpt": {k: found[k] for k in ("estimate", "ci_low", "ci_high", "method")}}

    # ------------------------------------------------------ sheets, drawings, reports
    dxf_layers = {"GROUND": 7, "WHEEL": 5}  # scenes/rimless_wheel/dxf.py
    stage_columns = ("step", "impact_time", "speed_before", "speed_after", "foot_x", "foot_y")
    quantity_parts = {"rise": "every step", "tread": "every step"}
    quantity_units = {
        "slope": "rad", "leg_length": "m", "spokes": "", "step_period": "s", "rise": "m",
        "tread": "m", "landing_offset": "m", "nose_clearance": "m", "contraction": "",
    }

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

    draw_sheet = lazily(".drawing:draw_wheel_sheet")

    draw_dxf = lazily(".dxf:draw_dxf")

    def scene_parameters(self, scene):
        """`wheel` as built: the hub's mass (kg), its radius of gyration (m) and each spoke's
        mass (kg), the defaults (1, 0, 0) when the spec leaves them out."""
        w = scene.wheel
        return {"wheel": {"mass": w.mass, "gyration": w.gyration, "spoke_mass": w.spoke_mass}}

    def plot_run(self, spec, design, result, path, *, offsets=(), stages=None, title=""):
        from .plot import plot_wheel_run

        plot_wheel_run(spec, result, path, title=title)

    animation = lazily(".animation:animation")

    # ------------------------------------------------------ command line, tables, API
    tolerance_axes = ("slope",)
    column_labels = {"rise": ("rise", "m"), "tread": ("tread", "m"),
                     "landing_offset": ("landing offset", "m")}
