"""The real-link carry's contact rows over the whole carry (docs/physics.md section 2.1, "Over
the whole carry"): the curvature bound S of the palm's force along a closed-form carry against
finite differences, and the NLP's rows against the event simulator's own carry (its Lagrangian
swing integrated, the palm's force on the stuck object sampled densely): on a design whose
tip margin dips inside the carry, which the rows at the carry's ends accepted, the simulator
tips there, the new rows refuse it, and their least value is within the cells' allowance
below the simulator's least (never above it)."""

import math
import tomllib

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pdm_design.scenes.manipulators import physics as phys
from pdm_design.scenes.manipulators.formulation import _Model, rows
from pdm_design.scenes.manipulators.sim.phases import Swing, stuck_contact_force, swing_acceleration
from pdm_design.spec.loader import parse_spec

G = 9.81
# m = 1 kg, M = 0.1 kg, two 0.12 kg rods of 2 m, 1.6 N m of pivot friction, a tall object
# (0.18 x 0.4 m) on mu = 0.75; the object starts just above palm 1 moving as a periodic
# handover does, so every carry is the periodic one: the force crosses the base furthest
# behind its centre near th = 0.55 rad, between the back stop (-0.114) and the handover (0.766)
DIP = """
name = "carry_inside"
[scene]
kind = "manipulators"
gravity = 9.81
[scene.body]
mass = 1.0
width = 0.18
height = 0.4
[scene.palm]
width = 1.6
thickness = 0.05
friction = 0.75
restitution = 0.0
front_stop = 1.5707963
[scene.links]
mass = 0.12
count = 2
[scene.pivots]
friction_torque = 1.6
[initial]
position = [-0.227506, 1.992018]
velocity = [2.522914, -2.426885]
[design]
alpha = 0.114
beta = 0.766
link_length = 2.0
mass_ratio = 10.0
[verification]
stages = 3
"""


def _rows(spec):
    """{key: [(where, slack / scale)]} of the NLP's rows at the spec's fixed design (the speed
    interval from the first landing to the periodic one, as the NLP starts it), and the model."""
    vals = dict(spec.design, first_pivot_x=0.0, first_pivot_y=0.0)
    m = _Model(spec.scene, vals, spec.verification.stages, 0)
    S, u_lo, u_hi = (float(ca.DM(x)) for x in m.aux_start())
    out = {}
    for c in rows.conditions(m, S, u_lo, u_hi, {}, False):
        for k in c.keys:
            out.setdefault(k, []).append((c.where, float(ca.evalf(ca.SX(c.slack) / c.scale))))
    return out, m, (u_lo, u_hi)


def _simulated_carry(m, u):
    """(th, friction, normal) per object mass along the simulator's stuck swing (its
    Lagrangian, phases.swing_acceleration) from the back stop at speed u to beta, densely."""
    scene = m.scene
    link = scene.links.mass * scene.links.count
    obj, palm = scene.body.mass, scene.body.mass / m.mass_ratio
    sw = Swing(inertia=obj + palm + link / 3, weight=obj + palm + link / 2,
               torque=scene.pivots.friction_torque, damping=0.0, gravity=G, link_length=m.l)

    def rhs(t, y):
        return [y[1], swing_acceleration(y[0], y[1], sw, direction=1.0)]

    def reach(t, y):
        return y[0] - m.b
    reach.terminal = True
    sol = solve_ivp(rhs, (0.0, 10.0), [-m.a, u / m.l], events=reach, dense_output=True,
                    rtol=1e-11, atol=1e-13)
    out = []
    for t in np.linspace(0.0, sol.t[-1], 4001):
        th, om = sol.sol(t)
        out.append((th, *stuck_contact_force(th, om, swing_acceleration(th, om, sw, 1.0),
                                             gravity=G, link_length=m.l)))
    return np.array(out)


@pytest.mark.parametrize("seed", range(3))
def test_curvature_bound_holds_along_random_carries(seed):
    rng = np.random.default_rng(seed)
    for _ in range(200):
        l = float(rng.uniform(0.05, 5.0))
        g_e, f = float(rng.uniform(0.3, 1.6)) * G, float(rng.uniform(0.0, 0.3)) * G * l
        a, b = float(rng.uniform(0.0, 0.8)), float(rng.uniform(0.0, 1.3))
        u = float(rng.uniform(0.0, 3.0)) * math.sqrt(G * l)
        bound = phys.carry_contact_curvature(carry_gravity=g_e, fastest_u2=u * u, friction=f,
                                             link_length=l, span=a + b)
        th = np.linspace(-a, b, 4001)
        F, N = phys.carry_contact_at(th, u, a, gravity=G, carry_gravity=g_e, friction=f,
                                     link_length=l)
        h = th[1] - th[0]
        for values in (N, F):
            assert np.abs(np.diff(values, 2)).max() / h**2 <= bound


