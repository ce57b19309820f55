"""The periodic gait of a design: `fixed_point` (period 1) and `period_two` (the two-step map's
fixed point), with their multipliers by AD (stepmap)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ...accuracy import accuracy as accuracy_preset
from . import stepmap
from .ground import ground_of, params_for
from .simulate import STATE_NAMES, one_step

SETTLE_STEPS = 60  # steps simulated from a guess Newton's method does not converge from


def fixed_point(scene, design, guess=None) -> dict:
    """The period-1 gait near `guess` (a post-strike state: 4 numbers or a mapping by
    simulate.STATE_NAMES; None: the scene's [initial]) as JSON: fixed_point {stance, swing,
    stance_rate, swing_rate}, step_length, step_period, multipliers [[re, im], ...],
    spectral_radius. Raises stepmap.GaitNotFound."""
    return find_gait(scene, design, guess).to_json()


def find_gait(scene, design, guess=None, period_time=None) -> stepmap.Gait:
    """The period-1 Gait near the guess: Newton's method from it (its step time from one
    simulated step unless given), and if that fails, from where the simulator settles."""
    params = params_for(scene, design)
    ground = ground_of(design, params)
    x = _state(scene, guess)
    try:
        T = period_time if period_time is not None else _step_time(scene, params, ground, x)
        return stepmap.gait_at(params, ground, *stepmap.solve_periodic(params, ground, x, T))
    except stepmap.GaitNotFound:
        x, T = _settle(scene, params, ground, x)
        return stepmap.gait_at(params, ground, *stepmap.solve_periodic(params, ground, x, T))


def _state(scene, guess) -> np.ndarray:
    if guess is None:
        return np.array(scene.initial.state(), dtype=float)
    if isinstance(guess, Mapping):
        return np.array([float(guess[n]) for n in STATE_NAMES])
    return np.asarray(guess, dtype=float).ravel()[:4]


def _step_time(scene, params, ground, x) -> float:
    out = one_step(params, ground, x, np.inf, accuracy_preset("fast"))
    if out.kind != "step":
        raise stepmap.GaitNotFound(f"the guess does not take a step ({out.kind})")
    return out.time


def _settle(scene, params, ground, x):
    """Simulate from x until the step repeats (or SETTLE_STEPS): (state, step time)."""
    acc = accuracy_preset("fast")
    T = None
    for _ in range(SETTLE_STEPS):
        out = one_step(params, ground, x, np.inf, acc)
        if out.kind != "step":
            raise stepmap.GaitNotFound(f"from the guess the walker falls ({out.kind}) before "
                                       "it settles into a gait")
        if np.max(np.abs(out.after - x)) < 1e-6:
            return out.after, out.time
        x, T = out.after, out.time
    return x, T


def two_step(params, ground, x0, T1, T2):
    """(state after two steps, guard of step 1, guard of step 2) from x0 with step times T1, T2."""
    _, mid, g1 = stepmap.step(params, ground, x0, T1)
    _, end, g2 = stepmap.step(params, ground, mid, T2)
    return mid, end, g1, g2


def period_two(params, ground, gait: stepmap.Gait, kick: float = 1e-2) -> stepmap.Gait | None:
    """The period-2 gait born where `gait` has a multiplier below -1 (or near it): Newton's
    method on the two-step map from the gait pushed along that multiplier's eigenvector; None
    when it converges back to the period-1 gait or not at all."""
    values, vectors = np.linalg.eig(gait.jacobian)
    k = int(np.argmin(np.abs(values + 1.0)))
    if abs(values[k].imag) > 1e-9:
        return None
    v = np.real(vectors[:, k])
    v = v / np.max(np.abs(v))
    x0 = np.asarray(gait.state)
    for size in (kick, 3 * kick, 0.3 * kick, 10 * kick):
        try:  # a flip: the two steps on either side of the period-1 gait
            xa, xb = x0 + size * v, x0 - size * v
            times = [_step_time(None, params, ground, x) for x in (xa, xb)]
            return _two_step_gait(params, ground, xa, xb, *times)
        except stepmap.GaitNotFound:
            continue
    return None


def _two_step_gait(params, ground, xa, xb, Ta, Tb):
    f = stepmap.functions(ground.stairs)["residual"]
    jac = stepmap.functions(ground.stairs)["jacobian"]
    p = np.asarray(params, dtype=float)
    g = np.array([ground.slope, ground.rise_per_length])
    z = np.array([*xa, Ta, *xb, Tb])  # (x_a, T_a, x_b, T_b): x_b = P(x_a), x_a = P(x_b)
    for _ in range(stepmap.NEWTON_ITERATIONS):
        ra, Ja = (np.asarray(v) for v in f(z[:4], z[4], p, g))
        rb, Jb = (np.asarray(v) for v in f(z[5:9], z[9], p, g))
        ra, rb = ra.ravel(), rb.ravel()
        xa, xb = z[:4], z[5:9]
        # after(x_a) = x_b, guard_a = 0, after(x_b) = x_a, guard_b = 0 (f gives after - own x)
        r = np.concatenate([ra[:4] + xa - xb, ra[4:], rb[:4] + xb - xa, rb[4:]])
        J = np.zeros((10, 10))
        J[:5, :5], J[5:, 5:] = Ja, Jb
        J[:4, :4] += np.eye(4)
        J[5:9, 5:9] += np.eye(4)
        J[:4, 5:9] -= np.eye(4)
        J[5:9, :4] -= np.eye(4)
        if np.max(np.abs(r)) < stepmap.NEWTON_TOL * 10:
            break
        z = z + np.linalg.solve(J, -r)
    else:
        raise stepmap.GaitNotFound("no period-2 gait")
    if np.max(np.abs(z[:4] - z[5:9])) < 1e-6 or not (z[4] > 0 and z[9] > 0):
        raise stepmap.GaitNotFound("the two-step map's root is the period-1 gait")
    Ma = np.asarray(jac(z[:4], z[4], p, g))
    Mb = np.asarray(jac(z[5:9], z[9], p, g))
    J2 = Mb @ Ma
    mults = stepmap.multipliers_of(J2)
    from . import physics as phys

    lengths = [float(phys.step_length(s[1], s[0], params)) for s in (z[:4], z[5:9])]
    return stepmap.Gait(state=tuple(float(v) for v in z[:4]), step_period=float(z[4] + z[9]),
                        step_length=float(np.mean(lengths)), multipliers=mults,
                        spectral_radius=float(max(abs(m) for m in mults)), jacobian=J2,
                        period=2)
