"""The rimless wheel's linearised yield inside the NLP (docs/rimless_wheel.md, section 13): the
rows of statistical.py (physics.stance_rows, and physics.landing_rows on stairs, written once
for numbers and symbols) on the NLP's design symbols, their gradients in every build error
(every step's slope on a ramp, rise and tread on stairs, each step's own or one for every step
of a build: a lot; the start speed) by CasADi's exact derivatives at the nominal build
(statistical.py takes central differences), chained through the step map with its state
x = E (a ramp) or (E, s) (stairs: the stance energy and the foothold's place on its tread);
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
    of a build), for q in PER_STEP of the ground, and the start speed's."""

    each: list
    lot: list
    start: object


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
                             ground=spec.scene.ground))


def sigmas(tolerances, scale=1.0, *, ground="ramp"):
    """(each, lot) sigma lists (formulation/yield_target.scaled_sigmas's form): each value / 3
    times scale, each = [every step's own sigma of q for q in PER_STEP], lot = [a lot's sigma
    of q ..., the start speed's]."""
    from ...tolerance_model import SIGMAS_PER_TOLERANCE

    names = PER_STEP[ground]
    each, lot = [0.0] * len(names), [0.0] * (len(names) + 1)
    for t in tolerances:
        sigma = t.value / SIGMAS_PER_TOLERANCE * scale
        if t.quantity == "start_speed":
            lot[-1] += sigma
        elif t.applies_to == "lot":
            lot[names.index(t.quantity)] += sigma
        else:
            each[names.index(t.quantity)] += sigma
    return each, lot


def spread_of(each, lot) -> Spread:
    """A Spread from sigmas' (each, lot) lists."""
    return Spread(list(each), list(lot[:-1]), lot[-1])


def local_step(m, x, prev, cur):
    """(rows, next state) of stance k on the closed forms `m` (formulation._Model): the state
    x_{k-1} (E; on stairs (E, s)), the errors of step k - 1 (`prev`: the chord the stance
    starts on, on stairs the tread it stands on) and of step k (`cur`: the chord it ends on,
    the tread it lands on)."""
    wheel = SimpleNamespace(alpha=m.alpha, rate=m.rate, leg=m.leg, k2=m.k2, eta=m.eta,
                            beta=m.beta, gravity=m.scene.gravity, friction=m.scene.friction)
    beta_prev, beta = m.chord_angle(prev[0]), m.chord_angle(cur[0])
    rows = [g for _, g in phys.stance_rows(wheel, x[0], beta_prev, beta, m.ground)]
    state = [m.eta**2 * x[0] + phys.step_offset(beta, m.alpha, m.eta, m.rate)]
    if m.stairs:
        before, after = m.tread + prev[1], m.tread + cur[1]
        rows += [g for _, g in phys.landing_rows(wheel, x[1], beta, before, after, m.tread)]
        state.append(phys.next_foothold(x[1], m.chord, beta, before))
    return ca.vertcat(*rows), ca.vertcat(*state)


def _is_zero(value) -> bool:
    return isinstance(value, (int, float)) and value == 0.0


def linear_step(m):
    """(x, rows, their Jacobian in (x, e_{k-1}, e_k), the next state, M, N) of one stance at
    zero errors, x the state's symbol (row_moments)."""
    nx, ne = (2, 2) if m.stairs else (1, 1)
    x, prev, cur = ca.SX.sym("x", nx), ca.SX.sym("prev", ne), ca.SX.sym("cur", ne)
    rows, state = local_step(m, x, prev, cur)
    every = ca.vertcat(x, prev, cur)
    rows, jac, state, step_jac = ca.substitute(
        [rows, ca.jacobian(rows, every), state, ca.jacobian(state, every)],
        [ca.vertcat(prev, cur)], [ca.SX.zeros(2 * ne)])
    if ca.depends_on(step_jac, x):
        raise AssertionError("the step map is not linear in its state")  # A = diag(eta^2, 1)
    big_m = ca.vertcat(step_jac[:, :nx + ne], ca.SX.zeros(ne, nx + ne))  # M = [A B_p; 0 0]
    big_n = ca.vertcat(step_jac[:, nx + ne:], ca.SX.eye(ne))  # N = [B_c; I]
    return x, rows, jac, state, big_m, big_n


def row_moments(m, stages: int, spread: Spread):
    """(g, sd): SX columns of every row of every step at the nominal build. Stance k's rows
    depend on the errors through the state x_{k-1}, the errors e_{k-1} of the step before and
    its own e_k alone, and x_k = A x_{k-1} + B_p e_{k-1} + B_c e_k (A, B constant: the map's
    Jacobians at the nominal build), so z_k = (x_k, e_k) = M z_{k-1} + N e_k. The steps' own
    errors: Q_k = cov(z_k) = M Q_{k-1} M^T + N S N^T; a row's variance H Q_{k-1} H^T +
    G_c S G_c^T (H = [g_x, g_p]). The lots and the start speed: J_k = dz_k/dlots = M J_{k-1} +
    N L, a row's gradient H J_{k-1} + G_c L. One stance differentiated once: rows and time
    linear in the steps."""
    x, rows, jac, state, big_m, big_n = linear_step(m)
    nz, ne = big_m.shape[0], big_n.shape[1]
    lots = [i for i, s in enumerate(spread.lot) if not _is_zero(s)]
    lot_map = ca.SX.zeros(ne, len(lots) + 1)  # L: a lot moves its quantity on every step
    for col, i in enumerate(lots):
        lot_map[i, col] = 1.0
    lot_var = ca.vertcat(*[ca.SX(spread.lot[i])**2 for i in lots], ca.SX(spread.start)**2)
    each = ca.diag(ca.vertcat(*[ca.SX(s)**2 for s in spread.each]))
    speed = m.scene.initial.speed
    nominal = ca.vertcat(phys.stance_energy(speed, m.beta - m.alpha, m.rate),
                         *([m.s0] if m.stairs else []))  # x_0
    cov, sens = ca.SX.zeros(nz, nz), ca.SX.zeros(nz, len(lots) + 1)
    sens[0, len(lots)] = 2.0 * speed  # dE_0 / d(start speed)
    noise = big_n @ each @ big_n.T
    gs, sds = [], []
    for _ in range(stages):
        g, j = ca.substitute([rows, jac], [x], [nominal])
        h, g_cur = j[:, :nz], j[:, nz:]
        var = (ca.sum2((h @ cov) * h) + ca.sum2((g_cur @ each) * g_cur)
               + (h @ sens + g_cur @ lot_map)**2 @ lot_var)
        gs.append(g)
        sds.append(ca.sqrt(var + SD_FLOOR))
        cov = big_m @ cov @ big_m.T + noise
        sens = big_m @ sens + big_n @ lot_map
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
    of_ground = partial(sigmas, ground=spec.scene.ground)

    def nines_of(s):
        return nines(m, spec.verification.stages,
                     spread_of(*yield_target.scaled_sigmas(spec.tolerances, s, of_ground)))

    return yield_target.target_rows(spec, symbols, bounds, nines_of)