def test_cell_bound_is_exact_where_steep_and_below_the_function():
    # r = -S t^2 / 2 + c t on [0, 1]: the least of ra + D x - bend x (1 - x) is its own least
    for S, c in ((2.0, 0.3), (2.0, 5.0), (0.5, -3.0)):
        t = np.linspace(0.0, 1.0, 10001)
        r = -S * t**2 / 2 + c * t  # |r''| = S
        least = float(rows.cell_least(r[0], r[-1], S / 2))
        assert least <= r.min() + 1e-12
        if abs(r[-1] - r[0]) > S / 2:
            assert least == pytest.approx(min(r[0], r[-1]), abs=1e-12)


@pytest.fixture(scope="module")
def dip():
    spec = parse_spec(tomllib.loads(DIP))
    out, m, speeds = _rows(spec)
    return spec, out, m, speeds


def test_simulator_tips_inside_the_carry(dip):
    from pdm_design.scenes.manipulators.sim import simulate_manipulators

    spec, *_ = dip
    run = simulate_manipulators(spec.scene, _design(spec), stages=3)
    # the onset of tipping, well inside the carry (the object rocks from there)
    onset = next(e for e in run.events if e.kind == "rock")
    assert -0.114 + 0.2 < onset.before["theta"] < 0.766 - 0.1
    # the tall object (0.18 x 0.4 m) comes down on palm 2, turns over onto its side there (at
    # pi/2 about its base corner) and is carried on lying on it, to the end of the row
    roll = next(e for e in run.events if e.kind == "roll")
    assert roll.before["phi"] == pytest.approx(math.pi / 2, abs=1e-9) and roll.stage == 2
    assert run.outcome.completed


def _design(spec):
    from pdm_design.scenes.manipulators.model import ManipulatorsDesign

    return ManipulatorsDesign(**spec.design)


def test_ends_accept_and_the_whole_carry_refuses(dip):
    _, out, _, _ = dip
    for key in ("lift_off", "slip_carry", "tip_carry"):
        ends = [v for w, v in out[key] if "during the carry" not in w]
        assert min(ends) > 0.1, key  # the rows at the carry's ends accepted it
    inside = [v for w, v in out["tip_carry"] if "during the carry" in w]
    assert min(inside) < -0.05
    # and every other row holds (the design is feasible for the rows at the carry's ends)
    assert min(v for k, rs in out.items() for w, v in rs if "during the carry" not in w) > 0.0


@pytest.mark.parametrize("edge, sign", [("object's front edge", 1.0),
                                        ("object's rear edge", -1.0)])
def test_rows_agree_with_the_simulators_carry(dip, edge, sign):
    """The least tip row over the carry's cells (slack / scale: (d N +- (h/2) F) / (d g), d =
    w / 2) against the simulator's carry sampled at 4001 points: never above it (sound), and
    below it by at most the cells' allowance (d + h/2) S h_cell^2 / 8 / (d g)."""
    spec, out, m, (u_lo, u_hi) = dip
    d, half_h = spec.scene.body.width / 2, spec.scene.body.height / 2
    rows_least = min(v for w, v in out["tip_carry"] if "during the carry" in w and edge in w)
    sim_least = math.inf
    for u in (u_lo, u_hi):
        carry = _simulated_carry(m, u)
        sim_least = min(sim_least, float(np.min((d * carry[:, 2] + sign * half_h * carry[:, 1])
                                                / (d * G))))
    S = phys.carry_contact_curvature(carry_gravity=m.gc, fastest_u2=u_hi**2, friction=m.f,
                                     link_length=m.l, span=m.a + m.b)
    allowance = (d + half_h) * S * ((m.a + m.b) / rows.CARRY_CELLS) ** 2 / 8 / (d * G)
    assert rows_least <= sim_least + 1e-9
    assert rows_least >= sim_least - allowance
    if sign < 0:  # the dip: the simulator's own margin is negative inside
        assert sim_least < -0.03


