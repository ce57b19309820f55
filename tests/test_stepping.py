"""The time stepper (sim/stepping.py) against closed forms and scipy's integration, and the runs
it takes on (sim/stepped.py)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pdm_design.scenes.manipulators.sim.stepping import Block, Slab, Stepper, contacts, step

G, MU, L, W, H, M_OBJ = 9.81, 0.8, 2.0, 0.4, 0.2, 1.0
FRONT = 0.5 * math.pi
BLOCK = Block(M_OBJ, M_OBJ * (W * W + H * H) / 12.0, W, H)


def stepper(palm_mass=0.1, dt=2e-4, mu=MU, low=-0.06):
    slab = Slab((0.0, 0.0), L, palm_mass, palm_mass, 0.0, 0.0, low, FRONT, 1.6, 0.05)
    return Stepper(BLOCK, (slab,), G, mu, dt)


def run(st, q, v, seconds):
    found = ()
    for _ in range(round(seconds / st.dt)):
        q, v, found = step(st, q, v, found)
    return q, v


def test_contacts_by_separating_axes():
    st = stepper()
    top_x, top_y = st.slabs[0].top(FRONT)
    # lying flat 1 mm above the palm: its two base corners, 1 mm off, the normal up
    found = contacts(st, np.array([top_x, top_y + 0.5 * H + 1e-3, 0.0, FRONT]), 0.01)
    assert sorted(round(c.point[0] - top_x, 12) for c in found) == [-0.5 * W, 0.5 * W]
    assert all(c.gap == pytest.approx(1e-3) and c.normal == (0.0, 1.0) for c in found)
    # turned a quarter and pierced by the slab's end (no corner of either inside the other):
    # in contact, with the overlap as a negative gap
    q = np.array([top_x + 0.8, top_y - 0.025, 0.5 * math.pi, FRONT])
    found = contacts(st, q, 0.01)
    assert found and min(c.gap for c in found) < -0.02
    # beside the palm's end, 3 cm clear: one face against the other, 3 cm
    found = contacts(st, np.array([top_x + 0.8 + 0.5 * W + 0.03, top_y, 0.0, FRONT]), 0.05)
    assert found and all(c.gap == pytest.approx(0.03) for c in found)
    assert all(c.normal == pytest.approx((1.0, 0.0)) for c in found)


def test_a_slide_on_a_palm_held_at_its_front_stop_stops_after_v2_over_2_mu_g():
    st = stepper()
    top_x, top_y = st.slabs[0].top(FRONT)
    q0 = np.array([top_x - 0.5, top_y + 0.5 * H, 0.0, FRONT])
    v0 = 2.0
    q, v = run(st, q0, np.array([v0, 0.0, 0.0, 0.0]), 0.2)  # still sliding at 0.2 s
    assert v[0] == pytest.approx(v0 - MU * G * 0.2, abs=MU * G * st.dt)
    q, v = run(st, q, v, 0.2)
    assert q[0] - q0[0] == pytest.approx(v0 * v0 / (2.0 * MU * G), rel=2e-3)
    assert np.abs(v).max() < 1e-9  # at rest, and the palm held by its stop
    assert q[1] == pytest.approx(q0[1], abs=1e-9) and q[3] == FRONT


def test_rocking_about_a_held_palm_edge_is_the_pendulum_about_the_corner():
    # the object's centre 5 cm beyond the palm's front end, from rest: it turns about the edge
    st = stepper()
    top_x, top_y = st.slabs[0].top(FRONT)
    d = 0.05
    q = np.array([top_x + 0.8 + d, top_y + 0.5 * H, 0.0, FRONT])
    rho = math.hypot(d, 0.5 * H)
    about = BLOCK.inertia + M_OBJ * rho * rho
    lean = math.atan2(d, 0.5 * H)
    sol = solve_ivp(lambda t, z: [z[1], M_OBJ * G * rho * math.sin(lean + z[0]) / about],
                    (0.0, 0.2), [0.0, 0.0], rtol=1e-11, atol=1e-13)
    q, v = run(st, q, np.zeros(4), 0.2)
    assert q[2] == pytest.approx(sol.y[0, -1], rel=3e-3)
    assert v[2] == pytest.approx(sol.y[1, -1], rel=3e-3)


def test_an_empty_palm_swings_as_its_pendulum_and_stops_at_its_front_stop():
    st = stepper()
    # far from the object: only the palm moves (l th'' = g sin th)
    q = np.array([50.0, 50.0, 0.0, 0.3])
    sol = solve_ivp(lambda t, z: [z[1], G * math.sin(z[0]) / L], (0.0, 0.4), [0.3, 0.0],
                    rtol=1e-11, atol=1e-13)
    q1, v1 = run(st, q.copy(), np.zeros(4), 0.4)
    assert q1[3] == pytest.approx(sol.y[0, -1], rel=2e-3)
    q2, v2 = run(st, q1, v1, 1.5)
    assert q2[3] == pytest.approx(FRONT, abs=1e-9) and v2[3] == pytest.approx(0.0, abs=1e-9)


def test_a_flat_plastic_landing_on_a_free_palm_keeps_the_momentum_along_the_swing():
    # the palm free at th = 0.2 (off its stops), the object coming down flat onto it: the
    # impulse is along the palm's normal and the links', so (M + m) l th'+ = M l th' + m v.t
    palm_mass, theta = 0.1, 0.2
    st = stepper(palm_mass=palm_mass, dt=1e-5)
    top_x, top_y = st.slabs[0].top(theta)
    vx, vy = 0.5, -2.0
    q = np.array([top_x, top_y + 0.5 * H + 1e-4, 0.0, theta])
    v = np.array([vx, vy, 0.0, 0.0])
    q, v = run(st, q, v, 2e-3)  # the fall of 0.1 mm, the impact, and a little after
    tangent = vx * math.cos(theta) - vy * math.sin(theta)
    expected = M_OBJ * tangent / ((palm_mass + M_OBJ) * L)
    assert v[3] == pytest.approx(expected, rel=2e-2)  # (gravity acts over the 2 ms too)
    assert abs(v[2]) < 1e-9  # it lands flat and stays flat


def test_nothing_passes_through_a_palm():
    # an object thrown hard at a palm's side from every angle stays out of the slab
    st = stepper(dt=2e-4)
    top_x, top_y = st.slabs[0].top(-0.06)
    for spin in (-20.0, 0.0, 20.0):
        q = np.array([top_x - 1.2, top_y - 0.1, 0.3, -0.06])
        q, v = run(st, q, np.array([6.0, 0.0, spin, 0.0]), 0.15)
        assert min((c.gap for c in contacts(st, q, 1.0)), default=1.0) > -2e-3


def test_rocking_row_builds_stepped_past_a_contact_are_handed_back_and_complete(rocking_skips):
    # builds 56 (the rocking object meets a corner of palm 5) and 111 (the tumbling object
    # lands on palm 6 with no consistent sliding impact) once ended there, not followed; time
    # stepped, the object comes to lie flat on a palm, the phases take it on, and the row
    # completes
    from pdm_design.tolerances.yield_ import simulate_one

    spec, design, tolerances = rocking_skips
    for index, first in ((56, "the rocking object hits a corner of palm 5"),
                         (111, "the tumbling object lands on palm 6")):
        result = simulate_one(spec.scene, design, tolerances, 0, index, 8, accuracy="default",
                              allow_skips=True)
        assert result.outcome.completed
        events = result.events
        stepped = [i for i, e in enumerate(events) if e.kind == "stepped"]
        assert events[stepped[0]].detail.startswith(first)
        handed = [i for i in stepped if "the phases take it on" in events[i].detail]
        assert handed
        for i in handed:  # the object on the palm's top, within it, where the phases go on
            after = events[i].after
            assert abs(after["offset"]) <= 0.5 * 1.6 + 0.2
            assert events[i + 1].time >= events[i].time
            assert events[i + 1].kind in {"stick", "slip", "handover", "catch", "rock",
                                          "front_stop", "complete", "lift_off", "push"}


def test_an_edge_that_ends_on_the_face_span_is_clipped_without_error():
    # the object's base corner exactly above the palm's end: the first clip keeps that one
    # point (at distance 0 from the face's end), the second has one point to clip
    st = stepper()
    top_x, top_y = st.slabs[0].top(FRONT)
    q = np.array([top_x + 0.8 + 0.5 * W, top_y + 0.5 * H + 1e-4, 0.0, FRONT])
    (found,) = contacts(st, q, 0.01)  # the corner over the palm's end, 0.1 mm above its top
    assert found.point == pytest.approx((top_x + 0.8, top_y + 1e-4), abs=1e-12)
    assert found.gap == pytest.approx(1e-4) and found.normal == (0.0, 1.0)


@pytest.mark.parametrize("index, passage", [
    (111, "followed by time stepping"),
    (224, "followed by time stepping"),
    # the tumbling object leaves palm 5, held by its stop, and comes back down on it (the
    # flight once left that palm unguarded and the object fell through it)
    (854, "the tumbling object comes down on palm 5"),
    # across palms 3 and 2, the object turns until its base meets palm 3 away from its
    # contact (the bridge once guarded only the contacts, and the object passed into palm 2)
    (42, "meets palm 3 away from its contact"),
])
def test_builds_the_phases_complete_past_a_contact_complete_stepped_whole(
        rocking_skips, monkeypatch, index, passage):
    # a second method: the whole run time stepped from the feed, every palm in the stepper
    # and nothing handed to the phases, completes too
    from pdm_design.scenes.manipulators.sim.run import Run
    from pdm_design.tolerances.yield_ import simulate_one

    spec, design, tolerances = rocking_skips
    flight = Run._flight

    def stepped_from_the_feed(self, t0, x, y, vx, vy, stage):
        if t0 == 0.0 and not self.events:
            return self._step_whole(t0, x, y, vx, vy)
        return flight(self, t0, x, y, vx, vy, stage)

    phases = simulate_one(spec.scene, design, tolerances, 0, index, 8, allow_skips=True)
    assert phases.outcome.completed
    assert any(passage in e.detail for e in phases.events)
    with monkeypatch.context() as patch:
        patch.setattr(Run, "_flight", stepped_from_the_feed)
        whole = simulate_one(spec.scene, design, tolerances, 0, index, 8, allow_skips=True)
    assert whole.outcome.completed
    assert [e.kind for e in whole.events[-1:]] == ["complete"]
    assert not any(e.kind in ("landing", "handover", "rock", "catch") for e in whole.events)
