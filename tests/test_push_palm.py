"""The carried object pushing the next palm off its back stop (sim/pushing.py, docs/physics.md
section 2.2c): the impact against a second method (the impulse built up in small steps of the
normal impulse, the slip direction read at every step) and the momentum balance written out by
hand; the push against a linear solve of the three balances; a rocking-row build where the
pushed palm parts, swings to its front stop as scipy's pendulum does and later receives the
object."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pdm_design.scenes.manipulators.sim.pushing import push_accelerations, push_impact
from pdm_design.tolerances.yield_ import one_build, simulate_one


def _keller_by_steps(u_k, u_j, th_k, th_j, m_k, m_j, mu, steps=2000000):
    """The impact built up in small steps dp of the normal impulse: at each step the friction
    opposes the current slip of the object up the corner's face (no slip: the step that keeps
    it nil if within the cone); ends when the approach along the row has ended."""
    tk = np.array([math.cos(th_k), -math.sin(th_k)])
    tj = np.array([math.cos(th_j), -math.sin(th_j)])
    vn0 = u_k * tk[0] - u_j * tj[0]
    dp = 2.0 * vn0 * max(m_k, m_j) / steps
    pn = pt = 0.0
    for _ in range(10 * steps):
        vn = u_k * tk[0] - u_j * tj[0]
        if vn <= 0.0:
            break
        vt = u_k * tk[1] - u_j * tj[1]
        # the friction step that would bring vt to zero, capped by the cone
        d_vt_dpt = tk[1] ** 2 / m_k + tj[1] ** 2 / m_j  # vt per unit impulse up the face
        d_vt_dpn = -tk[0] * tk[1] / m_k - tj[0] * tj[1] / m_j
        want = -(vt + d_vt_dpn * dp) / d_vt_dpt
        dpt = max(-mu * dp, min(mu * dp, want))
        P = np.array([-dp, dpt])
        u_k += P @ tk / m_k
        u_j -= P @ tj / m_j
        pn, pt = pn + dp, pt + dpt
    return u_k, u_j, pn, pt


@pytest.mark.parametrize("th_k", [0.35, -0.05, 0.0])
def test_the_push_impact_is_the_impulse_built_up_in_small_steps(th_k):
    m_k, m_j, mu, th_j, u_k = 1.1, 0.1, 0.8, -0.0613, 3.0
    imp = push_impact(u_k, 0.0, th_k, th_j, m_k=m_k, m_j=m_j, mu=mu)
    uk, uj, pn, pt = _keller_by_steps(u_k, 0.0, th_k, th_j, m_k, m_j, mu)
    assert imp is not None and not imp.stick
    assert imp.u_k == pytest.approx(uk, abs=2e-5)
    assert imp.u_j == pytest.approx(uj, abs=2e-5)
    assert imp.pn == pytest.approx(pn, rel=1e-4)
    assert imp.pt == pytest.approx(pt, abs=1e-4 * pn)
    # by hand: each swing's generalized momentum changes by the impulse along its tangent,
    # P = (-pn, pt) on the object, -P on palm j; plastic along the row; Coulomb; no energy
    tk = (math.cos(th_k), -math.sin(th_k))
    tj = (math.cos(th_j), -math.sin(th_j))
    assert m_k * (imp.u_k - u_k) == pytest.approx(-imp.pn * tk[0] + imp.pt * tk[1], abs=1e-12)
    assert m_j * imp.u_j == pytest.approx(imp.pn * tj[0] - imp.pt * tj[1], abs=1e-12)
    assert imp.u_k * tk[0] - imp.u_j * tj[0] == pytest.approx(0.0, abs=1e-12)
    assert abs(imp.pt) <= mu * imp.pn * (1 + 1e-12)
    lost = 0.5 * m_k * u_k ** 2 - 0.5 * m_k * imp.u_k ** 2 - 0.5 * m_j * imp.u_j ** 2
    assert lost > 0.0
    assert imp.u_j > imp.u_k * math.cos(th_k)  # palm j is pushed off ahead of the object


def test_a_palm_moving_away_faster_is_not_met():
    assert push_impact(1.0, 2.0, 0.1, -0.06, m_k=1.1, m_j=0.1, mu=0.8) is None


def test_the_push_is_the_three_balances_solved_together():
    """Object-plus-palm k along t_k, palm j along t_j, the contact force N (-1, -sgn mu) on
    the object (-N (...) on palm j) and the face kept on the corner: a 3 x 3 linear solve."""
    th_k, om_k, th_j, om_j = 0.4, 1.5, -0.03, 1.3
    l_k, l_j, m_k, m_j, mu, g = 2.01, 1.99, 1.1, 0.12, 0.7, 9.81
    for sgn in (1.0, -1.0):
        tk = np.array([math.cos(th_k), -math.sin(th_k)])
        tj = np.array([math.cos(th_j), -math.sin(th_j)])
        d = np.array([-1.0, -sgn * mu])
        # unknowns (th_k'', th_j'', N); rows: the two swings, the constraint's second derivative
        A = np.array([[m_k * l_k, 0.0, -d @ tk],
                      [0.0, m_j * l_j, d @ tj],
                      [l_k * tk[0], -l_j * tj[0], 0.0]])
        # x of the face minus x of the corner, l_k sin th_k - l_j sin th_j, kept: its second
        # derivative vanishes
        b = np.array([m_k * g * math.sin(th_k), m_j * g * math.sin(th_j),
                      l_k * om_k ** 2 * math.sin(th_k) - l_j * om_j ** 2 * math.sin(th_j)])
        want = np.linalg.solve(A, b)
        got = push_accelerations(th_k, om_k, th_j, om_j, acc_k=g * math.sin(th_k) / l_k,
                                 acc_j=g * math.sin(th_j) / l_j, l_k=l_k, l_j=l_j, m_k=m_k,
                                 m_j=m_j, mu=mu, sgn=sgn)
        assert got == pytest.approx(tuple(want), rel=1e-10)


def test_a_pushed_palm_parts_swings_as_its_pendulum_and_later_receives_the_object(rocking_skips):
    spec, design, tol = rocking_skips
    result = simulate_one(spec.scene, design, tol, 0, 198, 8, allow_skips=True)
    kinds = [e.kind for e in result.events]
    assert "push" in kinds and "part" in kinds
    push = next(e for e in result.events if e.kind == "push")
    part = next(e for e in result.events if e.kind == "part")
    assert "palm 8" in push.detail and push.stage == 6
    lengths = 2.0 + one_build(tol, 0, 198, 8, scene=spec.scene)["link_length"][0]
    l_k, l_j = lengths[5], lengths[7]
    # the face stays on the corner through the push: the constraint is kept
    gap0 = l_k * math.sin(push.after["theta"]) - l_j * math.sin(push.after["palm_theta"])
    gap1 = l_k * math.sin(part.after["theta"]) - l_j * math.sin(part.after["palm_theta"])
    assert gap1 == pytest.approx(gap0, abs=1e-6)
    assert part.after["palm_theta"] > push.after["palm_theta"]  # pushed forward off its stop
    # through the push friction at the corner only takes energy out: the two swings' energy
    # (palm 6 with the object, palm 8) is lower at the part than just after the impact
    dev = one_build(tol, 0, 198, 8, scene=spec.scene)
    masses = spec.scene.body.mass / design.mass_ratio + dev["palm_mass"][0]
    m_k, m_j, g = spec.scene.body.mass + masses[5], masses[7], spec.scene.gravity

    def energy(e):
        return (0.5 * m_k * (l_k * e.after["omega"]) ** 2
                + m_k * g * l_k * math.cos(e.after["theta"])
                + 0.5 * m_j * (l_j * e.after["palm_omega"]) ** 2
                + m_j * g * l_j * math.cos(e.after["palm_theta"]))
    assert 1e-4 * energy(push) < energy(push) - energy(part) < 0.05 * energy(push)
    # palm 8, parted, swings alone to its front stop: scipy's pendulum from the part state
    g, fs = spec.scene.gravity, spec.scene.palm.front_stop

    def at_stop(t, y):
        return y[0] - fs
    at_stop.terminal, at_stop.direction = True, 1
    sol = solve_ivp(lambda t, y: [y[1], g * math.sin(y[0]) / l_j], (part.time, part.time + 5.0),
                    [part.after["palm_theta"], part.after["palm_omega"]], method="DOP853",
                    rtol=1e-11, atol=1e-13, events=at_stop)
    stop = next(e for e in result.events if e.kind == "front_stop" and e.stage == 8
                and e.time > part.time)
    assert stop.time == pytest.approx(float(sol.t_events[0][0]), abs=1e-6)
    assert stop.before["omega"] == pytest.approx(float(sol.y_events[0][0][1]), rel=1e-6)
    # and the object later comes onto the palm it pushed
    onto = [e for e in result.events if e.kind == "landing" and e.after.get("palm") == 8
            and e.time > part.time]
    assert onto


@pytest.mark.slow  # 240 builds simulated: about 8 s
def test_the_map_leaves_every_build_whose_object_pushes_a_palm_to_the_simulator(rocking_skips):
    """The closed forms have no push: a build where the simulator logs one (the carried object
    against a palm's rear end) must be one the map hands over (closed_form False)."""
    from pdm_design.tolerances.yield_ import map_builds

    spec, design, tol = rocking_skips
    builds = 240
    mapped = map_builds(spec.scene, design, tol, builds, 8, 0)
    pushed = [i for i in range(builds)
              if any(e.kind == "push" for e in simulate_one(spec.scene, design, tol, 0, i, 8,
                                                            allow_skips=True).events)]
    assert len(pushed) >= 10  # (builds 67, 73, 79, 136, 140, ... of this seed)
    assert not mapped.closed_form[pushed].any()
    assert (mapped.failure[pushed] != "").any()  # the map's own account: most fail there


def test_the_sliding_push_starts_where_the_stuck_push_leaves_its_cone():
    """At the friction coefficient where the stuck push's palm-k force lies on its cone, the
    sliding push (five balances, pushslide.py) must have the object start from relative rest
    (s'' = 0) with the stuck push's accelerations and forces: two formulations, one state."""
    from scipy.optimize import brentq

    from pdm_design.scenes.manipulators.sim.phases import stuck_contact_force
    from pdm_design.scenes.manipulators.sim.pushslide import slide_push_accelerations

    th_k, om_k, th_j, om_j, sgn = 0.45, 1.5, -0.03, 1.45, -1.0
    l_k, l_j, m, M_k, m_j, g = 2.0, 2.0, 1.0, 0.1, 0.1, 9.81

    def stuck(mu):
        thdd_k, thdd_j, n = push_accelerations(
            th_k, om_k, th_j, om_j, acc_k=g * math.sin(th_k) / l_k,
            acc_j=g * math.sin(th_j) / l_j, l_k=l_k, l_j=l_j, m_k=m + M_k, m_j=m_j, mu=mu,
            sgn=sgn)
        fx, fn = stuck_contact_force(th_k, om_k, thdd_k, gravity=g, link_length=l_k)
        return thdd_k, thdd_j, n, m * fx + n, m * fn + sgn * mu * n

    mu = brentq(lambda c: abs(stuck(c)[3]) - c * stuck(c)[4], 0.05, 3.0, xtol=1e-14)
    thdd_k, thdd_j, n, fx, fn = stuck(mu)
    assert fn > 0.0 and n > 0.0
    got = slide_push_accelerations(
        (th_k, om_k, 0.1, 0.0, th_j, om_j), acc_k=g * math.sin(th_k) / l_k,
        acc_j=g * math.sin(th_j) / l_j, l_k=l_k, l_j=l_j, m=m, m_k=M_k, m_j=m_j, mu=mu, sgn=sgn,
        sgn_s=-math.copysign(1.0, fx), g=g)
    assert got[1] == pytest.approx(0.0, abs=1e-9)
    assert got[[0, 2, 3, 4]] == pytest.approx([thdd_k, thdd_j, fn, n], rel=1e-9)


def test_the_object_sliding_while_it_pushes_keeps_its_face_on_the_corner(rocking_skips):
    """Rocking-row build 180 (seed 0, skips allowed): palm 5's object pushes palm 7, slips on
    palm 5 while pushing, and palm 7 parts: from the slip to the part the face stays on the
    corner (l_5 sin th_5 + s - l_7 sin th_7 kept) and no energy is gained."""
    spec, design, tol = rocking_skips
    result = simulate_one(spec.scene, design, tol, 0, 180, 8, allow_skips=True)
    slip = next(e for e in result.events if e.kind == "slip" and "pushes palm 7" in e.detail)
    part = next(e for e in result.events if e.kind == "part")
    assert slip.time < part.time and "palm 7" in part.detail
    dev = one_build(tol, 0, 180, 8, scene=spec.scene)
    l_k, l_j = 2.0 + dev["link_length"][0][4], 2.0 + dev["link_length"][0][6]
    masses = spec.scene.body.mass / design.mass_ratio + dev["palm_mass"][0]
    M_k, M_j, m, g = masses[4], masses[6], spec.scene.body.mass, spec.scene.gravity

    def gap(e):
        return (l_k * math.sin(e.after["theta"]) + e.after["offset"]
                - l_j * math.sin(e.after["palm_theta"]))

    def energy(e):
        a = e.after
        return (0.5 * m * (a["vx"] ** 2 + a["vy"] ** 2) + m * g * l_k * math.cos(a["theta"])
                + 0.5 * M_k * (l_k * a["omega"]) ** 2 + M_k * g * l_k * math.cos(a["theta"])
                + 0.5 * M_j * (l_j * a["palm_omega"]) ** 2
                + M_j * g * l_j * math.cos(a["palm_theta"]))

    assert abs(part.after["offset"] - slip.after["offset"]) > 1e-6  # it has slid
    assert gap(part) == pytest.approx(gap(slip), abs=1e-6)
    assert energy(part) < energy(slip)


def test_a_second_push_while_the_first_pushed_palm_swings_is_followed(rocking_skips):
    """Rocking-row build 293 (seed 0, skips allowed): palm 4's object pushes palm 5, which
    parts and swings on; then pushes palm 6 and slips while pushing it, palm 5 carried along as
    a swinging palm; palm 6 parts and the carry goes on."""
    spec, design, tol = rocking_skips
    events = simulate_one(spec.scene, design, tol, 0, 293, 8, allow_skips=True).events
    kinds = [(e.kind, e.detail.split(" off")[0][-6:]) for e in events
             if e.kind in ("push", "part", "slip")]
    assert [k for k, _ in kinds] == ["push", "part", "push", "slip", "part"]
    assert "palm 5" in kinds[0][1] and "palm 6" in kinds[2][1]
