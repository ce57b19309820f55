"""The rimless wheel's linearised yield (docs/rimless_wheel.md, section 13): every condition the
step map judges, written as a continuous row g(d) >= 0 of the build's deviations d (every
step's slope on a ramp, every step's rise and tread on stairs, the start speed), linearised at
the nominal build: with d normal (sigma = t / 3, independent), row i fails with probability
Phi(-g_i / sd_i), sd_i^2 = sum_j (dg_i / dd_j)^2 sigma_j^2, and a build fails with at most the
sum over the rows and the steps (the union bound). The gradients are central differences of
the rows, every perturbed build at once on the vectorised closed forms.

Rows of stance k (k = 1..K, on chord k - 1 from phi0 = beta_{k-1} - alpha to phi1 =
beta_k + alpha, energy E_{k-1} from the step map's linear filter), each in its own unit divided
by a nominal scale: over the top (E_{k-1} / rate, where the stance starts behind the vertical),
the normal force and mu N - |F| at phi0, the top and phi1 (per unit g), the impact's normal
impulse and mu P_n - |P_t|; on stairs the nose (reach(beta_k) less the nose's distance ahead
of foothold k - 1) and the landing (tread k less foothold k's place), per unit tread.

A lot (one slope, rise or tread error for every step of a build) is one axis that moves every
step at once. Each spoke's own length is an axis of its own (it recurs at every step that
stands on or lands that spoke), a lot of spoke lengths one axis for all of them, and the hub's
mass one (it moves k^2 alone; with no spoke mass nothing: its sigma adds nothing): those builds
run a loop over the steps (`spoke_rows`, physics.spoke_step). The uniform distribution is not
linearised here: a spec with it is refused in words (ValueError).
"""

from __future__ import annotations

import numpy as np

from . import physics as phys
from .analysis import resolve
from .steps import energies

LINEARISED = {"ramp": ("slope", "start_speed", "leg_length", "mass"),
              "stairs": ("rise", "tread", "start_speed", "leg_length", "mass")}
OWN = ("leg_length", "mass")  # a build's spokes and hub
STEP = 1e-6  # central differences, in sigmas of each deviation


def _sigmas(scene, tolerances, stages):
    """(per-step sigmas {quantity: sigma}, lot sigmas {quantity: sigma}, start speed sigma);
    ValueError for what is not linearised."""
    from ...tolerance_model import SIGMAS_PER_TOLERANCE

    allowed = LINEARISED[scene.ground]
    each, lot, start = {}, {}, 0.0
    for t in tolerances:
        if t.quantity not in allowed or t.distribution != "normal" or t.value is None:
            raise ValueError("the rimless wheel's linearised yield takes normal "
                             f"{', '.join(allowed)} tolerances with values; not {t.quantity} "
                             f"({t.distribution})")
        sigma = t.value / SIGMAS_PER_TOLERANCE
        if t.quantity == "start_speed":
            start = sigma
        elif t.applies_to == "lot" or t.quantity == "mass":
            lot[t.quantity] = sigma
        else:
            each[t.quantity] = sigma
    return each, lot, start


def rows(scene, design, deviations, stages):
    """(names, g (builds, rows)): every row of every build (deviations {quantity: (builds,
    stages)}, start_speed (builds,)), on the closed forms."""
    if any(q in deviations for q in OWN):
        return spoke_rows(scene, design, deviations, stages)
    wh, geo, problems = resolve(scene, design)
    if problems:
        raise ValueError("; ".join(problems))
    builds = len(deviations["start_speed"])
    zero = np.zeros((builds, stages))
    speed = scene.initial.speed + deviations["start_speed"]
    if scene.ground == "ramp":
        betas = wh.beta + deviations.get("slope", zero)
    else:
        rises = geo["rise"] + deviations.get("rise", zero)
        betas = np.arcsin(np.clip(rises / wh.chord, -1.0, 1.0))
    e0 = phys.stance_energy(speed, wh.beta - wh.alpha, wh.rate)
    e = energies(wh, e0, betas)[:, :-1]  # E_{k-1} of stance k
    prev = np.concatenate([np.full((builds, 1), wh.beta), betas[:, :-1]], axis=1)
    found = phys.stance_rows(wh, e, prev, betas, wh.ground)  # physics.py: also the NLP's rows
    if wh.beta - wh.alpha >= 0.0:  # starts past the top: no over_the_top row
        found = found[1:]
    names, out = [n for n, _ in found], [g for _, g in found]

    def add(name, value):
        names.append(name)
        out.append(value)

    if scene.ground == "stairs":  # the footholds' drift: physics.next_foothold
        treads = np.concatenate([np.full((builds, 1), geo["tread"]),
                                 geo["tread"] + deviations.get("tread", zero)], axis=1)
        advance = phys.next_foothold(0.0, wh.chord, betas, treads[:, :-1])
        s_prev = geo["landing_offset"] + np.concatenate(
            [np.zeros((builds, 1)), np.cumsum(advance, axis=1)[:, :-1]], axis=1)
        for name, g in phys.landing_rows(wh, s_prev, betas, treads[:, :-1], treads[:, 1:],
                                         geo["tread"]):
            add(name, g)
    return names, np.stack(out, axis=2)  # (builds, stages, rows)


