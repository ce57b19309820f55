"""The event simulator: the puck integrated down each ramp (scipy, event-located at the ramp's
foot), an impact at each bob; named failures. It does not use the periodic closed forms: the
tests hold those against it."""

from __future__ import annotations

import math

from pdm_design.sim.core import Event, Outcome, SimulationResult

KIND = "pendulum_row"


def _down_the_ramp(v0: float, length: float, g: float, angle: float, accuracy):
    """(speed at the foot, time, the slide: distance along the incline at a time) of a slide
    from speed v0 down `length` metres of incline."""
    from scipy.integrate import solve_ivp

    def foot(t, y):
        return y[0] - length

    foot.terminal, foot.direction = True, 1
    horizon = 10.0 * (length / max(v0, 1e-12) + math.sqrt(2.0 * length / (g * math.sin(angle))))
    run = solve_ivp(lambda t, y: (y[1], g * math.sin(angle)), (0.0, horizon), (0.0, v0),
                    events=foot, rtol=accuracy.rtol, atol=accuracy.atol * max(1.0, length),
                    dense_output=True)
    return float(run.y_events[0][0][1]), float(run.t_events[0][0]), lambda t: run.sol(t)[0]


def simulate(scene, design, *, stages: int, accuracy, masses=None, drops=None,
             record_trajectory: bool = False) -> SimulationResult:
    """The run from the first bob; record_trajectory: the puck's path (time, x, y; the first
    bob at the origin, x along the row, y up), sampled along every ramp."""
    m, e, g = scene.puck.mass, scene.puck.restitution, scene.gravity
    l = design.rod_length
    masses = [design.bob_mass] * stages if masses is None else masses  # a build's own parts
    drops = [design.drop] * stages if drops is None else drops
    v, t, events, records, failure = scene.initial.speed, 0.0, [], [], None
    path = {"time": [0.0], "x": [0.0], "y": [0.0]}
    cos_a, sin_a = math.cos(scene.ramp_angle), math.sin(scene.ramp_angle)
    for k in range(1, stages + 1):
        M, length = masses[k - 1], drops[k - 1] / math.sin(scene.ramp_angle)
        v_after = (m * v - e * M * v) / (m + M)  # momentum, and restitution's speed apart
        bob = v_after + e * v
        events.append(Event(t, "impact", k, {"speed": v}, {"speed": v_after, "bob_speed": bob}))
        records.append({"bob": k, "time": t, "bob_speed_before": v, "puck_after": v_after,
                        "bob_after": bob})
        if bob * bob >= 4.0 * g * l:
            failure = Event(t, "looped", k, {"bob_speed": bob}, {},
                            f"bob {k} swings over its pivot ({bob:.4g} m/s)", failure=True)
        elif v_after <= 0.0:
            failure = Event(t, "stalled", k, {"speed": v_after}, {},
                            f"the puck stops or bounces back at bob {k}", failure=True)
        if failure is not None:
            events.append(failure)
            break
        v, dt, slide = _down_the_ramp(v_after, length, g, scene.ramp_angle, accuracy)
        if record_trajectory:
            x0, y0 = path["x"][-1], path["y"][-1]
            for i in range(1, 9):
                along = float(slide(dt * i / 8))
                path["time"].append(t + dt * i / 8)
                path["x"].append(x0 + along * cos_a)
                path["y"].append(y0 - along * sin_a)
        t += dt
    passed = len(records) - (failure is not None)
    return SimulationResult(KIND, Outcome(failure is None, passed, failure), records, events,
                            accuracy, path if record_trajectory else {})
