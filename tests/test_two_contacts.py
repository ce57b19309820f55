"""The object coming down on a second palm while it bears on its own (twocontact.py) and resting
across both (bridge.py), against independent computations: the sticking impact as the
mass-weighted projection onto the constraints' null space (Gauss; no impulses), the sliding
impact against Newton-Euler balances written out here, the linkage's equations integrated by
scipy with the energy kept (stuck, or sliding without friction) or lost (with friction), and the
rocking row's builds that come down on two palms."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import null_space

from pdm_design.scenes.manipulators.sim.bridge import bridge_accelerations, contact_geometry
from pdm_design.scenes.manipulators.sim.twocontact import (
    contact_jacobian,
    two_contact_impact,
)
from pdm_design.tolerances.yield_ import simulate_one

M_OBJ, W, H, G = 1.0, 0.4, 0.2, 9.81
I_C = M_OBJ * (W * W + H * H) / 12.0


def _scene(rng):
    """A random object pose, two palms, the contacts at its base corners; velocities."""
    phi = rng.uniform(-0.3, 0.3)
    centre = np.array([rng.uniform(-0.2, 0.2), rng.uniform(2.0, 2.2)])
    thetas = rng.uniform(-0.4, 0.4, 2)
    ls = rng.uniform(1.8, 2.2, 2)
    felts = rng.uniform(0.1, 0.5, 2)
    rs = []
    for bx in (-0.5 * W, 0.5 * W):
        c, s = math.cos(phi), math.sin(phi)
        rs.append(np.array([bx * c - 0.5 * H * s, -bx * s - 0.5 * H * c]))  # R(phi) b
    qd = np.concatenate([rng.normal(0, 1.5, 3), rng.normal(0, 1.0, 2)])
    return phi, centre, thetas, ls, felts, rs, qd


def _masses(ls, felts):
    return np.array([M_OBJ, M_OBJ, I_C, felts[0] * ls[0] ** 2, felts[1] * ls[1] ** 2])


def _relative(qd, r, l, theta, col):
    """Object point minus palm point, written out: V + phi'(r_y, -r_x) - l th' t."""
    return (np.array([qd[0] + qd[2] * r[1], qd[1] - qd[2] * r[0]])
            - l * qd[col] * np.array([math.cos(theta), -math.sin(theta)]))


@pytest.mark.parametrize("seed", range(6))
def test_the_stuck_impact_is_gausss_projection_and_loses_carnots_energy(seed):
    """Sticking at both contacts: q'+ is the M-orthogonal projection of q'- onto the null
    space of the contact rows (computed by SVD, no impulses), and the energy lost is Carnot's
    1/2 (q'- - q'+)^T M (q'- - q'+) >= 0."""
    rng = np.random.default_rng(seed)
    phi, _, thetas, ls, felts, rs, qd = _scene(rng)
    mass = _masses(ls, felts)
    jacs = [contact_jacobian(rs[i], ls[i], thetas[i], 3 + i) for i in range(2)]
    normals = [(0.0, 1.0), (math.sin(phi), math.cos(phi))]
    after, impulses = two_contact_impact(1.0 / mass, qd, jacs, normals, ("stick", "stick"), 0.8)
    basis = null_space(np.vstack(jacs))
    assert basis.shape[1] == 1  # a one-degree-of-freedom linkage
    mm = np.diag(mass)
    projected = basis @ np.linalg.solve(basis.T @ mm @ basis, basis.T @ mm @ qd)
    assert np.allclose(after, projected, atol=1e-10)
    lost = 0.5 * qd @ mm @ qd - 0.5 * after @ mm @ after
    assert lost == pytest.approx(0.5 * (qd - after) @ mm @ (qd - after), rel=1e-9, abs=1e-12)
    assert lost >= 0.0
    # the impulses are the momentum change, contact by contact (tangent t = (n_y, -n_x))
    total = np.zeros(2)
    for (pn, pt), n in zip(impulses, normals):
        total += pn * np.array(n) + pt * np.array([n[1], -n[0]])
    assert np.allclose(M_OBJ * (after[:2] - qd[:2]), total, atol=1e-10)


@pytest.mark.parametrize("seed", range(6))
def test_the_sliding_impact_balances_momentum_written_out(seed):
    """The old contact sliding through the impact: the object's momentum and spin, each
    palm's momentum along its swing change by the impulses (Newton-Euler, written here), the
    sliding impulse on the cone's side against the slip, no normal approach after at either
    contact, the new contact stuck, and energy lost."""
    rng = np.random.default_rng(100 + seed)
    phi, _, thetas, ls, felts, rs, qd = _scene(rng)
    mass, mu = _masses(ls, felts), 0.6
    jacs = [contact_jacobian(rs[i], ls[i], thetas[i], 3 + i) for i in range(2)]
    normals = [np.array([0.0, 1.0]), np.array([math.sin(phi), math.cos(phi)])]
    tang = [np.array([n[1], -n[0]]) for n in normals]
    way = math.copysign(1.0, _relative(qd, rs[1], ls[1], thetas[1], 4) @ tang[1])
    after, impulses = two_contact_impact(1.0 / mass, qd, jacs, normals, ("stick", way), mu)
    p = [pn * n + pt * t for (pn, pt), n, t in zip(impulses, normals, tang)]
    assert impulses[1][1] == pytest.approx(-way * mu * impulses[1][0], rel=1e-12)
    assert np.allclose(M_OBJ * (after[:2] - qd[:2]), p[0] + p[1], atol=1e-10)
    spin = sum(r[1] * pi[0] - r[0] * pi[1] for r, pi in zip(rs, p))  # clockwise moments
    assert I_C * (after[2] - qd[2]) == pytest.approx(spin, abs=1e-10)
    for i in range(2):
        t_hat = np.array([math.cos(thetas[i]), -math.sin(thetas[i])])
        assert mass[3 + i] * (after[3 + i] - qd[3 + i]) == pytest.approx(
            -ls[i] * t_hat @ p[i], abs=1e-10)
    assert np.allclose(_relative(after, rs[0], ls[0], thetas[0], 3), 0.0, atol=1e-10)
    assert _relative(after, rs[1], ls[1], thetas[1], 4) @ normals[1] == pytest.approx(0.0,
                                                                                     abs=1e-10)
    mm = np.diag(mass)
    if impulses[1][0] > 0.0 and way * (_relative(after, rs[1], ls[1], thetas[1], 4)
                                       @ tang[1]) >= 0.0:
        assert 0.5 * qd @ mm @ qd - 0.5 * after @ mm @ after >= -1e-12


def _linkage(rng, edge):
    """A consistent state of the object across two palms: its base corners (or, edge, palm 2's
    edge under its base) on the palms' tops, a velocity in the linkage's null space."""
    phi = rng.uniform(-0.15, 0.15)
    c, s = math.cos(phi), math.sin(phi)
    centre = np.array([0.1, 2.3])
    thetas, ls, pivots, contacts = rng.uniform(-0.3, 0.3, 2), (2.0, 2.1), [], []
    for i, bx in enumerate((-0.5 * W, 0.5 * W if not edge else 0.05)):
        point = centre + np.array([bx * c - 0.5 * H * s, -bx * s - 0.5 * H * c])
        e = 0.5 if i == 0 else (-0.6 if not edge else 0.8)
        pivot = point - ls[i] * np.array([math.sin(thetas[i]), math.cos(thetas[i])]) \
            - np.array([e, 0.0])
        pivots.append(tuple(pivot))
        contacts.append(((bx, -0.5 * H), e, ls[i], tuple(pivot), edge and i == 1))
    return phi, centre, thetas, ls, contacts


def _energy(y, masses, weights, ls):
    return (0.5 * np.asarray(y[5:]) ** 2 @ masses + M_OBJ * G * y[1]
            + sum(weights[i] * G * ls[i] * math.cos(y[3 + i]) for i in range(2)))


@pytest.mark.parametrize("case", ["stuck", "frictionless_corner_slides",
                                  "frictionless_edge_slides", "friction"])
def test_the_linkage_keeps_its_energy_and_contacts_integrated_by_scipy(case):
    """The object across two plain palms (no pivot friction): stuck on both, or sliding on
    palm 2 with mu = 0 (its corner on the face, or palm 2's edge along its base: the turning
    normal's terms), the energy T + V is kept to 1e-7 over 0.3 s of scipy's integration of
    bridge_accelerations and the contacts stay closed; sliding with friction it falls."""
    rng = np.random.default_rng(7)
    edge = case == "frictionless_edge_slides"
    phi, centre, thetas, ls, contacts = _linkage(rng, edge)
    felts = (0.12, 0.1)
    masses = np.array([M_OBJ, M_OBJ, I_C, felts[0] * ls[0] ** 2, felts[1] * ls[1] ** 2])
    q = np.array([*centre, phi, *thetas])
    jac = np.vstack([contact_geometry(np.array([*q[:3], q[3 + i], 0.0]), np.zeros(5),
                                      contacts[i], "stick", H)[1] for i in range(2)])
    full = np.zeros((4, 5))  # the two palms' own columns
    full[:2, :4] = jac[:2, :4]
    full[2:, :3], full[2:, 4] = jac[2:, :3], jac[2:, 3]
    slide = case != "stuck"
    rows = full if not slide else np.vstack([full[:2], contacts_normal(phi, edge) @ full[2:]])
    qd = null_space(rows) @ rng.normal(0, 1.0, null_space(rows).shape[1])
    qd *= 1.5 / np.linalg.norm(qd)
    mu = 0.5 if case == "friction" else 0.0
    y0 = np.concatenate([q, qd])
    modes = ("stick", "stick") if not slide else ("stick", _slip_sign(y0, contacts[1], edge))
    geometry = (contacts, modes, (False, False), H)

    def rhs(t, y):
        forces = [0.0, -M_OBJ * G, 0.0] + [felts[i] * G * ls[i] * math.sin(y[3 + i])
                                            for i in range(2)]
        return np.concatenate([y[5:], bridge_accelerations(y, masses, forces, geometry,
                                                           1e-3, mu)[0]])

    def reverses(t, y):  # the slip stops (the simulator ends the slide there; mu = 0: no matter)
        return 1.0 if mu == 0.0 else _slip(y, contacts[1]) * modes[1]

    reverses.terminal = True
    sol = solve_ivp(rhs, (0.0, 0.3), y0, rtol=1e-10, atol=1e-12, dense_output=True,
                    events=reverses)
    assert sol.success
    end = sol.t[-1]
    e0 = _energy(y0, masses, felts, ls)
    ends = [_energy(sol.sol(t), masses, felts, ls) for t in np.linspace(0.0, end, 31)]
    if case == "friction":
        assert end > 0.01
        assert ends[-1] < e0 - 1e-4
        assert all(b <= a + 1e-8 for a, b in zip(ends, ends[1:]))
    else:
        assert end == 0.3
        assert max(abs(e - e0) for e in ends) < 1e-7
    y = sol.sol(end)
    for i, mode in enumerate(modes):
        gap = contact_geometry(np.array([*y[:3], y[3 + i], 0.0]), np.zeros(5), contacts[i],
                               mode, H)[3]
        assert np.all(np.abs(gap) < 1e-8)


def contacts_normal(phi, edge):
    return np.array([math.sin(phi), math.cos(phi)]) if edge else np.array([0.0, 1.0])


def _slip(y, contact):
    """Palm 2's contact's slip (object point minus palm point along t)."""
    q = np.array([*y[:3], y[4], 0.0])
    qd = np.array([*y[5:8], y[9], 0.0])
    _, jac, _, _, n = contact_geometry(q, qd, contact, "stick", H)
    return float(np.array([n[1], -n[0]]) @ (jac @ qd))


def _slip_sign(y, contact, edge):
    return math.copysign(1.0, _slip(y, contact))


def test_the_rocking_rows_two_contact_builds_rest_across_two_palms(rocking_skips):
    """Rocking row, skips allowed, seed 0: builds 9, 74 and 91 come down on a second palm still
    bearing on their own (before, `tip` there): each logs `bridge`, the impact at both
    contacts, and ends later (74 and 91 at rest across the two palms, `stranded`, as the whole
    run time stepped from the feed ends too: results/bench_stepped_row.json); the map hands
    every one of them to the simulator (closed_form False). Build 561 across palms 6 and 5
    turns until its base comes down on palm 5 away from its contact, is stepped, lies on palm
    5 and completes (so does the whole run time stepped)."""
    from pdm_design.tolerances.yield_ import map_builds

    spec, design, tol = rocking_skips
    builds = (9, 74, 91)
    for i in builds:
        result = simulate_one(spec.scene, design, tol, 0, i, 8, allow_skips=True)
        kinds = [e.kind for e in result.events]
        assert "bridge" in kinds
        assert kinds.index("bridge") < len(kinds) - 1  # followed past the impact
        if i in (74, 91):
            failure = result.outcome.failure
            assert failure.kind == "stranded" and "rests across palms" in failure.detail
    mapped = map_builds(spec.scene, design, tol, 562, 8, 0)
    assert not mapped.closed_form[[*builds, 561]].any()
    result = simulate_one(spec.scene, design, tol, 0, 561, 8, allow_skips=True)
    assert result.outcome.completed
    details = [e.detail for e in result.events]
    beyond = next(i for i, d in enumerate(details) if "meets palm 5 away from its contact" in d)
    assert "the object lies on palm 5" in details[beyond + 1]