def spoke_rows(scene, design, deviations, stages):
    """`rows` of builds whose spokes have their own lengths (deviations["leg_length"] (builds,
    spokes)) or whose hub its own mass (deviations["mass"] (builds,)): a loop over the steps,
    stance k on spoke k - 1 landing spoke k (mod n), physics.spoke_step (the NLP's step)."""
    wh, geo, problems = resolve(scene, design)
    if problems:
        raise ValueError("; ".join(problems))
    builds, n, w = len(deviations["start_speed"]), wh.n, scene.wheel
    zero = np.zeros((builds, stages))
    lengths = wh.leg + np.asarray(deviations.get("leg_length", np.zeros((builds, n))), float)
    k2 = phys.gyration_squared(w.mass + np.asarray(deviations.get("mass", np.zeros(builds))),
                               w.gyration, w.spoke_mass, n, wh.leg)
    speed = scene.initial.speed + deviations["start_speed"]
    phi0 = np.full(builds, wh.beta - wh.alpha)
    energy = phys.stance_energy(speed, phi0, phys.stance_rate(wh.gravity, k2, lengths[:, 0]))
    stairs = scene.ground == "stairs"
    if stairs:
        s_prev, tread_before = np.full(builds, geo["landing_offset"]), np.full(builds,
                                                                             geo["tread"])
    names, out = [], []
    for k in range(stages):
        a, b = lengths[:, k % n], lengths[:, (k + 1) % n]
        chord = phys.chord_between(a, b, wh.alpha)
        beta = (wh.beta + deviations.get("slope", zero)[:, k] if not stairs else
                np.arcsin((geo["rise"] + deviations.get("rise", zero)[:, k]) / chord))
        found, after, phi1 = phys.spoke_step(wh, energy, phi0, beta, a, b, k2, wh.ground)
        if wh.beta - wh.alpha >= 0.0:  # starts past the top: no over_the_top row
            found = found[1:]
        if stairs:
            tread = geo["tread"] + deviations.get("tread", zero)[:, k]
            found += phys.landing_rows(wh, s_prev, beta, tread_before, tread, geo["tread"],
                                       chord, phys.nose_reach_between(a, wh.alpha, phi1))
            s_prev = phys.next_foothold(s_prev, chord, beta, tread_before)
            tread_before = tread
        names = [name for name, _ in found]
        out.append(np.stack([np.broadcast_to(g, (builds,)) for _, g in found], axis=1))
        energy, phi0 = after, phi1 - 2.0 * wh.alpha
    return names, np.stack(out, axis=1)  # (builds, stages, rows)


def _axes(scene, design, tolerances, stages):
    """[(quantity, step, spoke or None)] and their sigmas: each axis a step's own error, a lot
    (step "lot"), a spoke's own length (step "spoke"), the start speed (step None)."""
    each, lot, start = _sigmas(scene, tolerances, stages)
    per_step = [q for q in LINEARISED[scene.ground] if q not in ("start_speed", *OWN)]
    axes = ([(q, k) for q in per_step if q not in lot for k in range(stages)]
            + [(q, "lot") for q in (*per_step, *OWN) if q in lot])
    if "leg_length" in each:
        axes += [("leg_length", ("spoke", j)) for j in range(int(design.spokes))]
    axes.append(("start_speed", None))
    sigma = np.array([start if k is None else lot[q] if k == "lot" else each.get(q, 0.0)
                      for q, k in axes])
    return per_step, axes, sigma


def _moved(per_step, axes, sigma, stages, spokes):
    """The deviations of the nominal build and of each axis moved by +-STEP sigmas."""
    count = 2 * len(axes) + 1
    dev = {q: np.zeros((count, stages)) for q in per_step}
    dev["start_speed"] = np.zeros(count)
    if any(q == "leg_length" for q, _ in axes):
        dev["leg_length"] = np.zeros((count, spokes))
    if any(q == "mass" for q, _ in axes):
        dev["mass"] = np.zeros(count)
    for i, (q, k) in enumerate(axes):
        h = STEP * max(sigma[i], 1e-12)
        for sign, row in ((1.0, 1 + 2 * i), (-1.0, 2 + 2 * i)):
            if k is None or (k == "lot" and q == "mass"):
                dev[q][row] = sign * h
            elif k == "lot":
                dev[q][row, :] = sign * h
            else:
                dev[q][row, k[1] if isinstance(k, tuple) else k] = sign * h
    return dev


def row_reliability(scene, design, tolerances, stages: int):
    """(g, sd, names, step) of every row of every step at the nominal build, flattened: each
    axis (a step's own error, a lot's error on every step, a spoke's own length, the start
    speed) moved by +-STEP sigmas, every moved build at once."""
    per_step, axes, sigma = _axes(scene, design, tolerances, stages)
    dev = _moved(per_step, axes, sigma, stages, int(design.spokes))
    names, g = rows(scene, design, dev, stages)
    g0 = g[0]
    slopes = np.stack([(g[1 + 2 * i] - g[2 + 2 * i]) / (2.0 * STEP * max(sigma[i], 1e-12))
                       for i in range(len(axes))])  # (axes, stages, rows)
    sd = np.sqrt(np.einsum("a,asr->sr", sigma**2, slopes**2))
    step = np.repeat(np.arange(1, stages + 1)[:, None], len(names), axis=1)
    return (g0.ravel(), sd.ravel(), tuple(names) * stages, step.ravel())


def linearised_yield(scene, design, tolerances, stages: int) -> dict:
    """1 - the union bound of every row of every step: {yield, failure_bound, min_beta, rows}
    (Scene.linearised_yield)."""
    from ...formulation.chain_moments import summary

    g, sd, names, _ = row_reliability(scene, design, tolerances, stages)
    moved = (sd > 0.0) | (g <= 0.0)  # a row no deviation moves and that holds never fails
    return summary(g, np.where(sd > 0.0, sd, 1e-300), moved)


def placed_rows(scene, design, tolerances, stages: int):
    """The rows placed along the run, place k the stance k (plugin_tolerances.PlacedRows)."""
    from ...plugin_tolerances import PlacedRows

    g, sd, names, step = row_reliability(scene, design, tolerances, stages)
    return PlacedRows(g, sd, names, np.ones(len(g)), step, ("step", "steps", None))
