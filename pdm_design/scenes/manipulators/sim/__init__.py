"""Event simulator of the manipulators scene: the object is followed from its initial state
through flights, landings, carries and handovers; nothing assumes the periodic solution.

Phases (docs/manipulators_model.md has the model and its derivations):
  flight   ballistic, closed form; first contact with a resting palm found exactly;
  stuck    carry with the object stuck on palm k: closed form in the palm angle th, every guard
           a function of th located by root finding, time by quadrature of l dth / v(th);
  sliding  carry with the object sliding on palm k: solve_ivp with terminal events;
  bouncing (restitution > 0 only) object in flight above its moving palm: solve_ivp;
  lift-off the object flies on while its empty palm swings alone; where it meets that palm is
           located exactly (closed-form swing time, Brent on bracketed roots): liftoff.py;
  rocking  past a tip onset the object turns about an edge of its support: rocking.py;
  edge slide  its edge or corner slides (Coulomb), it comes down flat or rolls onto a side
           face: edgeslide.py;
  tumbling it leaves its edge and flies turning until a corner or a palm's edge meets a palm:
           tumbling.py;
  pushing  the carried object pushes a palm ahead off its back stop until that palm parts and
           swings on alone (followed as a palm swinging from rest): pushing.py; sliding on its
           palm while it pushes: pushslide.py;
  bridge   the rocking object comes down on a second palm still bearing on its own: a plastic
           impact at both contacts (twocontact.py), then it rests across both, stuck or
           sliding on each, until one contact opens: bridge.py.

The run is *complete* when the object, carried by the last manipulator of the row, reaches that
manipulator's handover angle beta (so it has been handed over by every other manipulator and
carried over the last one's top through the whole nominal carry arc). Outcome.stages_passed is
the number of manipulators passed: those that handed the object over, plus the last one on
completion.
"""

from __future__ import annotations

import math

import numpy as np

from ....accuracy import accuracy as resolve_accuracy
from ....sim.core import SimulationResult, check_scales
from .. import physics as phys
from .run import Run

EVENT_KINDS = {
    "landing": "the object lands on a palm from a flight (at rest, or swinging after a lift-off)",
    "handover": "the object, carried by palm k, meets the next palm and lands on it",
    "slip": "the carried object starts to slide on its palm (or reverses its sliding); the "
            "rocking object's contact starts to slide (or reverses its sliding)",
    "stick": "the sliding object comes to rest on its palm and is carried stuck; the rocking "
             "object's sliding contact sticks again",
    "jam": "a sliding contact jams (Painleve-type tangential impact) and sticks",
    "bounce": "the object bounces off a palm (restitution > 0)",
    "front_stop": "an empty palm reaches its front stop and is stopped",
    "back_stop": "an empty palm swings back onto its back stop",
    "pivot_friction_stop": "an empty palm stops mid-swing where pivot friction holds it",
    "complete": "the last manipulator carried the object to its handover angle",
    "rock": "the object starts to turn about an edge of its supported base (the force or "
            "impulse line reached it), or rocks on to the base's other end",
    "settle": "the rocking object comes back down flat on its palm and is carried on",
    "catch": "a corner of the rocking object comes down on another palm, which carries it on",
    "release": "the rocking object (or the object across two palms) drags a palm off the stop "
               "it rested on",
    "bridge": "the rocking object comes down on a second palm still bearing on its own: a "
              "plastic impact at both contacts, then it rests across both palms until one "
              "contact opens",
    "roll": "the object turned to pi/2 about its base corner: the side face it turned onto "
            "comes down on the palm and is its base from then on",
    "leave": "the rocking object leaves its palm (its contact force vanishes, or its sliding "
             "contact runs off the end of its base or of the palm) and flies on, tumbling",
    "push": "the carried object meets the rear end of the next palm, resting on its back "
            "stop, and pushes it off the stop (a plastic impact with friction at its corner)",
    "part": "the palm the carried object pushes parts from it and swings on alone",
    "stepped": "a contact no phase follows (a palm's side or corner met, a third contact, an "
               "impact or slide with no consistent mode) is followed by time stepping from "
               "there; logged again when the object lies flat on one palm and the phases take "
               "it on",
    "lift_off": "the palm's normal force vanished (v^2 >= g l cos th): the object flies on and "
                "the empty palm swings alone",
}
FAILURE_KINDS = {
    "blocked": "the object hits the side or underside of a palm where time stepping cannot "
               "take it on (restitution > 0); or, pushing the next palm off its back stop, "
               "lifts, tips or meets another palm before that palm parts from it (a sustained "
               "push: not followed)",
    "fell_clear": "the object fell past the row",
    "missed": "the object lifted off and fell past the row without landing on a palm",
    "tip": "the object tips or tumbles in a way the model does not follow: with restitution "
           "> 0, or (restitution 0, where time stepping does not take it on) landing with no "
           "face turned to come down about its contact, a slip or sliding impact that would "
           "reverse, a sliding contact riding its palm onto a stop; across two palms: no "
           "consistent impact or slide, a palm reaching a stop, both palms held",
    "tipped_over": "the rocking object turned to pi/2 on a palm's edge (its base stands against "
                   "the edge; not followed)",
    "stall": "the carry stops before the top: the palm swings back to its back stop",
    "slid_off": "the object's centre slid off the end of its palm",
    "stranded": "the palm reached its front stop still carrying the object (no handover), or "
                "the object came to rest across two palms (or, time stepped, wedged among "
                "palms)",
    "impact_jam": "an impact has no consistent sliding solution (Painleve paradox)",
    "skipped_palm": "the object flew over a palm and came onto one further on (a spec may allow "
                    "it: [verification] allow_skips)",
    "swinging_palm": "the object meets the side of a palm released past the vertical (or "
                     "pushed off its back stop) while it still swings, or passes one after "
                     "rocking (not followed: restitution > 0; with restitution 0 it is time "
                     "stepped)",
    "timeout": "a phase ran longer than the model allows without an event (time stepping: "
               "3 s without reaching a state the phases follow)",
    "too_many_events": "the run exceeded its event budget",
}


