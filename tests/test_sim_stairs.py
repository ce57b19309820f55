"""The stairs event simulator against independent numbers.

Expected values come from the closed forms in pdm_design.scenes.stairs.physics, from formulas
derived by hand in this file (written out next to each test), or from brute-force sampling of the
ballistic path (an independent way to find contacts) - never from the simulator's own output.
"""

import math

import numpy as np
import pytest

from pdm_design.analysis import analyse
from pdm_design.scenes.common import StepError
from pdm_design.scenes.stairs import physics as phys
from pdm_design.scenes.stairs.model import Ball, StairsDesign, StairsInitial, StairsScene
from pdm_design.scenes.stairs.sim import (
    bounce_sequence,
    impact_map,
    simulate_stairs,
    stairs_geometry,
)

G = 9.81
H0 = 1.0
EPS = 0.8
BALL2 = dict(radius=0.5, mass=0.283, inertia=0.035)


def paper1(radius=0.05, **design):
    scene = StairsScene(initial=StairsInitial(drop_height=H0), ball=Ball(radius=radius))
    return scene, StairsDesign(restitution=design.pop("restitution", EPS),
                               launch_speed=design.pop("launch_speed", 2.0), **design)


def paper2(friction=0.5, spin=0.5, launch_speed=3.0, **design):
    scene = StairsScene(initial=StairsInitial(drop_height=H0, spin=spin),
                        ball=Ball(**BALL2), friction=friction)
    return scene, StairsDesign(restitution=design.pop("restitution", EPS),
                               launch_speed=launch_speed, **design)


def kinds(result):
    return [e.kind for e in result.events]


def failure_kind(result):
    return None if result.outcome.failure is None else result.outcome.failure.kind


def min_gap(cx, cy, vx, vy, px, py, r, t_end, n=400_001):
    """Smallest distance from a corner (px, py) to a ball of radius r whose centre starts at
    (cx, cy) with velocity (vx, vy), over [0, t_end], by dense sampling (independent method)."""
    t = np.linspace(0.0, t_end, n)
    return float(np.min(np.hypot(cx + vx * t - px, cy + vy * t - 0.5 * G * t * t - py)) - r)


# --- single drops and bounces ------------------------------------------------------------------

@pytest.mark.parametrize("h", [1e-4, 0.37, 1.0, 25.0])
@pytest.mark.parametrize("accuracy", ["fast", "default", "precise"])
def test_drop_from_h_lands_after_sqrt_2h_over_g(h, accuracy):
    scene = StairsScene(initial=StairsInitial(drop_height=h), ball=Ball(radius=0.01))
    result = simulate_stairs(scene, StairsDesign(restitution=0.5, launch_speed=1.0),
                             stages=1, accuracy=accuracy)
    first = result.stages[0]
    assert first["impact_time"] == pytest.approx(math.sqrt(2 * h / G), rel=1e-12)
    assert first["vy_before"] == pytest.approx(-math.sqrt(2 * G * h), rel=1e-12)
    assert first["step"] == 1


@pytest.mark.parametrize("eps", [0.4, 0.5, 0.8, 0.999])
def test_bounce_apex_is_eps_squared_h(eps):
    scene, design = paper1(restitution=eps)
    first = simulate_stairs(scene, design, stages=2).stages[0]
    assert first["apex_height"] == pytest.approx(eps**2 * H0, rel=1e-12)
    assert first["vy_after"] == pytest.approx(eps * math.sqrt(2 * G * H0), rel=1e-12)


def test_first_landing_is_at_the_designed_offset():
    scene, design = paper1(landing_offset=0.3)
    first = simulate_stairs(scene, design, stages=1).stages[0]
    assert first["landing_x"] == pytest.approx(0.3, abs=1e-12)


# --- paper example 1: frictionless, 1000 bounces -------------------------------------------------

def test_frictionless_paper_example_is_periodic_for_1000_bounces():
    scene, design = paper1()
    n = 1000
    result = simulate_stairs(scene, design, stages=n)
    assert result.outcome.completed and result.outcome.stages_passed == n
    speed = phys.periodic_impact_speed(2.0, G, H0)
    tread = phys.periodic_tread(2.0, G, H0, EPS)
    rise = phys.periodic_rise(H0, EPS)
    t1, period = math.sqrt(2 * H0 / G), phys.flight_time(G, H0, EPS)
    for i, stage in enumerate(result.stages):
        assert stage["step"] == i + 1
        assert stage["impact_speed"] == pytest.approx(speed, rel=1e-9)
        assert stage["landing_x"] == pytest.approx(tread / 2, rel=1e-9)
        assert stage["impact_time"] == pytest.approx(t1 + i * period, rel=1e-9)
        assert stage["y"] == pytest.approx(-i * rise, abs=1e-9 * (1 + i))
    # the paper's own numbers (section 4: h = 0.36 m, d = 1.626 m, rounded with g = 9.8)
    xs = [s["x"] for s in result.stages]
    assert np.diff(xs) == pytest.approx(np.full(n - 1, tread), rel=1e-9)
    assert tread == pytest.approx(1.626, abs=1e-3)


