"""The step map in CasADi: one step's flow by fixed-step RK4, the heel strike as its guard, the
periodic gait as a root of `state after one step - state`, and its multipliers by AD.

The stance phase is integrated by SUBSTEPS classical RK4 steps of T / SUBSTEPS (T the step's
time, a variable); the flow and every derivative of it are exact to rounding for that
discretisation, and the discretisation is within ~1e-10 of the exact flow on the gaits of this
scene (tests/test_compass_gait_multipliers.py checks it against the event simulator).

The return map on post-heel-strike states x = (q1, q2, w1, w2): P(x) = strike(phi(T(x), x)) with
T(x) the root of guard(phi(T, x)) = 0. Its Jacobian (implicit function theorem)
    dP/dx = P_x - P_T G_x / G_T
has rank 3 (every image satisfies the section's equation): one eigenvalue is 0 identically, the
other three are the gait's multipliers.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from . import physics as phys

SUBSTEPS = 200
NEWTON_TOL = 1e-12
NEWTON_ITERATIONS = 30


class GaitNotFound(ValueError):
    """No periodic gait near the guess (Newton did not converge or found a degenerate step)."""


@dataclass(frozen=True)
class Ground:
    """slope (rad, the ramp's descent) and rise per leg length (stairs; 0 on a ramp)."""

    slope: float
    rise_per_length: float = 0.0

    @property
    def stairs(self) -> bool:
        return self.rise_per_length != 0.0


def _rhs(ca, x, p):
    q1, q2, w1, w2 = x[0], x[1], x[2], x[3]
    a1, a2 = phys.accelerations(q1, q2, w1, w2, phys.Params(*[p[i] for i in range(6)]))
    return ca.vertcat(w1, w2, a1, a2)


@functools.lru_cache(maxsize=4)
def functions(stairs: bool, substeps: int = SUBSTEPS):
    """CasADi Functions of (x0[4], T, params[6], ground[2]): 'step' -> (x_end, after, guard),
    'residual' -> (r[5], dr/d(x0, T)), 'jacobian' -> dP/dx (4x4). ground = (slope, rise / l)."""
    import casadi as ca

    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 6)
    h = ca.SX.sym("h")
    k1 = _rhs(ca, x, p)
    k2 = _rhs(ca, x + h / 2 * k1, p)
    k3 = _rhs(ca, x + h / 2 * k2, p)
    k4 = _rhs(ca, x + h * k3, p)
    rk4 = ca.Function("rk4", [x, h, p], [x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    flow = rk4.mapaccum("flow", substeps, [0], [0])

    x0, T = ca.MX.sym("x0", 4), ca.MX.sym("T")
    pm, gm = ca.MX.sym("p", 6), ca.MX.sym("ground", 2)
    end = flow(x0, T / substeps, pm)[:, -1]
    params = phys.Params(*[pm[i] for i in range(6)])
    after = ca.vertcat(*phys.heel_strike(end[0], end[1], end[2], end[3], params))
    rise = gm[1] if stairs else 0.0
    guard = phys.strike_guard(end[0], end[1], gm[0], rise)
    step = ca.Function("step", [x0, T, pm, gm], [end, after, guard])
    z = ca.vertcat(x0, T)
    r = ca.vertcat(after - x0, guard)
    residual = ca.Function("residual", [x0, T, pm, gm], [r, ca.jacobian(r, z)])
    P_x, P_T = ca.jacobian(after, x0), ca.jacobian(after, T)
    G_x, G_T = ca.jacobian(guard, x0), ca.jacobian(guard, T)
    jac = ca.Function("jacobian", [x0, T, pm, gm], [P_x - P_T @ G_x / G_T])
    return {"step": step, "residual": residual, "jacobian": jac}


@dataclass(frozen=True)
class Gait:
    """A periodic gait: the post-heel-strike state it returns to (q1, q2, w1, w2), its step time
    (s) and length (m), its multipliers (complex, largest modulus first) and spectral radius."""

    state: tuple[float, float, float, float]
    step_period: float
    step_length: float
    multipliers: tuple[complex, ...]
    spectral_radius: float
    jacobian: np.ndarray
    period: int = 1

    @property
    def stable(self) -> bool:
        return self.spectral_radius < 1.0

    def to_json(self) -> dict:
        q1, q2, w1, w2 = self.state
        return {
            "fixed_point": {"stance": q1, "swing": q2, "stance_rate": w1, "swing_rate": w2},
            "step_length": self.step_length, "step_period": self.step_period,
            "multipliers": [[m.real, m.imag] for m in self.multipliers],
            "spectral_radius": self.spectral_radius, "period": self.period,
        }


def multipliers_of(jacobian: np.ndarray, trivial: int = 1) -> tuple[complex, ...]:
    """The eigenvalues of a return map's Jacobian less its `trivial` smallest (the section's
    zeros), largest modulus first."""
    values = np.linalg.eigvals(jacobian)
    order = np.argsort(-np.abs(values), kind="stable")
    kept = values[order][: len(values) - trivial]
    return tuple(complex(v) for v in kept)


def solve_periodic(params, ground: Ground, state, period_time,
                   tol: float = NEWTON_TOL) -> tuple[np.ndarray, float]:
    """Newton's method on (x0, T): strike(phi(T, x0)) = x0 and guard(phi(T, x0)) = 0, from the
    guess (state, period_time). Returns (x0, T) or raises GaitNotFound."""
    f = functions(ground.stairs)["residual"]
    p = np.asarray(params, dtype=float)
    g = np.array([ground.slope, ground.rise_per_length])
    z = np.array([*state, period_time], dtype=float)
    scale = 1.0
    for _ in range(NEWTON_ITERATIONS):
        r, J = f(z[:4], z[4], p, g)
        r, J = np.asarray(r).ravel(), np.asarray(J)
        norm = float(np.max(np.abs(r)))
        if not math.isfinite(norm):
            break
        if norm <= tol * max(1.0, float(np.max(np.abs(z[2:4]))) * abs(z[4])):
            return _checked(z)
        try:
            dz = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            break
        # damp steps that would change the step time by more than half of it
        limit = 0.5 * abs(z[4]) / max(abs(dz[4]), 1e-300)
        scale = min(1.0, limit)
        z = z + scale * dz
    raise GaitNotFound("Newton's method on the periodic gait did not converge from the guess "
                       f"(stance {state[0]:.4g}, swing {state[1]:.4g} rad, step time "
                       f"{period_time:.4g} s)")


def _checked(z):
    x0, T = z[:4], float(z[4])
    if not T > 0.0 or not x0[1] > x0[0]:
        raise GaitNotFound(f"Newton's method converged to a degenerate step (step time {T:.4g} "
                           f"s, stance {x0[0]:.4g}, swing {x0[1]:.4g} rad)")
    return x0.copy(), T


def gait_at(params, ground: Ground, x0, T) -> Gait:
    """The Gait of a solved fixed point: multipliers from the AD Jacobian of the return map."""
    jac = np.asarray(functions(ground.stairs)["jacobian"](
        x0, T, np.asarray(params, dtype=float), [ground.slope, ground.rise_per_length]))
    mults = multipliers_of(jac)
    p = phys.Params(*params)
    return Gait(state=tuple(float(v) for v in x0), step_period=float(T),
                step_length=float(phys.step_length(x0[1], x0[0], p)),
                multipliers=mults, spectral_radius=float(max(abs(m) for m in mults)),
                jacobian=jac)


def step(params, ground: Ground, x0, T):
    """(state before the strike, state after it, guard) after time T from x0 (the RK4 flow)."""
    end, after, guard = functions(ground.stairs)["step"](
        x0, T, np.asarray(params, dtype=float), [ground.slope, ground.rise_per_length])
    return np.asarray(end).ravel(), np.asarray(after).ravel(), float(guard)
