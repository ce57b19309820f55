"""The rimless wheel's linearised yield inside the NLP (docs/rimless_wheel.md, section 13): the
rows of statistical.py (physics.stance_rows, and physics.landing_rows on stairs, written once
for numbers and symbols) on the NLP's design symbols, their gradients in every build error
(every step's slope on a ramp, rise and tread on stairs, each step's own or one for every step
of a build: a lot; the start speed; each spoke's length, a lot of them, the hub's mass:
physics.spoke_step, each spoke a lot of its own at the steps that use it) by CasADi's exact
derivatives at the nominal build (statistical.py takes central differences), chained through
the step map with its state x = E (a ramp) or (E, s) (stairs: the stance energy and the
foothold's place on its tread);
sd_i^2 = sum_j (dg_i / dd_j)^2 sigma_j^2, and -log10 of the union bound sum_i Phi(-g_i / sd_i)
over every row of every step (nines): the max_yield term and a yield target's row
(formulation/yield_target.py).
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import NamedTuple

import casadi as ca

from ...errors import SpecError
from ...formulation import chain_moments
from . import physics as phys

SD_FLOOR = 1e-24  # added to every row's variance: a row no deviation moves is far from failing
PER_STEP = {"ramp": ("slope",), "stairs": ("rise", "tread")}  # a step's own build errors


class Spread(NamedTuple):
    """The sigmas of the build errors: each[q] (every step its own), lot[q] (one for every step
    of a build), for q in PER_STEP of the ground, and the start speed's; leg_each (every spoke
    its own length), leg_lot (one for all spokes) and mass (the hub's, a lot)."""

    each: list
    lot: list
    start: object
    leg_each: object = 0.0
    leg_lot: object = 0.0
    mass: object = 0.0


OWN = ("leg_length", "mass")  # the build's own: its spokes and its hub


def checked_sigmas(spec, key: str) -> Spread:
    """The spread of the spec's tolerances with values; a SpecError naming `key` for what the
    linearised yield does not take."""
    from dataclasses import replace

    from .statistical import _sigmas

    try:  # an allocated tolerance is judged at a unit value
        _sigmas(spec.scene, [replace(t, value=1.0) if t.allocate else t
                             for t in spec.tolerances], spec.verification.stages)
    except ValueError as error:
        raise SpecError(spec.source or "<spec>", key, str(error), found="those tolerances") \
            from None
    return spread_of(*sigmas([t for t in spec.tolerances if not t.allocate],
                             ground=spec.scene.ground), ground=spec.scene.ground)


def sigmas(tolerances, scale=1.0, *, ground="ramp"):
    """(each, lot) sigma lists (formulation/yield_target.scaled_sigmas's form): each value / 3
    times scale, each = [every step's own sigma of q for q in PER_STEP, every spoke's own
    length's], lot = [a lot's sigma of q ..., the spokes' lot, the hub's mass, the start
    speed's]."""
    from ...tolerance_model import SIGMAS_PER_TOLERANCE

    names = PER_STEP[ground]
    each, lot = [0.0] * (len(names) + 1), [0.0] * (len(names) + 3)
    for t in tolerances:
        sigma = t.value / SIGMAS_PER_TOLERANCE * scale
        if t.quantity == "start_speed":
            lot[-1] += sigma
        elif t.quantity == "mass":
            lot[-2] += sigma
        elif t.applies_to == "lot":
            lot[(*names, "leg_length").index(t.quantity)] += sigma
        else:
            each[(*names, "leg_length").index(t.quantity)] += sigma
    return each, lot


def spread_of(each, lot, *, ground="ramp") -> Spread:
    """A Spread from sigmas' (each, lot) lists."""
    q = len(PER_STEP[ground])
    return Spread(list(each[:q]), list(lot[:q]), lot[-1], each[q], lot[q], lot[q + 1])


def _is_zero(value) -> bool:
    return isinstance(value, (int, float)) and value == 0.0


def _slots(m, spread: Spread) -> dict:
    """{name: index} of a step's errors: PER_STEP's, then (with spokes' or the hub's errors)
    the stance spoke's and the landing spoke's lengths ("a", "b") and the hub's mass."""
    names = list(PER_STEP["stairs" if m.stairs else "ramp"])
    if not (_is_zero(spread.leg_each) and _is_zero(spread.leg_lot) and _is_zero(spread.mass)):
        names += ["a", "b", "mass"]
    return {n: i for i, n in enumerate(names)}


def _wheel(m):
    return SimpleNamespace(alpha=m.alpha, rate=m.rate, leg=m.leg, k2=m.k2, eta=m.eta,
                           beta=m.beta, gravity=m.scene.gravity, friction=m.scene.friction)


def local_step(m, x, prev, cur, slots=None):
    """(rows, next state) of stance k on the closed forms `m` (formulation._Model): the state
    x_{k-1} (E; on stairs (E, s)), the errors of step k - 1 (`prev`: the chord the stance
    starts on, on stairs the tread it stands on) and of step k (`cur`: the chord it ends on,
    the tread it lands on); with the spokes' slots (`_slots`), `spoke_step`."""
    if slots is not None and "a" in slots:
        return _spoke_step(m, x, prev, cur, slots)
    wheel = _wheel(m)
    beta_prev, beta = m.chord_angle(prev[0]), m.chord_angle(cur[0])
    rows = [g for _, g in phys.stance_rows(wheel, x[0], beta_prev, beta, m.ground)]
    state = [m.eta**2 * x[0] + phys.step_offset(beta, m.alpha, m.eta, m.rate)]
    if m.stairs:
        before, after = m.tread + prev[1], m.tread + cur[1]
        rows += [g for _, g in phys.landing_rows(wheel, x[1], beta, before, after, m.tread)]
        state.append(phys.next_foothold(x[1], m.chord, beta, before))
    return ca.vertcat(*rows), ca.vertcat(*state)


def _chord_angle(m, error, a, b):
    """A step's chord angle on spokes a, b: the slope's on a ramp, asin(rise / |tip a - tip
    b|) on stairs."""
    if not m.stairs:
        return m.beta + error
    from .formulation import asin_sx

    return asin_sx(m.rise + error, phys.chord_between(a, b, m.alpha))


def _spoke_step(m, x, prev, cur, slots):
    """local_step of a build whose spokes have their own lengths (the stance spoke l + a, the
    landing one l + b; step k - 1's pair sets where the stance starts) and whose hub its own
    mass (k^2 = (M k_h^2 + S l^2 / 3) / (M + S), the spokes' rods as designed): physics'
    spoke_step (docs/rimless_wheel.md section 13, "Spokes and hub")."""
    w = m.scene.wheel
    a, b = m.leg + cur[slots["a"]], m.leg + cur[slots["b"]]
    pa, pb = m.leg + prev[slots["a"]], m.leg + prev[slots["b"]]
    k2 = phys.gyration_squared(w.mass + cur[slots["mass"]], w.gyration, w.spoke_mass, m.n,
                               m.leg)
    beta_prev = _chord_angle(m, prev[0], pa, pb)
    beta = _chord_angle(m, cur[0], a, b)
    phi0 = phys.chord_offset(pa, pb, m.alpha) + beta_prev - 2.0 * m.alpha
    found, energy, phi1 = phys.spoke_step(_wheel(m), x[0], phi0, beta, a, b, k2, m.ground)
    rows, state = [g for _, g in found], [energy]
    if m.stairs:
        before, after = m.tread + prev[1], m.tread + cur[1]
        chord = phys.chord_between(a, b, m.alpha)
        rows += [g for _, g in phys.landing_rows(
            _wheel(m), x[1], beta, before, after, m.tread, chord,
            phys.nose_reach_between(a, m.alpha, phi1))]
        state.append(phys.next_foothold(x[1], chord, beta, before))
    return ca.vertcat(*rows), ca.vertcat(*state)


def linear_step(m, slots):
    """(x, rows, their Jacobian in (x, e_{k-1}, e_k), the next state, M(x), N(x)) of one stance
    at zero errors, x the state's symbol (row_moments): M and N are the step map's Jacobians,
    in x where a spoke's or the hub's error scales the energy (eta_ab^2 E)."""
    nx, ne = (2 if m.stairs else 1), len(slots)
    x, prev, cur = ca.SX.sym("x", nx), ca.SX.sym("prev", ne), ca.SX.sym("cur", ne)
    rows, state = local_step(m, x, prev, cur, slots)
    every = ca.vertcat(x, prev, cur)
    rows, jac, state, step_jac = ca.substitute(
        [rows, ca.jacobian(rows, every), state, ca.jacobian(state, every)],
        [ca.vertcat(prev, cur)], [ca.SX.zeros(2 * ne)])
    if ca.depends_on(step_jac[:, :nx], x):
        raise AssertionError("the step map is not linear in its state")  # A = diag(eta^2, 1)
    big_m = ca.vertcat(step_jac[:, :nx + ne], ca.SX.zeros(ne, nx + ne))  # M = [A B_p; 0 0]
    big_n = ca.vertcat(step_jac[:, nx + ne:], ca.SX.eye(ne))  # N = [B_c; I]
    return x, rows, jac, state, big_m, big_n


def _lot_columns(m, spread: Spread, slots: dict, stages: int):
    """(variances, L_1..L_K, dx_0/d lot): a lot's column moves its quantity on every step;
    spoke i's length (each spoke its own: a lot of its own) is the stance spoke of steps
    i + 1, i + 1 + n, ... and the landing one of steps i, i + n, ...; the spokes' lot moves
    both; the last column is the start speed. x_0's energy E_0 = w0^2 - rate(spoke 0, k^2)
    vers(beta - alpha) moves with the start speed, spoke 0 and the hub."""
    cols = []  # (sigma, what it moves: {slot: None} every step, or {"spoke": i})
    for i, sigma in enumerate(spread.lot):
        if not _is_zero(sigma):
            cols.append((sigma, {i: None}))
    if "a" in slots:
        if not _is_zero(spread.leg_each):
            cols += [(spread.leg_each, {"spoke": j}) for j in range(m.n)]
        if not _is_zero(spread.leg_lot):
            cols.append((spread.leg_lot, {slots["a"]: None, slots["b"]: None}))
        if not _is_zero(spread.mass):
            cols.append((spread.mass, {slots["mass"]: None}))
    lots = []
    for k in range(1, stages + 1):
        lot = ca.SX.zeros(len(slots), len(cols) + 1)
        for col, (_, moves) in enumerate(cols):
            if "spoke" in moves:
                lot[slots["a"], col] += float((k - 1) % m.n == moves["spoke"])
                lot[slots["b"], col] += float(k % m.n == moves["spoke"])
            for slot in (s for s in moves if s != "spoke"):
                lot[slot, col] = 1.0
        lots.append(lot)
    variances = ca.vertcat(*[ca.SX(s)**2 for s, _ in cols], ca.SX(spread.start)**2)
    return variances, lots, _start_gradient(m, spread, slots, cols)


def _start_gradient(m, spread, slots, cols):
    """dE_0 / d(each lot column) (rows: the state; the foothold's does not move)."""
    speed = m.scene.initial.speed
    dw, a, mass = ca.SX.sym("dw"), ca.SX.sym("a"), ca.SX.sym("mass")
    w = m.scene.wheel
    k2 = phys.gyration_squared(w.mass + mass, w.gyration, w.spoke_mass, m.n, m.leg)
    e0 = phys.stance_energy(speed + dw, m.beta - m.alpha,
                            phys.stance_rate(m.scene.gravity, k2, m.leg + a))
    grad = ca.substitute(ca.gradient(e0, ca.vertcat(dw, a, mass)), ca.vertcat(dw, a, mass),
                         ca.SX.zeros(3))
    nx = 2 if m.stairs else 1
    out = ca.SX.zeros(nx + len(slots), len(cols) + 1)
    out[0, len(cols)] = grad[0]
    for col, (_, moves) in enumerate(cols):
        if moves.get("spoke") == 0 or (slots.get("a") in moves):
            out[0, col] = grad[1]
        if slots.get("mass") in moves:
            out[0, col] = grad[2]
    return out


def row_moments(m, stages: int, spread: Spread):
    """(g, sd): SX columns of every row of every step at the nominal build. Stance k's rows
    depend on the errors through the state x_{k-1}, the errors e_{k-1} of the step before and
    its own e_k alone, and x_k = A x_{k-1} + B_p e_{k-1} + B_c e_k (A, B: the map's Jacobians
    at the nominal build, at its state), so z_k = (x_k, e_k) = M z_{k-1} + N e_k. The steps'
    own errors: Q_k = cov(z_k) = M Q_{k-1} M^T + N S N^T; a row's variance H Q_{k-1} H^T +
    G_c S G_c^T (H = [g_x, g_p]). The lots, each spoke's length, the hub's mass and the start
    speed: J_k = dz_k/dlots = M J_{k-1} + N L_k, a row's gradient H J_{k-1} + G_c L_k. One
    stance differentiated once: rows and time linear in the steps."""
    slots = _slots(m, spread)
    x, rows, jac, state, big_m, big_n = linear_step(m, slots)
    nz = big_m.shape[0]
    lot_var, lots, sens = _lot_columns(m, spread, slots, stages)
    each = ca.diag(ca.vertcat(*[ca.SX(s)**2 for s in spread.each],
                              ca.SX.zeros(len(slots) - len(spread.each))))
    speed = m.scene.initial.speed
    nominal = ca.vertcat(phys.stance_energy(speed, m.beta - m.alpha, m.rate),
                         *([m.s0] if m.stairs else []))  # x_0
    cov = ca.SX.zeros(nz, nz)
    gs, sds = [], []
    for lot in lots:
        g, j, mk, nk = ca.substitute([rows, jac, big_m, big_n], [x], [nominal])
        h, g_cur = j[:, :nz], j[:, nz:]
        var = (ca.sum2((h @ cov) * h) + ca.sum2((g_cur @ each) * g_cur)
               + (h @ sens + g_cur @ lot)**2 @ lot_var)
        gs.append(g)
        sds.append(ca.sqrt(var + SD_FLOOR))
        cov = mk @ cov @ mk.T + nk @ each @ nk.T
        sens = mk @ sens + nk @ lot
        nominal = ca.substitute(state, x, nominal)
    return ca.vertcat(*gs), ca.vertcat(*sds)


def nines(m, stages: int, spread: Spread):
    """-log10 of the union bound over every row of every step (smooth far into the tail:
    chain_moments.log_tail and a log-sum-exp)."""
    g, sd = row_moments(m, stages, spread)
    logs = chain_moments.log_tail(g / sd)
    top = ca.mmax(logs)
    return -(top + ca.log(ca.sum1(ca.exp(logs - top)))) / math.log(10.0)


def objective_term(spec, m):
    """The max_yield term (nines); 0 unless the spec asks for it."""
    if not float(spec.objective.get("max_yield", 0.0)) > 0.0:
        return ca.SX(0.0)
    return nines(m, spec.verification.stages, checked_sigmas(spec, "tolerances"))


def target_rows(spec, m, symbols: dict, bounds: dict):
    """A yield target's variable, row and objective (formulation/yield_target.py): the nines row
    with the allocated sigmas s times their shares."""
    from functools import partial

    from ...formulation import yield_target

    yield_target.refuse_objectives(spec)
    checked_sigmas(spec, "tolerances")
    _refuse_allocation(spec)
    of_ground = partial(sigmas, ground=spec.scene.ground)

    def nines_of(s):
        return nines(m, spec.verification.stages,
                     spread_of(*yield_target.scaled_sigmas(spec.tolerances, s, of_ground),
                               ground=spec.scene.ground))

    return yield_target.target_rows(spec, symbols, bounds, nines_of)


def _refuse_allocation(spec) -> None:
    """A SpecError (exit 2) for an allocation no yield bounds: refusals.allocation_refusal's
    (a hub mass no k^2 depends on, whose scale nothing limits; a given mass or start speed
    tolerance that takes the value to 0; fewer steps than spokes)."""
    from .refusals import allocation_refusal

    refusal = allocation_refusal(spec)
    if refusal is not None:
        key, expected, found = refusal
        raise SpecError(spec.source or "<spec>", key, expected, found=found)
