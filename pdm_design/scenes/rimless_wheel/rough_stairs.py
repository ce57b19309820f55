"""Steps before failure on stairs built rough: every step's rise and tread drawn normal (sigma =
t / 3), the mean first-passage time of the stairs' return map as an absorbing Markov chain
(docs/rimless_wheel.md, section 8).

The state after a step is (E, a): the stance energy referred to the vertical (as on a rough
ramp: with the rise of the next step it fixes that step) and the nose distance a = T - s, how
far ahead of the foothold the nose of its tread lies (T that tread's length, s the foothold's
place from its back). The next step draws its rise (chord angle beta = asin(rise / c)) and the
next tread T': it fails at the nose iff a > nose_reach(beta), in its stance or impact as a
ramp's step of chord beta on level treads, and its landing misses tread T' iff
a' = a + T' - c cos beta <= 0; E' = eta^2 E + b(beta), and the next stance must start (E' and
beta: `rough.starts`). E is binned as on a ramp, a over (0, c]; the rise's normal is integrated
by the midpoint rule over +-8 sigma (NODES points: the pass set's edges cost O(1 / NODES)), the
tread's exactly (Phi differences into each a bin). m = (I - Q)^{-1} (Q 1 + s) as in rough.py,
the start (E_0, a_0) its exact state.
"""

from __future__ import annotations

import numpy as np

from . import physics as phys
from .analysis import resolve
from .rough import _blas_one_thread, _post, _pre, sigma_of

NODES = 801
BINS = (40, 40)  # stance-energy bins, nose-distance bins
COARSE = (30, 30)  # the second resolution of the interval
SPAN = 8.0  # sigmas of the rise error integrated over
CHUNK = 16  # states whose transitions are computed together


def _stairs(scene, design):
    if scene.ground != "stairs":
        raise ValueError("the stairs chain is for stairs (ground = \"stairs\")")
    wh, geo, problems = resolve(scene, design)
    if problems:
        raise ValueError("; ".join(problems))
    return wh, geo


def _transitions(wh, geo, energies, noses, e_edges, a_edges, sigma_r, sigma_t):
    """(Q (states, E bins * a bins), pre, post) from each state (energies[i], noses[i]), a
    CHUNK of states at a time: a state's rows hold (nodes, a bins) numbers (33,000 at 801 x
    41), so 1,600 states at once held gigabytes; each row is the same sum either way."""
    parts = [_transitions_of(wh, geo, energies[i:i + CHUNK], noses[i:i + CHUNK], e_edges,
                             a_edges, sigma_r, sigma_t)
             for i in range(0, len(energies), CHUNK)]
    return tuple(np.concatenate(column) for column in zip(*parts))


def _transitions_of(wh, geo, energies, noses, e_edges, a_edges, sigma_r, sigma_t):
    """_transitions of a few states."""
    from scipy.special import ndtr

    z = np.linspace(-SPAN, SPAN, NODES)
    weight = np.exp(-0.5 * z**2) / np.sqrt(2.0 * np.pi) * (z[1] - z[0])
    rise = geo["rise"] + sigma_r * z
    ok_rise = (rise >= 0.0) & (rise < wh.chord)
    beta = np.arcsin(np.clip(rise / wh.chord, 0.0, 1.0 - 1e-15))
    e = energies[:, None]
    pre = _pre(wh, e, beta[None, :]) & ok_rise[None, :]
    pre &= noses[:, None] <= phys.nose_reach(wh.leg, wh.alpha, beta)[None, :]
    survive = pre & _post(wh, e, beta[None, :])
    nxt = wh.eta**2 * e + phys.step_offset(beta, wh.alpha, wh.eta, wh.rate)[None, :]
    e_bin = np.clip(np.searchsorted(e_edges, nxt) - 1, 0, len(e_edges) - 2)
    # a' = a + T' - c cos beta: into a bin [lo, hi) iff T' in [lo - shift, hi - shift)
    shift = noses[:, None] - wh.chord * np.cos(beta)[None, :]  # (states, nodes)
    cuts = ndtr((a_edges[None, None, :] - shift[..., None] - geo["tread"]) / sigma_t)
    into = np.diff(cuts, axis=2)  # (states, nodes, a bins); below a_edges[0] = 0: missed
    mass = (weight[None, :] * survive)[..., None] * into
    states, bins_e, bins_a = len(energies), len(e_edges) - 1, len(a_edges) - 1
    # sum the nodes' mass into each (E bin, a bin): rows of one state add up by bincount
    index = (np.arange(states)[:, None] * bins_e + e_bin)[..., None] * bins_a + np.arange(bins_a)
    q = np.bincount(index.ravel(), weights=mass.ravel(),
                    minlength=states * bins_e * bins_a).reshape(states, bins_e * bins_a)
    # the step is made when its stance, impact and nose pass and it lands on its tread
    # (a' > 0); a landing beyond the grid's top (a' > c) fails at the next nose: made, then
    # failed, as a next stance that does not start
    lands = (weight[None, :] * pre * (1.0 - cuts[..., 0])).sum(axis=1)
    return q, 1.0 - lands, np.maximum(lands - q.sum(axis=1), 0.0)


