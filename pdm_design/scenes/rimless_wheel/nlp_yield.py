"""The rimless wheel's linearised yield inside the NLP (docs/rimless_wheel.md, section 13): the
rows of statistical.py (physics.stance_rows, written once for numbers and symbols) on the NLP's
design symbols, their gradients in every step's slope error and the start speed error by
CasADi's exact derivatives at the nominal build (statistical.py takes central differences),
sd_i^2 = sum_j (dg_i / dd_j)^2 sigma_j^2, and -log10 of the union bound sum_i Phi(-g_i / sd_i)
over every row of every step (nines): the max_yield term and a yield target's row
(formulation/yield_target.py). On a ramp; stairs are refused (Scene.max_yield_refusal and
`refuse_stairs`).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import casadi as ca

from ...errors import SpecError
from ...formulation import chain_moments
from . import physics as phys

SD_FLOOR = 1e-24  # added to every row's variance: a row no deviation moves is far from failing


def refuse_stairs(spec, key: str) -> None:
    """SpecError (exit 2) naming `key`: the NLP's linearised yield is derived on a ramp."""
    if spec.scene.ground != "ramp":
        raise SpecError(spec.source or "<spec>", key, "a ramp (scene.ground = \"ramp\"): the "
                        "rimless wheel's linearised yield is in the NLP on a ramp only (`yield` "
                        "judges stairs)", found=f"ground = \"{spec.scene.ground}\"")


def checked_sigmas(spec, key: str):
    """([every step's slope sigma, the start speed's sigma],) of the spec's tolerances; a
    SpecError naming `key` for what the linearised yield does not take."""
    from dataclasses import replace

    from .statistical import _sigmas

    try:  # an allocated tolerance is judged at a unit value
        _sigmas(spec.scene, [replace(t, value=1.0) if t.allocate else t
                             for t in spec.tolerances], spec.verification.stages)
    except ValueError as error:
        raise SpecError(spec.source or "<spec>", key, str(error), found="those tolerances") \
            from None
    return sigmas([t for t in spec.tolerances if not t.allocate])


def sigmas(tolerances, scale=1.0):
    """([every step's slope sigma, the start speed's sigma],): each value / 3 times scale
    (formulation/yield_target.scaled_sigmas's form)."""
    from ...tolerance_model import SIGMAS_PER_TOLERANCE

    slope = start = 0.0
    for t in tolerances:
        sigma = t.value / SIGMAS_PER_TOLERANCE * scale
        if t.quantity == "start_speed":
            start = start + sigma
        else:
            slope = slope + sigma
    return ([slope, start],)


def row_moments(m, stages: int, slope_sigma, start_sigma):
    """(g, sd): SX columns of every row of every step at the nominal build, on the closed forms
    `m` (formulation._Model: alpha, rate, leg, k2, eta, beta, scene). Stance k's rows depend on
    the errors through E_{k-1}, the chord before (d_{k-1}) and its own (d_k) alone, and
    E_{k-1} = eta^2 E_{k-2} + b(beta_{k-1}): dE_{k-1}/dd_j = eta^{2(k-1-j)} b', dE_{k-1}/dw_0 =
    eta^{2(k-1)} 2 w_0. So sd^2 = (g_E S)^2 sigma_w^2 + (g_E^2 V + (g_E b' + g_prev)^2 + g_cur^2)
    sigma^2, with S and V (the sum of the squared older coefficients) carried step to step:
    rows and time linear in the steps (one stance's rows differentiated once)."""
    energy, d0, d1 = ca.SX.sym("energy"), ca.SX.sym("prev_error"), ca.SX.sym("error")
    wheel = SimpleNamespace(alpha=m.alpha, rate=m.rate, leg=m.leg, k2=m.k2, eta=m.eta,
                            beta=m.beta, gravity=m.scene.gravity, friction=m.scene.friction)
    local = ca.vertcat(*[g for _, g in phys.stance_rows(wheel, energy, m.beta + d0, m.beta + d1,
                                                        m.ground)])
    jac = ca.jacobian(local, ca.vertcat(energy, d0, d1))
    offset = phys.step_offset(m.beta + d1, m.alpha, m.eta, m.rate)
    local, jac, b_slope = ca.substitute([local, jac, ca.jacobian(offset, d1)], [d0, d1],
                                        [ca.SX(0.0), ca.SX(0.0)])
    speed = m.scene.initial.speed
    nominal = phys.stance_energy(speed, m.beta - m.alpha, m.rate)  # E_0
    b = phys.step_offset(m.beta, m.alpha, m.eta, m.rate)
    start, older, gs, sds = 2.0 * speed, 0.0, [], []
    for k in range(stages):
        g, jk = ca.substitute([local, jac], [energy], [nominal])
        g_e, g_prev, g_cur = jk[:, 0], jk[:, 1], jk[:, 2]
        last = g_e * b_slope + g_prev if k else 0.0 * g_e
        var = ((g_e * start)**2 * start_sigma**2
               + (g_e**2 * older + last**2 + g_cur**2) * slope_sigma**2)
        gs.append(g)
        sds.append(ca.sqrt(var + SD_FLOOR))
        older = m.eta**4 * (older + (b_slope**2 if k else 0.0))
        start = m.eta**2 * start
        nominal = m.eta**2 * nominal + b  # E_k of the nominal build (every chord beta)
    return ca.vertcat(*gs), ca.vertcat(*sds)


def nines(m, stages: int, slope_sigma, start_sigma):
    """-log10 of the union bound over every row of every step (smooth far into the tail:
    chain_moments.log_tail and a log-sum-exp)."""
    g, sd = row_moments(m, stages, slope_sigma, start_sigma)
    logs = chain_moments.log_tail(g / sd)
    top = ca.mmax(logs)
    return -(top + ca.log(ca.sum1(ca.exp(logs - top)))) / math.log(10.0)


def objective_term(spec, m):
    """The max_yield term (nines); 0 unless the spec asks for it."""
    if not float(spec.objective.get("max_yield", 0.0)) > 0.0:
        return ca.SX(0.0)
    refuse_stairs(spec, "objective.max_yield")
    ((slope, start),) = checked_sigmas(spec, "tolerances")
    return nines(m, spec.verification.stages, slope, start)


def target_rows(spec, m, symbols: dict, bounds: dict):
    """A yield target's variable, row and objective (formulation/yield_target.py): the nines row
    with the allocated sigmas s times their shares."""
    from ...formulation import yield_target

    refuse_stairs(spec, "tolerances.yield_target")
    yield_target.refuse_objectives(spec)
    checked_sigmas(spec, "tolerances")

    def nines_of(s):
        ((slope, start),) = yield_target.scaled_sigmas(spec.tolerances, s, sigmas)
        return nines(m, spec.verification.stages, slope, start)

    return yield_target.target_rows(spec, symbols, bounds, nines_of)