def simulate_manipulators(scene, design, *, stages: int = 6, offsets=(), accuracy="default",
                          record_trajectory: bool = False, parts=None,
                          allow_skips: bool = False) -> SimulationResult:
    """Simulate the object along a row of `stages` manipulators from the scene's initial state.

    offsets: objects with .manipulator (1-based), .dx, .dy (m, y up) shifting that pivot.
    parts: geometry.Parts, every manipulator's own link length, back stop and palm mass.
    allow_skips: an object that flies over a palm and comes onto one further on goes on (the
    palms flown over count as passed); by default the run fails there (`skipped_palm`).
    Returns a SimulationResult: outcome, one record per manipulator reached (see
    docs/manipulators_model.md for the fields), the event log, and, if asked for, trajectories
    (time, x, y, vx, vy of the object's bottom centre; theta and manipulator of its carrier).
    """
    acc = resolve_accuracy(accuracy)
    check_manipulators_scales(scene, design, offsets)
    return Run(scene, design, stages, offsets, acc, record_trajectory, parts,
               allow_skips).run()


def check_manipulators_scales(scene, design, offsets=()) -> None:
    """Refuse (core.SimulationRefused) a scene whose lengths, speeds or mass ratio are so far
    from the link length, sqrt(g l) and 1 that double precision cannot follow the motion."""
    l, g = design.link_length, scene.gravity
    check_scales(("the gravity", g), {})
    check_scales(("the body mass", scene.body.mass), {})
    (x, y), (vx, vy) = scene.initial.position, scene.initial.velocity
    lengths = {
        "body width": scene.body.width, "body height": scene.body.height,
        "palm width": scene.palm.width, "palm thickness": scene.palm.thickness,
        "initial x": x - design.first_pivot_x, "initial y": y - design.first_pivot_y,
    }
    for off in offsets:
        lengths[f"offset dx of manipulator {off.manipulator}"] = float(off.dx)
        lengths[f"offset dy of manipulator {off.manipulator}"] = float(off.dy)
    check_scales(("the link length", l), lengths)
    check_scales(("sqrt(g l)", math.sqrt(g) * math.sqrt(l)),
                 {"initial speed x": vx, "initial speed y": vy})
    check_scales(("1", 1.0), {"mass_ratio": design.mass_ratio, "friction": scene.palm.friction})


def handover_angle(beta, rise, link_length):
    """Angle at which a stuck carry hands over when the next palm stands `rise` higher than the
    nominal pitch (y up): cos th = cos beta + rise / l. nan where there is no such angle."""
    q = np.cos(beta) + np.asarray(rise, dtype=float) / link_length
    with np.errstate(invalid="ignore"):
        return np.where(np.abs(q) <= 1.0, np.arccos(np.clip(q, -1.0, 1.0)), np.nan)


def handover_map(speeds, alpha, beta, mass_ratio, g, l, *, arrival_angle=None,
                 departure_angle=None, friction=0.0):
    """Stick-regime stage map, vectorised: the speed at which a palm hands the object over, given
    the speed `speeds` at which the object was handed onto it.

    The object arrives along t(arrival_angle) (default beta: the previous handover angle), lands
    plastically on the palm resting at -alpha (u = m/(m+M) s cos(alpha + arrival_angle)) and is
    carried stuck to departure_angle (default beta): s'^2 = u^2 + 2 g l (cos alpha - cos dep).
    With the defaults this is s'^2 = c s^2 + D, physics.manipulators.next_handover_speed.
    nan where the carry cannot pass the top (u^2 < 2 g l (1 - cos alpha) or u < 0).
    Links and pivot friction: pass physics.manipulators.carry_terms' (q_e, g_e, f) as
    mass_ratio, g and friction."""
    s = np.asarray(speeds, dtype=float)
    arr = beta if arrival_angle is None else np.asarray(arrival_angle, dtype=float)
    dep = beta if departure_angle is None else np.asarray(departure_angle, dtype=float)
    # the physics closed forms: cos a - cos dep and 1 - cos a without cancellation (at
    # alpha = 1e-6 the plain differences lost 11 of 16 digits of the fixed point)
    u = phys.momentum_fraction(mass_ratio) * s * np.cos(alpha + arr)
    v2 = phys.carry_speed_squared(u, alpha, dep, gravity=g, link_length=l, friction=friction)
    passes = (u >= 0.0) & (u * u >= phys.top_speed_squared_needed(
        alpha, gravity=g, link_length=l, friction=friction))
    with np.errstate(invalid="ignore"):
        return np.where(passes & (v2 >= 0.0), np.sqrt(np.maximum(v2, 0.0)), np.nan)