def stairs_mfpt(scene, design, rise_tolerance: float, tread_tolerance: float, *,
                bins: tuple[int, int] = BINS) -> float:
    """Mean steps before failure on rough stairs (module docstring), by the chain of bins
    (E bins, nose-distance bins)."""
    wh, geo = _stairs(scene, design)
    sigma_r, sigma_t = sigma_of(rise_tolerance), sigma_of(tread_tolerance)
    start = float(phys.stance_energy(scene.initial.speed, wh.beta - wh.alpha, wh.rate))
    spread = [float(phys.periodic_energy(np.arcsin(np.clip((geo["rise"] + d) / wh.chord, 1e-9,
                                                           1 - 1e-9)),
                                         wh.alpha, wh.eta, wh.rate, wh.loss))
              for d in (-SPAN * sigma_r, SPAN * sigma_r)]
    e_edges = np.linspace(min(min(spread), 0.0, start), max(max(spread), start), bins[0] + 1)
    a_edges = np.linspace(0.0, wh.chord, bins[1] + 1)
    ec, ac = 0.5 * (e_edges[:-1] + e_edges[1:]), 0.5 * (a_edges[:-1] + a_edges[1:])
    energies, noses = np.repeat(ec, bins[1]), np.tile(ac, bins[0])
    q, fail_pre, post = _transitions(wh, geo, energies, noses, e_edges, a_edges, sigma_r,
                                     sigma_t)
    diagonal = np.arange(len(energies))
    off = q.copy()
    off[diagonal, diagonal] = 0.0
    lhs = -off
    lhs[diagonal, diagonal] = fail_pre + post + off.sum(axis=1)
    with _blas_one_thread():
        m = np.linalg.solve(lhs, q.sum(axis=1) + post)
    q0, _, post0 = _transitions(wh, geo, np.array([start]),
                                np.array([geo["tread"] - geo["landing_offset"]]), e_edges,
                                a_edges, sigma_r, sigma_t)
    return float(q0[0] @ (1.0 + m) + post0[0])


def mfpt_interval(scene, design, rise_tolerance: float, tread_tolerance: float) -> dict:
    """{estimate, ci_low, ci_high, method}: the chain at BINS, and the discretisation's
    interval: it and the chain at COARSE, widened on each side by their difference."""
    fine = stairs_mfpt(scene, design, rise_tolerance, tread_tolerance, bins=BINS)
    coarse = stairs_mfpt(scene, design, rise_tolerance, tread_tolerance, bins=COARSE)
    spread = abs(fine - coarse)
    return {"estimate": fine, "ci_low": min(fine, coarse) - spread,
            "ci_high": max(fine, coarse) + spread,
            "method": f"markov chain on (stance energy, nose distance) bins, {COARSE[0]} x "
                      f"{COARSE[1]} and {BINS[0]} x {BINS[1]}"}