def test_paper_example_1_with_g_9_8_reproduces_the_printed_tread():
    scene = StairsScene(initial=StairsInitial(drop_height=H0), gravity=9.8)
    result = simulate_stairs(scene, StairsDesign(restitution=EPS, launch_speed=2.0), stages=3)
    assert result.stages[2]["x"] - result.stages[1]["x"] == pytest.approx(1.626, abs=5e-4)
    assert result.stages[1]["y"] - result.stages[2]["y"] == pytest.approx(0.36, abs=1e-12)


def test_event_log_uses_state_names_and_never_retriggers():
    scene, design = paper1()
    result = simulate_stairs(scene, design, stages=50)
    impacts = [e for e in result.events if e.kind == "impact"]
    assert len(impacts) == 50
    for e in impacts:
        assert set(e.before) == set(e.after) == {"x", "y", "vx", "vy", "omega"}
        assert e.before["vy"] < 0 < e.after["vy"]
    times = [e.time for e in impacts]
    assert min(np.diff(times)) == pytest.approx(phys.flight_time(G, H0, EPS), rel=1e-9)
    assert [e.stage for e in impacts] == list(range(1, 51))


# --- paper example 2: friction and spin -----------------------------------------------------------

def test_a_first_impact_that_slides_gives_the_analysis_the_simulators_staircase():
    # friction 0.02 cannot end the first impact in rolling: Coulomb takes its whole
    # mu (1 + eps) sqrt(2 g h0) off vx (against the slip vx + r w > 0), and r m / J times that
    # off the spin. The tread follows from that speed, in the analysis as in the simulator.
    scene, design = paper2(friction=0.02, spin=0.5, launch_speed=3.0)
    m, r, inertia = BALL2["mass"], BALL2["radius"], BALL2["inertia"]
    dv = 0.02 * 1.8 * math.sqrt(2 * G * H0)
    analysis = analyse(scene, design, 5)
    assert analysis.periodic["horizontal_speed"] == pytest.approx(3.0 - dv, rel=1e-12)
    assert analysis.periodic["spin"] == pytest.approx(0.5 - r * m * dv / inertia, rel=1e-12)
    assert any("cannot stop the ball slipping" in p for p in analysis.problems)
    built = stairs_geometry(scene, design)
    assert analysis.geometry["tread"] == pytest.approx(built.tread, rel=1e-12)
    first = simulate_stairs(scene, design, stages=2).stages[0]
    assert first["vx"] == pytest.approx(3.0 - dv, rel=1e-12) and first["slipped"]


def test_backspin_that_sends_the_ball_back_has_no_tread_to_judge():
    # Rolling after the first impact: vx1 = (m r^2 v0 - J r w0) / (m r^2 + J) (docs/physics.md)
    # = (0.283 * 0.25 * 1 - 0.035 * 0.5 * 10) / (0.283 * 0.25 + 0.035) < 0: back up the stairs.
    scene, design = paper2(friction=2.0, spin=10.0, launch_speed=1.0)
    m, r, inertia = BALL2["mass"], BALL2["radius"], BALL2["inertia"]
    vx1 = (m * r * r * 1.0 - inertia * r * 10.0) / (m * r * r + inertia)
    assert vx1 < 0.0
    analysis = analyse(scene, design, 5)
    assert analysis.geometry["tread"] is None and analysis.design["landing_offset"] is None
    assert set(analysis.margins) == {"first_impact_friction"}  # none divided by a tread < 0
    assert analysis.problems == (f"the ball moves at {vx1:g} m/s along the stairs after the "
                                 "first impact: it does not go down them",)
    with pytest.raises(ValueError, match="does not go down them"):
        stairs_geometry(scene, design)


