"""The rimless wheel's step map on many wheels and many steps at once (numpy), for long runs,
Monte Carlo on rough ground and the build checks.

Stance k (k = 1..K) starts on chord k - 1 (the stance spoke at beta_{k-1} - alpha) with energy
E_{k-1} and ends on chord k (at beta_k + alpha); E_k = eta^2 E_{k-1} + step_offset(beta_k), run
by a first-order linear filter. Each stance is checked where its conditions are judged in closed
form: its start (the energy to vault: stalled; the forces: flight, slip), the top (the spoke
vertical, where the normal force is least for a point mass) and its end, and its impact
(friction, the impulse pushing); on stairs, the landing spoke's nose (nose_hit) and the foothold
on its tread (missed_tread). A failure in stance k leaves k - 1 steps passed, as in the event
simulator. Between the checked angles a stance is not checked (the event simulator is the judge
there; docs/rimless_wheel.md, sections 8 and 10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import physics as phys
from .analysis import WheelNumbers

CODES = ("", "stalled", "flight", "slip", "nose_hit", "missed_tread")
OK, STALLED, FLIGHT, SLIP, NOSE, MISSED = range(6)


@dataclass(frozen=True)
class StepRun:
    """passed: steps each wheel made before its failure (K if none); failure: its code (index in
    CODES, 0 for none); energies: E_0..E_K per wheel when kept."""

    passed: np.ndarray
    failure: np.ndarray
    energies: np.ndarray | None = None

    def kinds(self) -> list[str]:
        return [CODES[c] for c in self.failure]


def energies(wh: WheelNumbers, start_energy, betas):
    """E_0..E_K of each wheel (rows) over chords betas (N, K): a linear filter."""
    from scipy.signal import lfilter

    betas = np.atleast_2d(betas)
    q = wh.eta**2
    offset = phys.step_offset(betas, wh.alpha, wh.eta, wh.rate)
    e0 = np.broadcast_to(np.asarray(start_energy, float), (betas.shape[0],))
    out = lfilter([1.0], [1.0, -q], offset, axis=1, zi=(q * e0)[:, None])[0]
    return np.concatenate([e0[:, None], out], axis=1)


def point_failures(wh: WheelNumbers, energy, phi, ground):
    """Codes (FLIGHT, SLIP or OK) of the stance force conditions at angle phi."""
    w2 = phys.speed_squared(energy, phi, wh.rate)
    normal, tangential = phys.stance_forces(phi, w2, ground, wh.leg, wh.gravity, wh.k2)
    return np.where(normal <= 0.0, FLIGHT,
                    np.where(np.abs(tangential) > wh.friction * normal, SLIP, OK))


def stance_failures(wh: WheelNumbers, energy, beta_prev, beta, ground):
    """Code of stance k's first failure (its start, top, end, then its impact) from E_{k-1},
    beta_{k-1} and beta_k (arrays of one shape)."""
    phi0, phi1 = beta_prev - wh.alpha, beta + wh.alpha
    code = np.where(phi1 <= phi0, MISSED, OK)
    code = np.where((code == OK) & (phi0 < 0.0) & (energy <= 0.0), STALLED, code)
    for phi in (phi0, np.where((phi0 < 0.0) & (phi1 > 0.0), 0.0, phi0), phi1):
        code = np.where(code == OK, point_failures(wh, energy, phi, ground), code)
    normal, tangential = phys.impact_impulses(wh.eta, wh.alpha, beta, ground)
    impact = np.where(normal <= 0.0, FLIGHT,
                      np.where(np.abs(tangential) > wh.friction * normal, SLIP,
                               STALLED if wh.eta <= 0.0 else OK))
    return np.where(code == OK, impact, code)


def step_map(wh: WheelNumbers, start_speed, betas, *, ground: float, keep: bool = False,
             stairs: dict | None = None) -> StepRun:
    """Run wheels (rows of betas, (N, K): chord angles of steps 1..K; beta_0 = wh.beta, the
    ground as designed) from post-impact speed start_speed (a number or (N,)). stairs: the
    geometry {tread (N, K+1) tread 0..K lengths, landing_offset} for the landing checks."""
    betas = np.atleast_2d(np.asarray(betas, float))
    n, k = betas.shape
    e0 = phys.stance_energy(np.asarray(start_speed, float), wh.beta - wh.alpha, wh.rate)
    e = energies(wh, e0, betas)
    prev = np.concatenate([np.full((n, 1), wh.beta), betas[:, :-1]], axis=1)
    codes = stance_failures(wh, e[:, :-1], prev, betas, ground)
    if stairs is not None:
        codes = np.where(codes == OK, _landing_failures(wh, betas, stairs), codes)
    failed = codes != OK
    first = np.where(failed.any(axis=1), failed.argmax(axis=1), k)
    failure = np.where(first < k, codes[np.arange(n), np.minimum(first, k - 1)], OK)
    return StepRun(first, failure, e if keep else None)


def _landing_failures(wh: WheelNumbers, betas, stairs):
    """NOSE where step k's landing spoke meets the nose of tread k - 1, MISSED where its
    foothold is beyond tread k's nose: footholds s_k = s_{k-1} + chord cos beta_k - tread_{k-1}."""
    treads = np.broadcast_to(stairs["tread"], (betas.shape[0], betas.shape[1] + 1))
    advance = wh.chord * np.cos(betas)
    s = stairs["landing_offset"] + np.cumsum(advance - treads[:, :-1], axis=1)
    s_prev = np.concatenate([np.full((betas.shape[0], 1), stairs["landing_offset"]), s[:, :-1]],
                            axis=1)
    nose = treads[:, :-1] - s_prev
    reach = phys.nose_reach(wh.leg, wh.alpha, betas)
    return np.where(nose > reach, NOSE, np.where(s >= treads[:, 1:], MISSED, OK))


