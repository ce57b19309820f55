"""Impacts of the time stepper (sim/stepping.py) against closed forms derived by hand.

Conventions (those of the stepper): phi is clockwise, so a point at lever r = (rx, ry) from the
centre moves at v + phi' (ry, -rx); the counter-clockwise rate is W = -phi'. A palm's top centre
is pivot + l (sin th, cos th), so it moves at l th' (cos th, -sin th) and its kinetic energy is
F l^2 th'^2 / 2 (F the felt mass).

The stepper is first order: each step adds dt times gravity to the velocity, then solves the
plastic contacts. A corner that starts exactly touching is therefore met within the first step,
by one impulse on the velocity v0 + dt g: the closed forms below hold to the solver's tolerance.
A corner that starts a few steps above contact is met while the object has turned by phi' t_hit
(the closed forms use the lever at that turn), the impulse spread over two steps whose poses differ
by |phi'| dt from it: an error of order (speed / lever) |phi'| dt, a few 1e-5 at dt = 1e-5.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdm_design.scenes.manipulators.sim.stepping import Block, Slab, Stepper, step

G = 9.81
M, W, H = 2.0, 0.2, 0.1
I_C = M * (W * W + H * H) / 12.0  # a uniform rectangle about its centre
PHI = 0.3  # the object's tilt (clockwise): its front-bottom corner is the lowest
V0 = np.array([0.4, -1.0, 2.0])  # x', y', phi' before the impact
EXACT = 1e-8  # the projected Gauss-Seidel stops once no row changes a speed by 1e-10 m/s
SPREAD = 3e-4  # an impact spread over two steps of dt = 1e-5 (see the module's words)


def front_bottom(phi):
    """The lever of the front-bottom corner: R(phi) (W/2, -H/2), R the clockwise rotation."""
    c, s = math.cos(phi), math.sin(phi)
    return 0.5 * W * c - 0.5 * H * s, -0.5 * W * s - 0.5 * H * c


def front_top(phi):
    """The lever of the front-top corner: R(phi) (W/2, H/2)."""
    c, s = math.cos(phi), math.sin(phi)
    return 0.5 * W * c + 0.5 * H * s, -0.5 * W * s + 0.5 * H * c


# Palms held still: one with both stops at th = 0 (the stop rows hold th' = 0 both ways), one at
# its front stop th = pi/2, where its arc runs straight down, so the object's normal impulse
# drives it along its arc into the stop (its own weight too).
HELD = {
    "both_stops": (Slab((0.0, 0.0), 0.5, 3.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.05), 0.0),
    "front_stop": (Slab((-0.5, 0.5), 0.5, 3.0, 1.0, 0.0, 0.0, 0.0, math.pi / 2, 1.0, 0.05),
                   math.pi / 2),
}


def sticking(v, rx, ry, gravity_time=0.0):
    """A plastic impact of the corner at lever r that sticks: the impulses act at the corner, so
    the object's angular momentum about that (fixed) point is kept, L = I W - m (r x v) (the
    centre is at -r from it), and after it the corner is still, the object turning about it:
    W+ = L / (I + m |r|^2), v+ = W+ z x (-r) = W+ (ry, -rx). Gravity's moment about the corner,
    (-r) x (0, -m g) = m g rx, adds m g rx t to L over a time t (in flight and turning alike).
    Returns (x', y', phi')."""
    big_l = -I_C * v[2] - M * (rx * v[1] - ry * v[0]) + M * G * rx * gravity_time
    turn = big_l / (I_C + M * (rx * rx + ry * ry))
    return np.array([turn * ry, -turn * rx, -turn])


def sliding(v, rx, ry, mu):
    """A plastic impact of the corner at lever r on an upward normal that slides throughout:
    impulse (Px, Py) with Px = -sign(ux) mu Py, ux the corner's slip before. The object takes
    dv = P / m, dphi' = (Px ry - Py rx) / I, and the corner's normal speed uy = y' - phi' rx
    comes to zero:  uy + Py (1/m + (rx^2 + sign(ux) mu rx ry) / I) = 0.
    Returns ((x', y', phi') after, (Px, Py), the slip after)."""
    ux, uy = v[0] + v[2] * ry, v[1] - v[2] * rx
    sign = math.copysign(1.0, ux)
    py = -uy / (1.0 / M + (rx * rx + sign * mu * rx * ry) / I_C)
    px = -sign * mu * py
    after = np.array([v[0] + px / M, v[1] + py / M, v[2] + (px * ry - py * rx) / I_C])
    return after, (px, py), after[0] + after[2] * ry


def drop_on_corner(slab, th, gravity, mu, dt, height, steps):
    """The object tilted by PHI, its front-bottom corner `height` above the palm's top, at V0;
    `steps` steps. Returns (q, v, the found of every step)."""
    rx, ry = front_bottom(PHI)
    tx, ty = slab.top(th)
    stepper = Stepper(Block(M, I_C, W, H), (slab,), gravity, mu, dt)
    q, v, found, log = np.array([tx - rx, ty - ry + height, PHI, th]), np.array([*V0, 0.0]), (), []
    for _ in range(steps):
        q, v, found = step(stepper, q, v, found)
        log.append(found)
    return q, v, log


@pytest.mark.parametrize("gravity", [0.0, G])
@pytest.mark.parametrize("held", sorted(HELD))
def test_corner_sticks_touching(held, gravity):
    """A corner touching a held palm, mu large: one step ends the impact; the object then turns
    about the corner (angular momentum about it kept), the palm does not move."""
    slab, th = HELD[held]
    dt, mu = 1e-5, 5.0
    q, v, log = drop_on_corner(slab, th, gravity, mu, dt, 0.0, 1)
    rx, ry = front_bottom(PHI)
    expected = sticking(V0 + dt * np.array([0.0, -gravity, 0.0]), rx, ry)
    np.testing.assert_allclose(v[:3], expected, rtol=0, atol=EXACT)
    assert v[3] == pytest.approx(0.0, abs=EXACT)
    assert v[0] + v[2] * ry == pytest.approx(0.0, abs=EXACT)  # the corner is still
    assert v[1] - v[2] * rx == pytest.approx(0.0, abs=EXACT)
    (contact, normal, tangential), = log[0]
    # the impulse is the object's momentum change less gravity's; it lies within the cone
    impulse = M * (v[:2] - V0[:2]) + M * dt * np.array([0.0, gravity])
    assert normal == pytest.approx(impulse[1], rel=1e-7)
    assert abs(tangential) == pytest.approx(abs(impulse[0]), rel=1e-7)
    assert abs(impulse[0]) < mu * impulse[1]


@pytest.mark.parametrize("gravity", [0.0, G])
@pytest.mark.parametrize("held", sorted(HELD))
def test_corner_sticks_from_above(held, gravity):
    """The same corner three steps above contact, 30 steps on (the impact within the first
    four). With gravity the object keeps turning about the corner (the corner's centripetal
    acceleration W^2 |ry|, about 0.5 m/s^2, is less than g), its angular momentum about it having
    gained gravity's moment m g rx t over the whole 30 dt. With none, that acceleration lifts the
    corner off at once and the object flies on at the post-impact velocity."""
    slab, th = HELD[held]
    dt, steps = 1e-5, 30
    q, v, _ = drop_on_corner(slab, th, gravity, 5.0, dt, 3 * dt, steps)
    rx, ry = front_bottom(PHI)
    t_hit = 3 * dt / -(V0[1] - V0[2] * rx)  # the corner's normal speed closes the gap
    rx, ry = front_bottom(PHI + V0[2] * t_hit)
    if gravity:
        turn = -sticking(V0, rx, ry, steps * dt)[2]
        fx, fy = front_bottom(q[2])  # the lever now (the object has turned since)
        expected = np.array([turn * fy, -turn * fx, -turn])
    else:
        expected = sticking(V0, rx, ry)
    np.testing.assert_allclose(v[:3], expected, rtol=0, atol=SPREAD)
    assert v[3] == pytest.approx(0.0, abs=EXACT)


@pytest.mark.parametrize("gravity", [0.0, G])
@pytest.mark.parametrize("held", sorted(HELD))
def test_corner_slides_touching(held, gravity):
    """mu = 0.2: the corner's approach is stopped, the tangential impulse is mu times the
    normal one all through (the slip keeps its sign), so the corner still slides after."""
    slab, th = HELD[held]
    dt, mu = 1e-5, 0.2
    q, v, log = drop_on_corner(slab, th, gravity, mu, dt, 0.0, 1)
    rx, ry = front_bottom(PHI)
    expected, (px, py), slip = sliding(V0 + dt * np.array([0.0, -gravity, 0.0]), rx, ry, mu)
    assert slip > 0.1  # it slides through (else the closed form is not the case)
    np.testing.assert_allclose(v[:3], expected, rtol=0, atol=EXACT)
    assert v[3] == pytest.approx(0.0, abs=EXACT)
    (contact, normal, tangential), = log[0]
    assert normal == pytest.approx(py, rel=1e-7)
    assert abs(tangential) == pytest.approx(mu * normal, rel=1e-9)
    assert v[1] - v[2] * rx == pytest.approx(0.0, abs=EXACT)  # no normal speed left


@pytest.mark.parametrize("held", sorted(HELD))
def test_corner_slides_from_above(held):
    """Sliding from three steps above, no gravity: after the impact the corner's centripetal
    acceleration lifts it off, so the object flies on at the post-impact velocity."""
    slab, th = HELD[held]
    dt, mu = 1e-5, 0.2
    q, v, log = drop_on_corner(slab, th, 0.0, mu, dt, 3 * dt, 30)
    rx, ry = front_bottom(PHI)
    t_hit = 3 * dt / -(V0[1] - V0[2] * rx)
    expected, (px, py), slip = sliding(V0, *front_bottom(PHI + V0[2] * t_hit), mu)
    assert slip > 0.1
    np.testing.assert_allclose(v[:3], expected, rtol=0, atol=SPREAD)
    total_n = sum(pn for found in log for _, pn, _ in found)
    total_t = sum(abs(pt) for found in log for _, _, pt in found)
    assert total_n == pytest.approx(py, rel=1e-3)
    assert total_t == pytest.approx(mu * total_n, rel=1e-9)


# A free palm (weight 0 and no gravity: no force on it but the contact), off its stops.
FREE = Slab((0.0, 0.0), 0.5, 3.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.3, 0.03)
TH0, TH0_DOT = 0.4, -0.3


def end_face_run(phi, omega, lever_x, y, dt, gap, steps):
    """The object at tilt phi (its front face, or front-top corner, toward the palm's rear end
    face) moving at x' = 1 with spin omega; mu = 0, no gravity. Returns (v, found log)."""
    tx, ty = FREE.top(TH0)
    end = tx - 0.5 * FREE.width
    stepper = Stepper(Block(M, I_C, W, H), (FREE,), 0.0, 0.0, dt)
    q = np.array([end - lever_x - gap, y, phi, TH0])
    v, found, log = np.array([1.0, 0.0, omega, TH0_DOT]), (), []
    for _ in range(steps):
        q, v, found = step(stepper, q, v, found)
        log.append(found)
    return v, log


def end_face_impact(omega, ry):
    """The plastic impact of the object on the palm's end face, normal n = (-1, 0), no friction:
    an impulse P >= 0 on the object along n, -P n = (P, 0) on the palm, whose generalized
    impulse is (P, 0) . d top / d th = P l cos th (the links take the rest). So
    m dx' = -P,  I dphi' = (n . (ry, -rx)) P = -ry P,  F l^2 dth' = P l cos th,
    and the normal relative speed -(x' + phi' ry) + l th' cos th comes to zero:
    P = (x' + phi' ry - l th' cos th) / (1/m + ry^2 / I + cos^2 th / F)
    (the palm's felt mass along x is F / cos^2 th). Returns (P, v after)."""
    c = math.cos(TH0)
    approach = 1.0 + omega * ry - FREE.link * TH0_DOT * c
    impulse = approach / (1.0 / M + ry * ry / I_C + c * c / FREE.felt)
    return impulse, np.array([1.0 - impulse / M, 0.0, omega - ry * impulse / I_C,
                              TH0_DOT + impulse * c / (FREE.felt * FREE.link)])


@pytest.mark.parametrize("height", [0.0, 3e-5])
def test_corner_on_free_palm_end(height):
    """The tilted object's front-top corner on the free palm's end face, 2 mm below its top."""
    dt = 1e-5
    rx, ry = front_top(PHI)
    _, ty = FREE.top(TH0)
    steps = 1 if height == 0.0 else 20
    v, log = end_face_run(PHI, 0.5, rx, ty - 0.002 - ry, dt, height, steps)
    if height:
        t_hit = height / (1.0 + 0.5 * ry - FREE.link * TH0_DOT * math.cos(TH0))
        ry = front_top(PHI + 0.5 * t_hit)[1]
    impulse, expected = end_face_impact(0.5, ry)
    np.testing.assert_allclose(v, expected, rtol=0, atol=EXACT if not height else SPREAD)
    total = sum(pn for found in log for _, pn, _ in found)
    assert total == pytest.approx(impulse, rel=1e-8 if not height else 1e-4)
    # momentum along x of the object and the palm's x-momentum through the links: the impulse
    # on each is the same P (the one on the palm is its generalized momentum over l cos th)
    # (cos th at the start: the palm has swung by th' t since, 1e-4 rad over 20 steps)
    assert M * (1.0 - v[0]) == pytest.approx(FREE.felt * FREE.link * (v[3] - TH0_DOT)
                                             / math.cos(TH0), rel=1e-6 if not height else 1e-4)


@pytest.mark.parametrize("omega", [0.0, 0.5])
def test_face_on_free_palm_end(omega):
    """The upright object's front face flush on the free palm's end face (its centre level with
    the face's middle, levers ry = +-t/2): two points. Both come to zero normal speed, so the spin
    is stopped (phi' ry1 = phi' ry2), the sum of the impulses is the one-point P with ry = 0
    and their moments take the spin: (P1 - P2) t/2 = I phi' (the moment of P_i is -ry_i P_i)."""
    dt = 1e-5
    _, ty = FREE.top(TH0)
    half = 0.5 * FREE.thickness
    v, log = end_face_run(0.0, omega, 0.5 * W, ty - half, dt, 0.0, 1)
    impulse, expected = end_face_impact(0.0, 0.0)
    np.testing.assert_allclose(v, expected, rtol=0, atol=EXACT)
    by_lever = {round(c.lever[1] / half): pn for c, pn, _ in log[0]}
    assert by_lever[1] + by_lever[-1] == pytest.approx(impulse, rel=1e-8)
    assert (by_lever[1] - by_lever[-1]) * half == pytest.approx(I_C * omega, abs=1e-8)


def test_face_on_free_palm_end_from_above():
    """No spin, two steps above: the two points meet at once and the result is the same (to the
    palm's arc turning its x-speed l th' cos th down by l th' sin th dth over the 10 steps, about
    1e-5 of it, which the object, faster, keeps making up)."""
    v, log = end_face_run(0.0, 0.0, 0.5 * W, FREE.top(TH0)[1] - 0.5 * FREE.thickness, 1e-5,
                          2e-5, 10)
    np.testing.assert_allclose(v, end_face_impact(0.0, 0.0)[1], rtol=0, atol=1e-5)


def energy(stepper, q, v):
    """Object kinetic + m g y; each palm F l^2 th'^2 / 2 + weight g l cos th."""
    b = stepper.block
    total = 0.5 * b.mass * (v[0] ** 2 + v[1] ** 2) + 0.5 * b.inertia * v[2] ** 2
    total += b.mass * stepper.gravity * q[1]
    for i, s in enumerate(stepper.slabs):
        total += 0.5 * s.felt * s.link ** 2 * v[3 + i] ** 2
        total += s.weight * stepper.gravity * s.link * math.cos(q[3 + i])
    return total


def overlap(q, block, slab, th):
    """Depth of the overlap of the object and the slab by separating axes (the least overlap
    of their projections on the four face normals; <= 0 when apart)."""
    c, s = math.cos(q[2]), math.sin(q[2])
    ex, ey = (c, -s), (s, c)
    hw, hh = 0.5 * block.width, 0.5 * block.height
    body = [(q[0] + a * hw * ex[0] + b * hh * ey[0], q[1] + a * hw * ex[1] + b * hh * ey[1])
            for a in (-1, 1) for b in (-1, 1)]
    tx, ty = slab.top(th)
    palm = [(tx + a * 0.5 * slab.width, ty - b * slab.thickness) for a in (-1, 1) for b in (0, 1)]
    depth = math.inf
    for ax in (ex, ey, (1.0, 0.0), (0.0, 1.0)):
        pa = [x * ax[0] + y * ax[1] for x, y in body]
        pb = [x * ax[0] + y * ax[1] for x, y in palm]
        depth = min(depth, min(max(pa), max(pb)) - max(min(pa), min(pb)))
    return depth


@pytest.mark.parametrize("seed", range(10))
def test_drops_do_not_gain_energy(seed):
    """Random drops of a spinning object among a palm held at its stops and a free palm (no
    pivot torque or damping): contacts are plastic and friction dissipates, so the energy may
    rise only by the first-order stepping of the forces. In free flight that stepping loses
    m g^2 dt^2 / 2 a step; on a weight-turned palm (U = w g l cos th, |U''| <= w g l, the object
    carried adding at most m g l) a step's velocity-then-position update changes the energy by
    dt^2 (U'' th'^2 - U'^2 / (F l^2)) / 2 + O(dt^3), so it rises at most dt^2 (m + w) g l th'^2 / 2:
    summed over the run, O(dt). The object must not sink into a palm by 2 mm (the contacts'
    margin), by separating axes or by the stepper's own gaps."""
    rng = np.random.default_rng(seed)
    block = Block(1.5, 1.5 * (0.12 ** 2 + 0.06 ** 2) / 12.0, 0.12, 0.06)
    held = Slab((-0.15, 0.0), 0.5, 3.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.2, 0.03)
    free = Slab((0.15, 0.0), 0.5, 3.0, 2.0, 0.0, 0.0, -0.3, 0.3, 0.2, 0.03)
    dt = 1e-3
    stepper = Stepper(block, (held, free), G, float(rng.choice([0.2, 0.8])), dt)
    q = np.array([rng.uniform(-0.2, 0.25), rng.uniform(0.58, 0.7), rng.uniform(-1.0, 1.0),
                  0.0, rng.uniform(-0.1, 0.1)])
    v = np.array([rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 0.5), rng.uniform(-6.0, 6.0),
                  0.0, rng.uniform(-0.3, 0.3)])
    start, allowance, found = energy(stepper, q, v), 0.0, ()
    rate = dt * dt * (block.mass + held.weight + free.weight) * G * max(held.link, free.link) / 2
    for _ in range(500):
        allowance += rate * float(np.max(v[3:] ** 2))
        q, v, found = step(stepper, q, v, found)
        assert energy(stepper, q, v) <= start + allowance + 1e-9 * abs(start)
        assert all(c.gap > -2e-3 for c, _, _ in found)
        for i, slab in enumerate(stepper.slabs):
            assert overlap(q, block, slab, q[3 + i]) < 2e-3


def test_object_rising_under_a_thick_slab_is_stopped():
    """An object rising at 1 m/s 0.1 mm under a 0.3 m thick held slab: plastic, it stops."""
    slab = Slab((0.0, 0.0), 0.5, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.4, 0.3)  # bottom at y = 0.2
    stepper = Stepper(Block(1.0, 1.0 / 600.0, 0.1, 0.1), (slab,), 0.0, 0.5, 1e-3)
    q, v, found = np.array([0.0, 0.2 - 0.05 - 1e-4, 0.0, 0.0]), np.array([0.0, 1.0, 0.0, 0.0]), ()
    for _ in range(5):
        q, v, found = step(stepper, q, v, found)
    assert v[1] == pytest.approx(0.0, abs=1e-9)
    assert q[1] + 0.05 <= 0.2 + 1e-9