def test_friction_paper_example_rolls_after_the_first_impact_for_1000_bounces():
    scene, design = paper2()
    n = 1000
    result = simulate_stairs(scene, design, stages=n)
    assert result.outcome.completed
    vx1, spin1 = phys.rolling_impact(3.0, 0.5, **BALL2)
    tread = phys.periodic_tread(vx1, G, H0, EPS)
    speed = phys.periodic_impact_speed(vx1, G, H0)
    first = result.stages[0]
    assert first["vx"] == pytest.approx(vx1, rel=1e-12)
    assert first["spin_after"] == pytest.approx(spin1, rel=1e-12)
    assert not first["slipped"]
    for stage in result.stages:
        assert stage["vx"] == pytest.approx(vx1, rel=1e-12)
        assert stage["spin_after"] == pytest.approx(-vx1 / 0.5, rel=1e-12)
        assert stage["landing_x"] == pytest.approx(tread / 2, rel=1e-9)
    for stage in result.stages[1:]:
        assert stage["impact_speed"] == pytest.approx(speed, rel=1e-9)
    assert "slip" not in kinds(result)
    # paper: d = 1.565 m (its rounding; docs/physics.md derives 1.5640 with g = 9.81)
    assert result.stages[2]["x"] - result.stages[1]["x"] == pytest.approx(1.565, abs=1.5e-3)


def test_energy_lost_at_each_periodic_impact_is_m_g_rise():
    scene, design = paper2()
    m, inertia = BALL2["mass"], BALL2["inertia"]
    rise = phys.periodic_rise(H0, EPS)
    result = simulate_stairs(scene, design, stages=200)

    def kinetic(vx, vy, spin):
        return 0.5 * m * (vx * vx + vy * vy) + 0.5 * inertia * spin * spin

    for stage in result.stages[1:]:
        lost = (kinetic(stage["vx_before"], stage["vy_before"], stage["spin_before"])
                - kinetic(stage["vx"], stage["vy_after"], stage["spin_after"]))
        assert lost == pytest.approx(m * G * rise, rel=1e-9)
    # between equivalent states (just before impacts n and n+1) the energy is the same:
    # the potential energy m g rise given back by gravity equals the impact loss
    a, b = result.stages[5], result.stages[6]
    ea = kinetic(a["vx_before"], a["vy_before"], a["spin_before"]) + m * G * a["y"]
    eb = kinetic(b["vx_before"], b["vy_before"], b["spin_before"]) + m * G * b["y"]
    assert ea - eb == pytest.approx(m * G * rise, rel=1e-9)


def test_first_friction_impact_loses_normal_and_sticking_energy():
    # Hand derivation: a sticking impact dissipates 1/2 m_eff c^2 tangentially, with the
    # effective mass m_eff = m J / (J + m r^2) at the contact and c = vx + r omega the slip;
    # the normal part loses 1/2 m (1 - eps^2) vy^2.
    scene, design = paper2()
    m, inertia, r = BALL2["mass"], BALL2["inertia"], BALL2["radius"]
    first = simulate_stairs(scene, design, stages=1).stages[0]
    vy = math.sqrt(2 * G * H0)
    c = 3.0 + r * 0.5
    expected = 0.5 * m * (1 - EPS**2) * vy**2 + 0.5 * (m * inertia / (inertia + m * r * r)) * c**2
    before = 0.5 * m * (9.0 + vy**2) + 0.5 * inertia * 0.25
    after = 0.5 * m * (first["vx"] ** 2 + first["vy_after"] ** 2) \
        + 0.5 * inertia * first["spin_after"] ** 2
    assert before - after == pytest.approx(expected, rel=1e-12)


def test_insufficient_friction_slides_through_the_first_impact():
    mu = 0.05
    scene, design = paper2(friction=mu)
    result = simulate_stairs(scene, design, stages=1)
    first = result.stages[0]
    vy = math.sqrt(2 * G * H0)
    r, m, inertia = BALL2["radius"], BALL2["mass"], BALL2["inertia"]
    # slip c = 3 + 0.5 * 0.5 > 0, so friction pushes back with mu Pn, Pn = m (1 + eps) vy
    impulse = -mu * m * (1 + EPS) * vy
    assert first["slipped"]
    assert first["vx"] == pytest.approx(3.0 + impulse / m, rel=1e-12)
    assert first["spin_after"] == pytest.approx(0.5 + r * impulse / inertia, rel=1e-12)
    demand = phys.rolling_impulse_ratio(3.0, 0.5, -vy, EPS, **BALL2)
    assert first["friction_demand"] == pytest.approx(demand, rel=1e-12)
    slip = [e for e in result.events if e.kind == "slip"]
    assert len(slip) == 1 and not slip[0].failure
    assert result.outcome.completed


