"""Everything the shared layers need of the rimless wheel scene, by the names the stairs scene's
pieces have, so wiring it into the scene interface is mechanical. Heavy modules (numpy, scipy,
casadi) are imported only when a function here is called.

    KIND, SCENE_CLASS, DESIGN_CLASS, MARGINS, QUANTITIES, FAILURE_KINDS, VERIFICATION_HINTS
    analyse(scene, design, stages=None)            -> analysis.result.Analysis
    simulate(scene, design, *, stages, accuracy, step_errors, record_trajectory, ...)
                                                   -> sim.core.SimulationResult (subclass)
    build(spec)                                    -> (SceneModel, bounds, closed forms)
    spoke_counts(spec), with_spokes(spec, n)       -> the integer spoke count, one NLP each
    run_builds(scene, design, tolerances, *, stages, builds, seed, distribution)
                                                   -> yield after `stages` steps
    mfpt(scene, design, tolerance), monte_carlo(...), longest_lasting(...): rough ground
    template()                                     -> the spec template's TOML text
"""

from __future__ import annotations

from . import KIND, MARGINS  # noqa: F401  (re-exported)
from .model import RimlessWheelDesign, RimlessWheelScene

SCENE_CLASS = RimlessWheelScene
DESIGN_CLASS = RimlessWheelDesign
QUANTITIES = ("slope", "rise", "tread", "speed")
FAILURE_KINDS = ("stalled", "flight", "slip", "nose_hit", "missed_tread")
VERIFICATION_HINTS = {"offsets": "offsets are for manipulators scenes; a rimless wheel takes "
                                 "step_errors (slope on a ramp, rise and tread on stairs)"}


def analyse(scene, design, stages=None):
    from .analysis import analyse_rimless_wheel

    return analyse_rimless_wheel(scene, design, stages)


def simulate(scene, design, **kwargs):
    from .sim import simulate_rimless_wheel

    return simulate_rimless_wheel(scene, design, **kwargs)


def build(spec):
    from .formulation import build as build_rows

    return build_rows(spec)


def spoke_counts(spec):
    from .formulation import spoke_counts as counts

    return counts(spec)


def with_spokes(spec, count):
    from .formulation import with_spokes as fixed

    return fixed(spec, count)


def run_builds(scene, design, tolerances, **kwargs):
    from .builds import run_builds as run

    return run(scene, design, tolerances, **kwargs)


def mfpt(scene, design, tolerance, **kwargs):
    from .rough import mfpt as chain

    return chain(scene, design, tolerance, **kwargs)


def monte_carlo(scene, design, tolerance, **kwargs):
    from .rough import monte_carlo as mc

    return mc(scene, design, tolerance, **kwargs)


def longest_lasting(scene, counts, slope_range, leg_length, tolerance, **kwargs):
    from .rough import longest_lasting as search

    return search(scene, counts, slope_range, leg_length, tolerance, **kwargs)


def template():
    from .template import rimless_wheel_template

    return rimless_wheel_template()