def test_lift_off_and_slip_agree_with_the_simulators_carry(dip):
    spec, out, m, (u_lo, u_hi) = dip
    mu = spec.scene.palm.friction
    S = phys.carry_contact_curvature(carry_gravity=m.gc, fastest_u2=u_hi**2, friction=m.f,
                                     link_length=m.l, span=m.a + m.b)
    cell2 = ((m.a + m.b) / rows.CARRY_CELLS) ** 2 / 8
    carries = [_simulated_carry(m, u) for u in (u_lo, u_hi)]
    lift = min(float(np.min(c[:, 2])) for c in carries[1:]) / G
    rows_lift = min(v for w, v in out["lift_off"] if "during the carry" in w)
    assert lift - S * cell2 / G <= rows_lift <= lift + 1e-9
    for what, sign in (("sliding back", -1.0), ("sliding forward", 1.0)):
        sim = min(float(np.min(mu * c[:, 2] + sign * c[:, 1])) for c in carries) / (mu * G)
        least = min(v for w, v in out["slip_carry"] if "during the carry" in w and what in w)
        assert sim - (mu + 1) * S * cell2 / (mu * G) <= least <= sim + 1e-9


def test_analysis_and_stage_maps_flag_the_dip(dip):
    """The analysis' margins, the streamed stage maps (formulation/offsets.py) and the builds'
    map (tolerances.py) judge the carry with the NLP's whole-carry rows: the dip the ends
    accepted is a negative tip margin in each (the simulator tips the object on palm 1)."""
    from pdm_design.formulation import formulate
    from pdm_design.scenes.manipulators.analysis import analyse_manipulators
    from pdm_design.scenes.manipulators.tolerances import run_builds

    spec, out, _, _ = dip
    margins = analyse_manipulators(spec.scene, _design(spec), 3).margins
    # the NLP's rows at the periodic carry (its speed interval's ends hold the first landing,
    # almost periodic here): the same least, at the same cell
    nlp_least = min(v for w, v in out["tip_carry"] if "during the carry" in w)
    assert margins["tip_carry"] == pytest.approx(nlp_least, abs=2e-3)
    assert margins["tip_carry"] < -0.05
    assert min(margins.values()) == margins["tip_carry"]  # every other margin holds
    form = formulate(spec)
    x = np.asarray(form.aux_init(np.zeros(0))).ravel()
    zero = np.zeros(4)
    worst = form.scenario_source.stream(x, {}, lambda K: (zero, zero), 4)
    assert worst["value"] < -0.05 and worst["stage"] == 1
    assert worst["label"].startswith("tip_carry (palm 1, during the carry, object's rear edge")
    built = run_builds(spec.scene, _design(spec), {"friction": np.zeros(2)}, 3)
    assert list(built.failure) == ["tip", "tip"] and not built.closed_form.any()
    assert (built.stages_passed == 0).all() and (built.min_margin < 0).all()


def test_whole_carry_rows_are_one_function_for_floats_arrays_and_casadi():
    """physics.carry_contact_nodes / carry_row_least on floats, on numpy arrays (one carry an
    entry) and on CasADi symbols give the same numbers, and the least is at or below the row
    sampled densely along the carry (a lower bound) on every carry."""
    rng = np.random.default_rng(7)
    n = 20
    u, a, b = rng.uniform(5.0, 6.0, n), rng.uniform(0.0, 0.3, n), rng.uniform(0.3, 0.9, n)
    kw = dict(gravity=G, carry_gravity=1.1 * G, friction=0.4, link_length=2.0)

    def least(u, a, b, c1, c2, cells=8):
        nodes, bend = phys.carry_contact_nodes(u, a, start=a, end=b, fastest_u2=u * u,
                                               cells=cells, **kw)
        return phys.carry_row_least(nodes, c1, c2, bend)

    sym = [ca.SX.sym(s) for s in "uab"]
    for c1, c2 in ((1.0, 0.0), (0.75, -1.0), (0.09, 0.2), (0.09, -0.2)):
        arrays = least(u, a, b, c1, c2)
        fn = ca.Function("least", sym, [least(*sym, c1, c2)])
        for i in range(n):
            assert float(least(float(u[i]), float(a[i]), float(b[i]), c1, c2)) == \
                pytest.approx(arrays[i], abs=1e-12)
            assert float(fn(u[i], a[i], b[i])) == pytest.approx(arrays[i], abs=1e-12)
            th = np.linspace(-a[i], b[i], 2001)
            F, N = phys.carry_contact_at(th, u[i], a[i], **kw)
            assert arrays[i] <= float(np.min(c1 * N + c2 * F)) + 1e-12
