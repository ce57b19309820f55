"""A pdm-design scene shipped as its own package: a puck slides down a chain of ramps, and at the
foot of each a pendulum bob hanging at rest takes part of its speed (docs/scenes.md in
pdm-design walks through it). Everything the scene knows is a method of `PendulumRow`; the
entry point in pyproject.toml is how pdm-design finds it."""

from __future__ import annotations

from pdm_design.plugin import Scene

TEMPLATE = '''# A puck passed down a row of hanging pendulums (pdm-design init pendulum_row).
name = "my_pendulum_row"
description = "The bob mass that keeps the puck going and every bob below its pivot."

[scene]
kind = "pendulum_row"
ramp_angle = 0.3        # rad, every ramp's slope

[scene.puck]
mass = 1.0              # kg
restitution = 0.5       # puck against a bob

[initial]
speed = 2.0             # m/s, at the first bob

[design]
bob_mass = { min = 0.1, max = 1.9, initial = 1.0 }   # kg (the puck goes on while e M < m)
drop = 0.2              # m, every ramp's drop
rod_length = 0.5        # m, every pendulum's rod

[objective]
max_min_margin = 1.0

[verification]
stages = 12

[expect]
feasible = true
'''


class PendulumRow(Scene):
    kind = "pendulum_row"
    title = "a puck sliding down a row of hanging pendulums"
    stage_noun = ("bob", "bobs")
    margins = ("forward", "first_no_loop", "no_loop")
    objectives = ("max_min_margin", "fastest_convergence", "min_drop")
    table_periodic = ("bob_speed", "contraction")
    # the units the reports print (pdm-design's own table knows only shared quantities)
    quantity_units = {"bob_mass": "kg", "drop": "m", "rod_length": "m", "pitch": "m",
                      "bob_speed": "m/s", "speed_after": "m/s"}

    def scene_class(self):
        from .model import PendulumRowScene

        return PendulumRowScene

    def design_class(self):
        from .model import PendulumRowDesign

        return PendulumRowDesign

    def template(self):
        return TEMPLATE

    def analyse(self, scene, design, stages=None):
        from .analysis import analyse

        return analyse(scene, design, stages)

    def simulate(self, spec, design, *, stages, accuracy, errors=None, record_trajectory=False):
        from .sim import simulate

        return simulate(spec.scene, design, stages=stages, accuracy=accuracy,
                        record_trajectory=record_trajectory)

    def quantities(self):
        from .builds import QUANTITIES

        return QUANTITIES

    def run_builds(self, scene, design, deviations, stages):
        from .builds import run_builds

        return run_builds(scene, design, deviations, stages)

    def simulate_build(self, scene, design, deviations, stages, *, accuracy="default",
                       record_trajectory=False, allow_skips=False):
        from .builds import per_stage
        from .sim import simulate

        masses, drops = per_stage(design, deviations, 1, stages)
        return simulate(scene, design, stages=stages, accuracy=accuracy, masses=masses[0],
                        drops=drops[0], record_trajectory=record_trajectory)

    def formulate(self, spec, parameters=None):
        from .formulation import build

        return build(spec)