def test_friction_just_enough_rolls_and_just_too_little_slides():
    vy = math.sqrt(2 * G * H0)
    demand = phys.rolling_impulse_ratio(3.0, 0.5, -vy, EPS, **BALL2)
    rolls = simulate_stairs(*paper2(friction=demand * (1 + 1e-9)), stages=1).stages[0]
    slides = simulate_stairs(*paper2(friction=demand * (1 - 1e-6)), stages=1).stages[0]
    assert not rolls["slipped"] and slides["slipped"]
    assert slides["vx"] == pytest.approx(rolls["vx"], rel=1e-5)  # continuous at the boundary


# --- vectorised impact map ------------------------------------------------------------------------

def test_impact_map_matches_closed_forms_on_arrays():
    rng = np.random.default_rng(1)
    n = 2000
    vx, vy, spin = rng.uniform(-3, 3, n), -rng.uniform(0.5, 6, n), rng.uniform(-20, 20, n)
    mu, r, m, inertia = 0.3, 0.5, 0.283, 0.035
    out = impact_map(vx, vy, spin, EPS, mu, r, m, inertia)
    demand = phys.rolling_impulse_ratio(vx, spin, vy, EPS, radius=r, mass=m, inertia=inertia)
    roll_vx, roll_spin = phys.rolling_impact(vx, spin, radius=r, mass=m, inertia=inertia)
    rolls = demand <= mu
    assert 100 < rolls.sum() < n - 100  # both branches exercised
    np.testing.assert_array_equal(out.slipped, ~rolls)
    np.testing.assert_allclose(out.vx[rolls], roll_vx[rolls], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(out.omega[rolls], roll_spin[rolls], rtol=1e-12, atol=1e-12)
    impulse = -np.sign(vx + r * spin) * mu * m * (1 + EPS) * np.abs(vy)
    np.testing.assert_allclose(out.vx[~rolls], (vx + impulse / m)[~rolls], rtol=1e-12)
    np.testing.assert_allclose(out.omega[~rolls], (spin + r * impulse / inertia)[~rolls],
                               rtol=1e-12)
    np.testing.assert_allclose(out.vy, -EPS * vy, rtol=1e-15)


def test_impact_map_frictionless_and_zero_inertia():
    vx, vy, spin = np.array([2.0, -1.0]), np.array([-3.0, -4.0]), np.array([5.0, 0.0])
    out = impact_map(vx, vy, spin, 0.5, 0.0, 0.1, 1.0, 0.01)
    np.testing.assert_array_equal(out.vx, vx)
    np.testing.assert_array_equal(out.omega, spin)
    # J = 0 with friction: the spin follows the rolling condition at once, vx unchanged
    out = impact_map(vx, vy, spin, 0.5, 0.7, 0.1, 1.0, 0.0)
    np.testing.assert_array_equal(out.vx, vx)
    np.testing.assert_allclose(out.omega, -vx / 0.1)
    assert not out.slipped.any()


# --- step errors ----------------------------------------------------------------------------------

def _periodic_leave(radius=0.05):
    """Ball leaving a tread of paper example 1: (landing offset, vx, vy up, tread, rise)."""
    tread = phys.periodic_tread(2.0, G, H0, EPS)
    return tread / 2, 2.0, EPS * math.sqrt(2 * G * H0), tread, phys.periodic_rise(H0, EPS)


def test_tread_error_shifts_every_later_landing_back_by_the_error():
    scene, design = paper1()
    delta = 0.3
    result = simulate_stairs(scene, design, stages=8, step_errors=[StepError(step=3, tread=delta)])
    assert result.outcome.completed
    landing = [s["landing_x"] for s in result.stages]
    half = phys.periodic_tread(2.0, G, H0, EPS) / 2
    assert landing[:3] == pytest.approx([half] * 3, rel=1e-9)      # step 3's back did not move
    assert landing[3:] == pytest.approx([half - delta] * 5, rel=1e-9)  # neutral: never recovers


def test_rise_error_moves_the_landing_on_that_step_by_the_extra_fall():
    scene, design = paper1()
    d_rise = 0.1
    result = simulate_stairs(scene, design, stages=4, step_errors=[StepError(step=3, rise=d_rise)])
    s, vx, up, tread, rise = _periodic_leave()
    t = (up + math.sqrt(up**2 + 2 * G * (rise + d_rise))) / G
    assert result.stages[2]["landing_x"] == pytest.approx(s + vx * t - tread, rel=1e-9)
    assert result.stages[2]["vy_before"] == pytest.approx(
        -math.sqrt(up**2 + 2 * G * (rise + d_rise)), rel=1e-12)


def test_long_tread_makes_the_ball_land_twice_on_that_step():
    # Leaving tread 3 at s, the ball is back at tread height after 2 up/g, at s + vx 2 up/g from
    # the tread's back. A nose beyond that point: it comes down on the same step.
    s, vx, up, tread, _ = _periodic_leave()
    x_same = s + vx * 2 * up / G
    delta = x_same - tread + 0.01
    result = simulate_stairs(*paper1(), stages=6, step_errors=[StepError(step=3, tread=delta)])
    f = result.outcome.failure
    assert (f.kind, f.after["step"], f.failure) == ("double_landing", 3, True)
    assert result.outcome.stages_passed == 3 and not result.outcome.completed
    assert f.before["x"] - result.stages[2]["x"] == pytest.approx(x_same - s, rel=1e-9)


@pytest.mark.parametrize("short, hit", [(0.005, True), (0.02, True), (0.04, False)])
def test_nose_just_short_of_the_same_height_return_is_hit(short, hit):
    s, vx, up, tread, rise = _periodic_leave()
    r = 0.05
    x_same = s + vx * 2 * up / G
    nose = x_same - short
    t_land = (up + math.sqrt(up**2 + 2 * G * rise)) / G
    gap = min_gap(s, r, vx, up, nose, 0.0, r, t_land)    # independent: touch iff gap < 0
    assert (gap < -1e-4) if hit else (gap > 1e-4)
    result = simulate_stairs(*paper1(radius=r), stages=6,
                             step_errors=[StepError(step=3, tread=nose - tread)])
    if hit:
        assert failure_kind(result) == "nose_hit" and result.outcome.failure.after["step"] == 3
    else:
        assert result.outcome.completed
        # it travels one periodic tread from s on tread 3; tread 4 starts at the moved nose
        assert result.stages[3]["landing_x"] == pytest.approx(s + tread - nose, rel=1e-9)


def test_short_tread_is_skipped():
    # Tread 3 shorter than the landing offset: the ball passes its nose and falls one more rise;
    # the nose is cleared when the sampled gap is positive, so the failure is skipped_step.
    s, vx, up, tread, rise = _periodic_leave()
    r, delta = 0.05, -1.0
    down = math.sqrt(2 * G * H0)
    t_extra = (-down + math.sqrt(down**2 + 2 * G * rise)) / G
    x = s + vx * t_extra                      # from tread 3's back, level of tread 4
    short_tread = tread + delta
    fall = (down + math.sqrt(down**2 + 2 * G * rise)) / G
    # independent clearance check of nose 3 (at (short_tread, 0) from tread 3's back)
    t0 = -0.3                                 # start well before, over tread 3 going down
    cy0 = r - down * t0 - 0.5 * G * t0 * t0
    assert min_gap(s + vx * t0, cy0, vx, -down - G * t0, short_tread, 0.0, r, fall - t0) > 1e-3
    result = simulate_stairs(*paper1(radius=r), stages=6,
                             step_errors=[StepError(step=3, tread=delta)])
    f = result.outcome.failure
    assert (f.kind, f.after["step"]) == ("skipped_step", 4)
    assert f.before["x"] - result.stages[1]["x"] == pytest.approx(tread + x - s, rel=1e-9)


def test_nose_hits_agree_with_sampled_distances():
    """Randomised: the simulator's nose_hit / double_landing / pass against brute force."""
    rng = np.random.default_rng(7)
    s, vx, up, tread, rise = _periodic_leave()
    r = 0.05
    x_same = s + vx * 2 * up / G
    t_land = (up + math.sqrt(up**2 + 2 * G * rise)) / G
    checked = {"nose_hit": 0, "double_landing": 0, None: 0}
    for nose in rng.uniform(x_same - 0.08, x_same + 0.02, 40):
        if nose >= x_same:
            expected = "double_landing"
        else:
            gap = min_gap(s, r, vx, up, nose, 0.0, r, t_land)
            if abs(gap) < 1e-5:
                continue
            expected = "nose_hit" if gap < 0 else None
        result = simulate_stairs(*paper1(radius=r), stages=5,
                                 step_errors=[StepError(step=3, tread=nose - tread)])
        assert failure_kind(result) == expected, nose
        checked[expected] += 1
    assert min(checked.values()) >= 3


# --- regimes at the edges -------------------------------------------------------------------------

def test_restitution_one_on_flat_stairs_bounces_forever_at_constant_apex():
    scene, design = paper1(radius=0.0, restitution=1.0, rise=0.0)
    result = simulate_stairs(scene, design, stages=1000)
    assert result.outcome.completed
    v = math.sqrt(2 * G * H0)
    for stage in result.stages:
        assert stage["apex_height"] == pytest.approx(H0, rel=1e-12)
        assert stage["impact_speed"] == pytest.approx(math.hypot(2.0, v), rel=1e-12)
        assert stage["y"] == 0.0
        assert stage["landing_x"] == pytest.approx(2.0 * 2 * v / G / 2, rel=1e-9)


@pytest.mark.parametrize("eps, lands_twice", [(0.2, True), (0.3, True), (0.36, False),
                                              (0.5, False)])
def test_mid_tread_landing_needs_restitution_above_one_third(eps, lands_twice):
    # Landing at tread/2, the same-height return is tread (1/2 + 2 eps / (1 + eps)) from the
    # back (tread = vx (1 + eps) v / g, return after 2 eps v / g): past the nose iff eps > 1/3.
    # The launch is the apex of such a bounce from the top landing (step 0), so with
    # eps < 1/3 the ball already comes down on the top landing, at V0 eps v / g from the launch.
    scene, design = paper1(radius=0.0, restitution=eps)
    result = simulate_stairs(scene, design, stages=3)
    if lands_twice:
        f = result.outcome.failure
        assert (f.kind, f.after["step"]) == ("double_landing", 0)
        v = math.sqrt(2 * G * H0)
        assert f.before["x"] == pytest.approx(2.0 * eps * v / G, rel=1e-12)
    else:
        assert result.outcome.completed


def test_restitution_zero_stops_bouncing():
    scene = StairsScene(initial=StairsInitial(drop_height=H0))
    design = StairsDesign(restitution=0.0, launch_speed=2.0, rise=0.3, tread=1.0,
                          landing_offset=0.5)
    result = simulate_stairs(scene, design, stages=2)
    assert result.outcome.stages_passed == 1
    assert result.stages[0]["landing_x"] == pytest.approx(0.5, abs=1e-12)
    assert failure_kind(result) == "no_rebound" and result.outcome.failure.after["step"] == 1


def test_backspin_drives_the_ball_into_the_riser_behind():
    # Rolling impact with strong backspin reverses vx (phys.rolling_impact). With a riser 2 m
    # tall behind tread 1, the ball's centre reaches x_back + r at t = (s - r) / |vx| while
    # still below the top of the riser: riser_hit on step 1 at t1 + t.
    scene = StairsScene(initial=StairsInitial(drop_height=3.0, spin=20.0), ball=Ball(**BALL2),
                        friction=0.5)
    design = StairsDesign(restitution=EPS, launch_speed=1.0, rise=2.0, tread=1.6,
                          landing_offset=0.8)
    result = simulate_stairs(scene, design, stages=3)
    vx, _ = phys.rolling_impact(1.0, 20.0, **BALL2)
    assert vx < 0
    up = EPS * math.sqrt(2 * G * 3.0)
    t = (0.8 - 0.5) / -vx
    assert 0.5 + up * t - 0.5 * G * t * t < 2.0
    f = result.outcome.failure
    assert (f.kind, f.after["step"]) == ("riser_hit", 1)
    assert f.time == pytest.approx(math.sqrt(2 * 3.0 / G) + t, rel=1e-12)


def test_backspin_over_a_low_riser_lands_on_the_top_landing():
    # Solid-sphere-like ball, backspin sending it back at vx = -2 m/s (rolling formula): it
    # clears the 5 cm riser and comes down on step 0, the top landing.
    r, m = 0.05, 1.0
    inertia = 0.4 * m * r * r
    spin = 9.5 / r                            # (1 - 0.4 r spin) / 1.4 = -2
    scene = StairsScene(initial=StairsInitial(drop_height=H0, spin=spin),
                        ball=Ball(radius=r, mass=m, inertia=inertia), friction=1.0)
    design = StairsDesign(restitution=EPS, launch_speed=1.0, rise=0.05, tread=1.6,
                          landing_offset=0.8)
    result = simulate_stairs(scene, design, stages=3)
    assert result.stages[0]["vx"] == pytest.approx(-2.0, rel=1e-12)
    up = EPS * math.sqrt(2 * G * H0)
    t = (up + math.sqrt(up**2 - 2 * G * 0.05)) / G
    f = result.outcome.failure
    assert (f.kind, f.after["step"]) == ("bounced_back", 0)
    assert f.before["x"] - result.stages[0]["x"] == pytest.approx(-2.0 * t, rel=1e-9)


def test_launch_inside_the_stairs_is_refused():
    scene = StairsScene(initial=StairsInitial(drop_height=0.2))
    design = StairsDesign(restitution=EPS, launch_speed=2.0, rise=0.5, tread=1.0,
                          landing_offset=0.1)
    with pytest.raises(ValueError, match="starts"):
        simulate_stairs(scene, design, stages=1)


@pytest.mark.parametrize("past", [0.02, 0.04])
def test_a_slow_launch_just_past_the_top_nose_comes_down_on_its_corner(past):
    # The ball starts with its lowest point at the top landing's level (rise = h0), its centre
    # `past` beyond that landing's nose, moving away at 5 cm/s. It falls r (time sqrt(2 r / g))
    # to bring its centre to the corner's level, by then past + v0 sqrt(2 r / g) < r from it:
    # it must touch the corner behind it on the way down.
    r, v0 = 0.05, 0.05
    assert past + v0 * math.sqrt(2 * r / G) < r
    scene, design = paper1(radius=r, launch_speed=v0, rise=H0, tread=1.0,
                           landing_offset=v0 * math.sqrt(2 * H0 / G) + past)
    failure = simulate_stairs(scene, design, stages=3).outcome.failure
    assert failure is not None and (failure.kind, failure.after["step"]) == ("nose_hit", 0)


def test_geometry_matches_the_closed_forms():
    geo = stairs_geometry(*paper2())
    vx1, _ = phys.rolling_impact(3.0, 0.5, **BALL2)
    assert geo.tread == pytest.approx(phys.periodic_tread(vx1, G, H0, EPS), rel=1e-12)
    assert geo.rise == pytest.approx(phys.periodic_rise(H0, EPS), rel=1e-12)
    assert geo.landing_offset == pytest.approx(geo.tread / 2, rel=1e-12)


# --- long runs ------------------------------------------------------------------------------------

def test_long_runs_keep_a_bounded_record_and_a_summary():
    scene, design = paper1()
    n = 2500
    result = simulate_stairs(scene, design, stages=n, record_limit=100)
    assert result.outcome.completed
    assert len(result.stages) == 101 and len(result.events) == 101
    assert result.stages[-1]["step"] == n
    summary = result.summary
    half = phys.periodic_tread(2.0, G, H0, EPS) / 2
    assert summary["bounces"] == n and summary["records_kept"] == len(result.stages)
    assert summary["landing_x_min"] == pytest.approx(half, rel=1e-9)
    assert summary["landing_x_max"] == pytest.approx(half, rel=1e-9)


def test_a_failure_beyond_the_record_limit_keeps_the_impact_before_it():
    s, vx, up, tread, _ = _periodic_leave()
    delta = s + vx * 2 * up / G - tread + 0.01      # lands twice on step 300 (see above)
    result = simulate_stairs(*paper1(), stages=500, record_limit=50,
                             step_errors=[StepError(step=300, tread=delta)])
    f = result.outcome.failure
    assert (f.kind, f.after["step"], result.outcome.stages_passed) == ("double_landing", 300, 300)
    assert [st["step"] for st in result.stages[-2:]] == [50, 300]
    assert [e.kind for e in result.events[-2:]] == ["impact", "double_landing"]


@pytest.mark.slow
def test_a_million_event_located_bounces_do_not_drift():
    # Tolerance: the landing offset is neutrally stable, so rounding walks it by at most a few
    # ulp(tread) ~ 1e-15 m per bounce: 1e-8 m after 1e6 bounces leaves a factor > 10.
    scene, design = paper1()
    n = 10**6
    result = simulate_stairs(scene, design, stages=n)
    assert result.outcome.completed and len(result.stages) <= 10_001
    half = phys.periodic_tread(2.0, G, H0, EPS) / 2
    assert abs(result.summary["landing_x_min"] - half) < 1e-8
    assert abs(result.summary["landing_x_max"] - half) < 1e-8
    last = result.stages[-1]
    assert last["impact_time"] == pytest.approx(
        math.sqrt(2 * H0 / G) + (n - 1) * phys.flight_time(G, H0, EPS), rel=1e-12)


def _periodic_start(friction):
    v = math.sqrt(2 * G * H0)
    if friction:
        vx, _ = phys.rolling_impact(3.0, 0.5, **BALL2)
        return dict(vx=vx, omega=-vx / BALL2["radius"], vy=-v, mu=0.5, r=BALL2["radius"],
                    m=BALL2["mass"], J=BALL2["inertia"])
    return dict(vx=2.0, omega=0.0, vy=-v, mu=0.0, r=0.05, m=1.0, J=0.0)


def _run_sequence(friction, bounces, samples=3):
    p = _periodic_start(friction)
    tread = phys.periodic_tread(p["vx"], G, H0, EPS)
    out = bounce_sequence(np.full(samples, tread / 2), p["vx"], p["vy"], p["omega"],
                          bounces=bounces, rise=phys.periodic_rise(H0, EPS), tread=tread,
                          eps=EPS, mu=p["mu"], r=p["r"], m=p["m"], J=p["J"], g=G)
    return out, p, tread


@pytest.mark.parametrize("friction", [False, True])
def test_vectorised_bounces_stay_on_the_closed_form_orbit(friction):
    n = 20_000
    out, p, tread = _run_sequence(friction, n)
    assert (out.failure == 0).all() and (out.bounces == n).all()
    assert np.abs(out.landing_max - tread / 2).max() < 1e-10
    assert np.abs(out.landing_min - tread / 2).max() < 1e-10
    np.testing.assert_allclose(out.vx, p["vx"], rtol=1e-12)
    np.testing.assert_allclose(out.vy, p["vy"], rtol=1e-12)
    np.testing.assert_allclose(out.time, n * phys.flight_time(G, H0, EPS), rtol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("friction", [False, True])
def test_a_million_vectorised_bounces_do_not_drift(friction):
    # Same tolerance argument as the event-located run: <= 1e-8 m of landing drift.
    n = 10**6
    out, p, tread = _run_sequence(friction, n, samples=2)
    assert (out.failure == 0).all()
    assert np.abs(out.landing_max - tread / 2).max() < 1e-8
    assert np.abs(out.landing_min - tread / 2).max() < 1e-8
    np.testing.assert_allclose(out.vx, p["vx"], rtol=1e-12)
    np.testing.assert_allclose(out.time, n * phys.flight_time(G, H0, EPS), rtol=1e-12)


@pytest.mark.parametrize("friction", [False, True])
def test_vectorised_failures_agree_with_sampling_and_the_event_simulator(friction):
    """Landing offsets across the tread: double landing / nose hit / clean bounce, decided three
    ways (brute-force distance sampling, bounce_sequence, simulate_stairs with a tread error on
    step 2 that puts the landing on step 3 at the same offset)."""
    p = _periodic_start(friction)
    r, vx = p["r"], p["vx"]
    up = EPS * math.sqrt(2 * G * H0)
    tread = phys.periodic_tread(vx, G, H0, EPS)
    rise = phys.periodic_rise(H0, EPS)
    t_land = (up + math.sqrt(up**2 + 2 * G * rise)) / G
    rng = np.random.default_rng(3)
    x_return = vx * 2 * up / G                     # same-height return, from the take-off point
    offsets = np.concatenate([rng.uniform(tread - x_return - 0.05, tread - x_return + r, 30),
                              rng.uniform(0.3 * tread, 0.9 * tread, 5)])
    expected = []
    for s in offsets:
        if s + x_return <= tread:
            expected.append("double_landing")
            continue
        gap = min_gap(s, r, vx, up, tread, 0.0, r, t_land)
        expected.append(None if abs(gap) < 1e-5 else ("nose_hit" if gap < 0 else ""))
    out = bounce_sequence(offsets, vx, p["vy"], p["omega"], bounces=3, rise=rise, tread=tread,
                          eps=EPS, mu=p["mu"], r=r, m=p["m"], J=p["J"], g=G)
    scene, design = paper2() if friction else paper1(radius=r)
    half = tread / 2
    counts = {}
    for s, want, got in zip(offsets, expected, out.failure_kinds()):
        if want is None:
            continue                               # a graze within sampling resolution
        assert got == want, s
        counts[want] = counts.get(want, 0) + 1
        # tread 2 longer by half - s: leaving it at half, its nose is tread - s ahead - the same
        # flight as leaving a uniform tread at s; if that is clean, every later one is too
        result = simulate_stairs(scene, design, stages=6,
                                 step_errors=[StepError(step=2, tread=half - s)])
        assert (failure_kind(result) or "") == want
        if want:
            assert result.outcome.failure.after["step"] == 2
        else:
            assert result.stages[2]["landing_x"] == pytest.approx(s, abs=1e-9)
    assert len(counts) == 3


# --- plots ----------------------------------------------------------------------------------------

def test_plot_writes_a_png(tmp_path):
    from pdm_design.scenes.stairs.sim.plot import plot_stairs_run

    result = simulate_stairs(*paper2(), stages=5, record_trajectory=True)
    assert len(result.trajectory["time"]) > 100
    path = plot_stairs_run(result, tmp_path / "run.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