def spoke_map(wh: WheelNumbers, start_speed, lengths, k2, *, ground: float, betas=None,
              stairs: dict | None = None) -> StepRun:
    """The step map of builds whose spokes have their own lengths and whose mass distribution
    its own k^2: lengths (N, n) spoke j's length (step k stands on spoke (k - 1) mod n and
    lands spoke k mod n), k2 (N,). A loop over the steps, each on every build at once (the
    map's coefficients change from step to step: no linear filter). The ground: betas (N, K),
    each step's chord angle (a ramp); or stairs {rise (N, K), tread (N, K + 1), landing_offset}
    where a step's chord angle is asin(rise / the distance between the two tips). The wheel
    starts as `step_map`'s: its stance spoke at wh.beta - alpha, at start_speed."""
    import dataclasses

    lengths = np.asarray(lengths, float)
    n_builds, n = lengths.shape
    k2 = np.broadcast_to(np.asarray(k2, float), (n_builds,))
    steps = (betas if stairs is None else stairs["rise"]).shape[1]
    alpha, g = wh.alpha, wh.gravity
    omega = np.broadcast_to(np.asarray(start_speed, float), (n_builds,)).copy()
    phi0 = np.full(n_builds, wh.beta - alpha)
    passed = np.full(n_builds, steps)
    failure = np.zeros(n_builds, dtype=int)
    alive = np.ones(n_builds, dtype=bool)
    s_prev = np.full(n_builds, stairs["landing_offset"]) if stairs else None
    for k in range(1, steps + 1):
        a, b = lengths[:, (k - 1) % n], lengths[:, k % n]
        rate = 2.0 * g * a / (k2 + a**2)
        at = dataclasses.replace(wh, leg=a, k2=k2, rate=rate)
        code = np.full(n_builds, OK)
        if stairs is None:
            beta = betas[:, k - 1]
        else:
            chord = phys.chord_between(a, b, alpha)
            ratio = stairs["rise"][:, k - 1] / chord
            code = np.where((ratio < 0.0) | (ratio >= 1.0), MISSED, code)
            beta = np.arcsin(np.clip(ratio, 0.0, 1.0 - 1e-15))
        phi1 = phys.chord_offset(a, b, alpha) + beta
        energy = phys.stance_energy(omega, phi0, rate)
        code = np.where((code == OK) & (phi1 <= phi0), MISSED, code)
        code = np.where((code == OK) & (phi0 < 0.0) & (energy <= 0.0), STALLED, code)
        top = np.where((phi0 < 0.0) & (phi1 > 0.0), 0.0, phi0)
        for phi in (phi0, top, phi1):
            code = np.where(code == OK, point_failures(at, energy, phi, ground), code)
        if stairs is not None:
            nose = stairs["tread"][:, k - 1] - s_prev
            s_new = s_prev + chord * np.cos(beta) - stairs["tread"][:, k - 1]
            code = np.where((code == OK) & (nose > phys.nose_reach_between(a, alpha, phi1)),
                            NOSE, code)
            code = np.where((code == OK) & (s_new >= stairs["tread"][:, k]), MISSED, code)
            s_prev = s_new
        eta = phys.impact_ratio_between(k2, a, b, alpha)
        normal, tangential = phys.impact_impulses_between(eta, a, b, alpha, phi1, ground)
        impact = np.where(normal <= 0.0, FLIGHT,
                          np.where(np.abs(tangential) > wh.friction * normal, SLIP,
                                   np.where(eta <= 0.0, STALLED, OK)))
        code = np.where(code == OK, impact, code)
        fails = alive & (code != OK)
        passed = np.where(fails, k - 1, passed)
        failure = np.where(fails, code, failure)
        alive &= ~fails
        omega = eta * np.sqrt(np.maximum(phys.speed_squared(energy, phi1, rate), 0.0))
        phi0 = phi1 - 2.0 * alpha
    return StepRun(passed, failure)
