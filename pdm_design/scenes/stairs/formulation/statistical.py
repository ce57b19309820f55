"""The stairs' yield by statistical linearisation: `max_yield` on a staircase.

Every condition the stairs yield map judges (tolerances/stairs.py, docs/tolerances.md section
3) is a row g_i(x, d) >= 0 of the design x = (restitution, launch speed, rise, tread, landing
offset) and the build's deviations d: on every flight the exact gaps to the nose it passes
(physics.stairs.launch_clearances for the launch, flight_clearances after: a gap below 0 is a
`nose_hit`), and on every landing the riser behind it cleared (the ball's disc past the nose
above it: a `nose_hit` too), the tread not overshot (`skipped_step`), the ball rebounding
(`no_rebound`) and the step buildable (`unbuildable_step`); each divided by the tread, as the
map's margins are. The map's own order: stage 1 is the launch to step 1, stage k + 1 the impact
on step k and the flight to step k + 1.

The chain (chain_moments): the state after stage k is s_k = (L_k, v_k, vx_k, omega_k), the
landing place from the back of tread k, the vertical impact speed there, the horizontal speed
and the spin. Stage k + 1 reads it, part k (tread k: the nose ahead is tread_k - L_k), part
k + 1 (rise_{k+1}: the fall; tread_{k+1}: the overshoot) and the lot (restitution and friction
of the boards, the launcher's speed and place, a rise or tread toleranced per lot); every step's
deviations are independent of every other step's, so the moments are carried as for the
manipulators' palms: exact first-order covariance and second-order means in O(stages). The
impact on step k is the map's: Newton restitution, and with friction the contact rolls when
friction can stop its slip (the branch at the nominal build), so after the first impact the
spin follows vx and the horizontal speed stays constant.

The landing's drift is what fails a long staircase: the lot's restitution and launch speed
drift every landing alike (a mean error times the stage), the steps' own errors add like
sqrt(stages), so the same row fails bounce after bounce and the union bound sum_i Phi(-beta_i)
counts one build's failure many times (59 % against the map's 4 % on stairs_yield). The term
is Hunter's bound instead: each nose and overshoot row counts only the failures its own one
bounce before does not have (chain_moments.tree_nines; every failure of the map ends a run,
none is survived as the manipulators' slips are), -log10 of it (nines): 4.11 % against 4.06 %
there (docs/optimizer.md section 10).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ....formulation import chain_moments
from ....physics.ops import where
from .. import physics as phys

DESIGN = ("restitution", "launch_speed", "rise", "tread", "landing_offset")
PARTS = ("rise", "tread")
LOTS = ("restitution", "friction", "launch_speed", "launch_x", "rise_lot", "tread_lot")
NOSE, SKIP = "nose_hit", "skipped_step"
NEWTON_STEPS = 4  # from a start within a fraction of the radius: converged to rounding


def sigmas(tolerances, scale=1.0):
    """(sigma of each step's rise and tread (2,), sigma of each lot quantity (6,)) as lists of
    floats or SX (scale: a common factor) from the tolerances."""
    return chain_moments.sigmas(tolerances, PARTS, LOTS, scale)


class StairsChain:
    """The linearised stage maps of one stairs scene (design symbols DESIGN, as a vector)."""

    def __init__(self, scene):
        self.scene = scene
        self.x = ca.SX.sym("design", len(DESIGN))
        self.ek, self.ek1 = ca.SX.sym("e_k", len(PARTS)), ca.SX.sym("e_k1", len(PARTS))
        self.el = ca.SX.sym("e_lot", len(LOTS))
        self.s = ca.SX.sym("s", 4)
        self.first = self._linearised(*self._launch())
        self.middle = self._linearised(*self._bounce())

    def _linearised(self, rows, state):
        return chain_moments.linearise(rows, state, self.x, self.s, self.ek, self.ek1, self.el)

    # -- the physics: the map of tolerances/stairs.py, one build, symbols ---------------------
    def _step(self, e):
        """(rise, tread) of a step with deviations e (+ the lot's)."""
        return self.x[2] + e[0] + self.el[4], self.x[3] + e[1] + self.el[5]

    def _landing(self, landing, rise, tread, vx, vy):
        """Rows of a landing L on a step of `rise` and `tread` at speeds (vx, -vy) (each row /
        the nominal tread): the nose above the riser behind cleared (L beyond the place where
        the disc's back grazes it, and clear of the riser itself), the tread not overshot, the
        step buildable."""
        clear = ca.fmax(self._grazing(rise, vx, vy),
                        phys.riser_reach(rise, self.scene.ball.radius))
        rows = [(NOSE, landing - clear), (SKIP, tread - landing),
                ("unbuildable_step", rise), ("unbuildable_step", tread)]
        return [(name, row / self.x[3]) for name, row in rows]

    def _grazing(self, rise, vx, vy):
        """Where a landing at (vx, -vy) must be, from the riser behind, for the ball to clear
        the nose `rise` above: the falling gap's zero (physics.stairs.corner_gaps; a point
        ball's height over the nose). tau before the landing the centre is at
        (L - vx tau, r + vy tau - g tau^2 / 2), moving at (vx, -(vy - g tau)); the disc
        touches the corner with its back when the corner lies r along the normal down and
        back, -(vy - g tau, vx) / w, w = |velocity|: its height gives
        h(tau) = vy tau - g tau^2 / 2 + r (1 - vx / w) - rise = 0 (Newton from the straight
        descent's tau), its place L = vx tau + r (vy - g tau) / w. Smooth in every speed, as
        the nonsmooth gap (a minimum over roots of a cubic) is not."""
        g, r = self.scene.gravity, self.scene.ball.radius

        def w(tau):
            return ca.sqrt(vx**2 + (vy - g * tau) ** 2)

        tau = (rise - r * (1.0 - vx / w(0.0))) / vy
        for _ in range(NEWTON_STEPS):
            h = vy * tau - 0.5 * g * tau**2 + r * (1.0 - vx / w(tau)) - rise
            dh = vy - g * tau - r * vx * g * (vy - g * tau) / w(tau) ** 3
            tau = tau - h / dh
        return vx * tau + r * (vy - g * tau) / w(tau)

    def _launch(self):
        """Stage 1: from the launcher (its apex h0 - rise above the top landing, whose nose is
        x_back_1 = v0 t(h0) - landing_offset ahead of the designed launch) to step 1."""
        g, h0 = self.scene.gravity, self.scene.initial.drop_height
        _, v0, rise, _, offset = (self.x[i] for i in range(len(DESIGN)))
        rise1, tread1 = self._step(self.ek)
        speed, launch_x = v0 + self.el[2], self.el[3]
        height = h0 - rise
        ahead = v0 * ca.sqrt(2.0 * h0 / g) - offset - launch_x
        fall = height + rise1
        landing = speed * ca.sqrt(2.0 * fall / g) - ahead
        down = ca.sqrt(2.0 * g * fall)
        state = ca.vertcat(landing, down, speed, self.scene.initial.spin)
        return self._landing(landing, rise1, tread1, speed, down), state

    def _bounce(self):
        """Stage k + 1: the impact on step k and the flight to step k + 1."""
        g = self.scene.gravity
        L, v, vx, omega = (self.s[i] for i in range(4))
        eps = self.x[0] + self.el[0]
        _, tread_k = self._step(self.ek)
        rise1, tread1 = self._step(self.ek1)
        vx, omega = self._impact(vx, omega, v, eps)
        up = eps * v
        ahead = tread_k - L
        down = ca.sqrt(up**2 + 2.0 * g * rise1)
        landing = vx * (up + down) / g - ahead
        rows = [("no_rebound", eps)] + self._landing(landing, rise1, tread1, vx, down)
        return rows, ca.vertcat(landing, down, vx, omega)

    def _impact(self, vx, omega, v, eps):
        """(vx, omega) after an impact at vertical speed v: unchanged without friction; with
        it, rolling where friction can stop the contact's slip, else sliding (the map's)."""
        scene = self.scene
        ball = scene.ball
        if scene.friction == 0.0 or ball.radius == 0.0:
            return vx, omega
        mu = scene.friction + self.el[1]
        kw = {"radius": ball.radius, "mass": ball.mass, "inertia": ball.inertia}
        roll_vx, roll_omega = phys.rolling_impact(vx, omega, **kw)
        if ball.inertia == 0.0:  # the spin follows at once: always rolls
            return roll_vx, roll_omega
        demand = phys.rolling_impulse_ratio(vx, omega, -v, eps, **kw)
        slide_vx, slide_omega = phys.sliding_impact(vx, omega, -v, eps, mu, **kw)
        rolls = demand <= mu
        return where(rolls, roll_vx, slide_vx), where(rolls, roll_omega, slide_omega)


def yield_term(scene, design: dict, tolerances, stages: int, scale=1.0):
    """The max_yield objective term: nines of Hunter's bound on the failure probability (the
    union bound less every row's failures shared with its own one bounce before). design:
    the DESIGN values by name (numbers or CasADi expressions)."""
    each, lot = sigmas(tolerances, scale)
    return _nines(scene, design, stages, each, lot)


def _nines(scene, design: dict, stages: int, each, lot):
    """Nines of Hunter's bound at these step and lot sigmas (numbers or SX): one node of an
    SX graph with its value, gradient and Hessian in the free symbols (chain_moments.
    second_order_term), the same size at any number of stages."""
    x = ca.vertcat(*[design[n] for n in DESIGN])
    _, names, previous, _, pieces, _ = _functions(scene, stages)
    drifting = _drifting(previous, names)
    return chain_moments.second_order_term(
        pieces, lambda g, sd, cross: chain_moments.tree_nines(g, sd, drifting, cross),
        [x, ca.vertcat(*each), ca.vertcat(*lot)])


def _drifting(previous, names):
    """`previous` kept for the rows the landing's drift fails stage after stage (the nose
    and the overshoot); the others (a rebound, a buildable step: far from failing, and not
    drifting) count alone, as in the union bound: fewer terms for the NLP, the same bound to
    within their own tiny share."""
    keep = np.array([n in (NOSE, SKIP) for n in names])
    return np.where(keep, previous, -1)


_ROWS: dict = {}  # (scene, stages) -> (Function (x, sigma_each, sigma_lot) -> (g, sd, cross),
#                      names, previous, Function (g, sd, cross) -> nines, ChainPieces, chain)


def rows_function(scene, stages: int):
    """(Function (design vector, step sigmas, lot sigmas) -> (g, sd, cross), names, previous,
    Function (g, sd, cross) -> Hunter's nines) of `stages` bounces: the launch and stages - 1
    flights, the flights iterated (chain_moments.chain_function: one graph at any number of
    stages); built once, cached."""
    return _functions(scene, stages)[:4]


def _functions(scene, stages: int):
    key = (repr(scene), stages)
    if key not in _ROWS:
        chain = StairsChain(scene)
        pieces = chain_moments.ChainPieces(chain.first, chain.middle, stages - 1, len(DESIGN),
                                           len(PARTS), len(LOTS), neighbours=True)
        names, previous = pieces.names, np.array(pieces.previous)
        n = len(names)
        gs, sds, crosses = (ca.SX.sym(v, n) for v in ("g", "sd", "cross"))
        nines = ca.Function("nines", [gs, sds, crosses], [
            chain_moments.tree_nines(gs, sds, _drifting(previous, names), crosses)])
        _ROWS.clear()
        _ROWS[key] = (pieces.rows_function(), names, previous, nines, pieces, chain)
    return _ROWS[key]


def design_values(scene, design) -> dict:
    """The DESIGN values of a fixed design (scenes.StairsDesign), rise, tread and landing
    offset derived as the simulator derives them."""
    from ..sim import stairs_geometry

    geo = stairs_geometry(scene, design)
    return {"restitution": design.restitution, "launch_speed": design.launch_speed,
            "rise": geo.rise, "tread": geo.tread, "landing_offset": geo.landing_offset}


def row_reliability(scene, design, tolerances, stages: int, neighbours=False):
    """(g, sd, names[, previous, cross]) of every row of a fixed design as numpy arrays: the
    launch's rows, then each flight's and landing's, stage by stage; neighbours: each row's
    own one bounce before (-1: none) and their first-order covariance."""
    each, lot = sigmas(tolerances)
    values = design_values(scene, design)
    fn, names, previous, _ = rows_function(scene, stages)
    g, sd, cross = (np.asarray(v).ravel()
                    for v in fn([float(values[n]) for n in DESIGN], each, lot))
    return (g, sd, names, previous, cross) if neighbours else (g, sd, names)


def linearised_yield(scene, design, tolerances, stages: int) -> dict:
    """The linearised yield of a fixed design: 1 - Hunter's bound (the objective's), that
    failure bound, the union bound's, the smallest reliability index and the row count."""
    g, sd, names, previous, cross = row_reliability(scene, design, tolerances, stages,
                                                    neighbours=True)
    out = chain_moments.summary(g, sd, np.ones(len(names), dtype=bool))
    bound = 10.0 ** -float(rows_function(scene, stages)[3](g, sd, cross))
    return {**out, "yield": max(0.0, 1.0 - bound), "failure_bound": bound,
            "union_bound": out["failure_bound"]}


def objective_term(spec, model):
    """The stairs NLP's max_yield term (formulation/stairs/__init__.py's closed forms `model`: the
    design's restitution, launch speed, rise, tread and landing offset, numbers or symbols);
    0 unless the spec asks for it."""
    if not float(spec.objective.get("max_yield", 0.0)) > 0.0:
        return ca.SX(0.0)
    return yield_term(spec.scene, model_design(model), spec.tolerances,
                      spec.verification.stages)


def model_design(model) -> dict:
    """The DESIGN values of the stairs NLP's closed forms `model` (numbers or symbols)."""
    return {"restitution": model.eps, "launch_speed": model.v0, "rise": model.rise,
            "tread": model.tread, "landing_offset": model.L1}


def target_rows(spec, model, symbols: dict, bounds: dict):
    """A yield target's variable, row and objective (formulation/yield_target.py) on the
    closed forms `model`, the nines row Hunter's bound's (yield_term's) with the allocated
    sigmas s times their shares."""
    from ....formulation import yield_target

    yield_target.refuse_objectives(spec)
    design = model_design(model)

    def nines_of(s):
        each, lot = yield_target.scaled_sigmas(spec.tolerances, s, sigmas)
        return _nines(spec.scene, design, spec.verification.stages, each, lot)

    return yield_target.target_rows(spec, symbols, bounds, nines_of)


def placed_rows(scene, design, tolerances, stages: int):
    """The rows of the linearised yield placed along the staircase (plugin_tolerances.
    PlacedRows): place k is bounce k (the flight to step k and the landing there), every row
    counted in the union bound."""
    from ....plugin_tolerances import PlacedRows

    g, sd, names = row_reliability(scene, design, tolerances, stages)
    chain = _functions(scene, stages)[5]
    sizes = [len(chain.first[1])] + [len(chain.middle[1])] * (stages - 1)
    return PlacedRows(g, sd, names, np.ones(len(names)), np.repeat(np.arange(1, stages + 1),
                                                                    sizes),
                      ("bounce", "bounces", None))
