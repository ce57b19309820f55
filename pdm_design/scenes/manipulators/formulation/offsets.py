"""The manipulators' conditions as explicit functions of every pivot's offset (no worst case).

d = (dx_1..dx_N, dy_1..dy_{N+1}): pivot K moved by (dx_K, dy_K) (y up) from its nominal place;
the object lands on palms 1..N and palm N hands it over to palm N+1 (whose dx does not matter).
Stage by stage, with the closed forms of `physics.manipulators`:
    first landing  Q = sqrt(vy0^2 + 2 g (H - dy_1)),  u_1 = m/(m+M) (vx0 cos a - Q sin a),
                   o_1 = C0 + vx0 (vy0 + Q) / g - dx_1
    handover K->K+1 at cos th = cos b + (dy_{K+1} - dy_K) / l,
                   speed v^2 = u_K^2 + 2 g l (cos a - cos th)
    landing on K+1 u_{K+1} = m/(m+M) v cos(a + th),
                   o_{K+1} = o_K + l (sin th - sin b) - (dx_{K+1} - dx_K)

The row is a chain of stage maps (banded: stage K reads the state (u_K, o_K) and the offsets of
pivots K - P .. K + 1, P the parked palms checked), each a small CasADi Function written once:
`Stages`. Two uses:
* `scenario`: the whole row as one Function of d (the calls inlined), for the cvxpy linearisation
  (solve/tolerance.py, built only when asked: it grows with the row);
* `Stages.stream`: many offset samples pushed through the chain stage by stage in numpy (the
  sampled check, solve/check.py), keeping only the state, the offset window and the worst row:
  memory flat in the number of stages.
"""

from __future__ import annotations

import functools
import threading
from dataclasses import replace

import casadi as ca
import numpy as np

from ....formulation.common import MARGIN, VALIDITY, ConditionInfo, Scenario
from .. import physics as phys
from .rows import CARRY_CELLS, impact_rows, join, nonzero, scene_sizes


class Stages:
    """The stage maps of one formulation's row (design symbols x as the formulation's; with
    scene parameters, formulation/parametric.py, x is followed by them: `bind`)."""

    def __init__(self, spec, model, m, parameters=None):
        self.spec, self.m = spec, m
        self.N, self.P = spec.verification.stages, m.parked
        self.x = ca.vertcat(*model.design_symbols.values(), *(s for _, s, _, _ in model.aux),
                            *([] if parameters is None else [parameters]))
        self._parked = _parked_clearance(spec, m)
        self._cache: dict[tuple, tuple] = {}
        self._maps: dict[tuple[int, int], object] = {}
        self._lock = threading.Lock()  # stream's buffers are this object's: one stream at once

    def __call__(self) -> Scenario:
        """The whole row's scenario (Formulation.scenario builds it on first use)."""
        return self.scenario()

    def reach(self, values: dict) -> int:
        """The parked palms that can reach the object at a design (values by name:
        `parked_rows` with the design's values for bounds)."""
        from . import parked_rows

        return parked_rows(self.spec.scene, values, {}, self.N)

    def bind(self, numbers, spec) -> Bound:
        """These maps at one spec's scene numbers (the parameters after x)."""
        return Bound(self, np.asarray(numbers, dtype=float), spec)

    @functools.cached_property
    def start(self):
        return self._start()

    # -- the maps -------------------------------------------------------------------------------
    def _start(self):
        """(Function (x, dx_1, dy_1) -> (rows, u_1, o_1), row templates): the first landing."""
        m = self.m
        dx1, dy1 = ca.SX.sym("dx1"), ca.SX.sym("dy1")
        rows: list[tuple] = []
        add = _adder(rows)
        add("start_height", "palm 1", m.H - dy1, m.l, VALIDITY)
        Q = m.fall_speed(dy1)
        u = m.first_speed(Q)
        add("forward_landing", "palm 1", u, m.k * ca.sqrt(m.vx0**2 + Q**2), VALIDITY)
        o = m.C0 + m.vx0 * m.flight_time(dy1) - dx1
        px, py = phys.landing_impulse(m.vx0, -Q, m.a, m.q)
        impact_rows(add, scene_sizes(self.spec.scene), "first_slip_impact", "first_tip_impact",
                    "palm 1", px, py, [o], [o])
        fn = ca.Function("first_landing", [self.x, dx1, dy1],
                         [_stack(rows, 2), _stack(rows, 3), u, o])
        return fn, rows

    def stage(self, K: int, reach: int | None = None):
        """(Function (x, u_K, o_K, dx window, dy window) -> (slack, scale, u_K+1, o_K+1), row
        templates) of stage K: carry on palm K, handover to K+1, landing on it (none after the
        last). Windows: pivots K - P .. K + 1 (P + 2 values; those before pivot 1 unused).
        reach: the parked palms to check (at most P, the default)."""
        n_parked = min(K - 1, self.P if reach is None else min(reach, self.P))
        key = (K == 1, n_parked, K == self.N)
        if key not in self._cache:
            self._cache[key] = self._stage(*key)
        return self._cache[key]

    def _stage(self, first_stage: bool, n_parked: int, last: bool):
        m, scene, P = self.m, self.spec.scene, self.P
        a, b, l, g = m.a, m.b, m.l, m.g
        body, palm = scene.body, scene.palm
        mu, W, w, h = palm.friction, palm.width, body.width, body.height
        u, o = ca.SX.sym("u"), ca.SX.sym("o")
        wdx, wdy = ca.SX.sym("wdx", P + 2), ca.SX.sym("wdy", P + 2)
        at = P  # window index of pivot K (pivot K + j at P + j)
        rows: list[tuple] = []
        add = _adder(rows)
        first = "first_" if first_stage else ""
        where = "palm {K}"
        add("landing", f"{where}, ahead", W / 2 - o - w / 2, W / 2)
        add("landing", f"{where}, behind", W / 2 + o - w / 2, W / 2)
        if m.steps:  # pivot damping: the integrated carry's slowest point
            add(f"{first}over_the_top", where, m.carry_v2(u, b, lowest=True)[1], u**2)
        else:
            add(f"{first}over_the_top", where, u**2 - m.top_needed, u**2)
        if m.plain:
            held = phys.lift_off_capacity(a, gravity=g, link_length=l)
            demand = phys.friction_demand(a)
            fp_back = phys.carry_force_point(-a, h)  # ahead of the centre
        else:  # links or pivots: the contact force depends on the speed (docs/physics.md 2.1)
            held, demand, fp_back = m.contact(-a, u**2)
            fp_back = fp_back * h
        add(f"{first}lift_off", f"{where}, back stop", held - u**2, held)
        add("slip_carry", f"{where}, back stop", mu - demand, mu)
        add("tip_carry", f"{where}, back stop, object's front edge", w / 2 - fp_back, w / 2)
        add("tip_carry", f"{where}, back stop, palm's front edge", W / 2 - o - fp_back, W / 2 - o)
        delta = wdy[at + 1] - wdy[at]
        cth = ca.cos(b) + delta / l
        th = ca.acos(cth)
        add("palm_clearance", "palm {K1}", m.pitch_y - delta, l)
        for n in range(1, n_parked + 1):  # palm K - n, parked at its front stop
            # pivot K - n from pivot K: n pitches back and up, plus the two offsets' difference
            add("parked_palms", f"{where}, palm {{K_{n}}} parked", self._parked(
                th, n * m.pitch_x - (wdx[at - n] - wdx[at]),
                n * m.pitch_y + (wdy[at - n] - wdy[at]), o, a, l), l)
        if palm.front_stop < ca.pi / 2:
            add("front_stop", where, palm.front_stop - th, palm.front_stop)
        v2 = m.carry_v2(u, th)
        if m.plain:
            held = g * l * cth  # lift_off_capacity(th), without cos(acos(.))
            demand = phys.friction_demand(th)
            fp_front = -phys.carry_force_point(th, h)  # behind the centre
        else:
            held, demand, fp_front = m.contact(th, v2)
            fp_front = -fp_front * h
        add(f"{first}lift_off", f"{where}, handover", held - v2, held)
        add("slip_carry", f"{where}, handover", mu - demand, mu)
        add("tip_carry", f"{where}, handover, object's rear edge", w / 2 - fp_front, w / 2)
        add("tip_carry", f"{where}, handover, palm's rear edge", W / 2 + o - fp_front, W / 2 + o)
        if not m.plain and not nonzero(m.delta):  # with damping the rows stay at the ends
            _whole_carry_rows(add, m, scene, u, th, o, where, f"{first}lift_off")
        u_next, o_next = u, o
        if not last:
            v = ca.sqrt(v2)
            u_next = phys.landing_speed(v * ca.cos(th), -v * ca.sin(th), a, m.q)
            add("forward_landing", "palm {K1}", u_next / v, m.k, VALIDITY)
            o_next = o + l * (ca.sin(th) - ca.sin(b)) - (wdx[at + 1] - wdx[at])
            px, py = phys.landing_impulse(ca.cos(th), -ca.sin(th), a, m.q)
            impact_rows(add, scene_sizes(scene), "slip_impact", "tip_impact", "palm {K1}", px, py,
                        [o_next], [o_next])
        fn = ca.Function("stage", [self.x, u, o, wdx, wdy],
                         [_stack(rows, 2), _stack(rows, 3), u_next, o_next])
        return fn, rows

    # -- the row as one Function ----------------------------------------------------------------
    def scenario(self) -> Scenario:
        N, P = self.N, self.P
        dx, dy = ca.SX.sym("dx", N), ca.SX.sym("dy", N + 1)
        zero = ca.SX(1, 1)

        def window(v, K):  # pivots K - P .. K + 1 (1-based) of v, zeros outside it
            return ca.vertcat(*[v[j - 1] if 1 <= j <= v.shape[0] else zero
                                for j in range(K - P, K + 2)])

        fn, rows = self.start
        slack, scale, u, o = fn(self.x, dx[0], dy[0])
        slacks, scales, infos = [slack], [scale], _infos(rows, 1, 0)
        for K in range(1, N + 1):
            fn, rows = self.stage(K)
            slack, scale, u, o = fn(self.x, u, o, window(dx, K), window(dy, K))
            slacks.append(slack)
            scales.append(scale)
            infos += _infos(rows, K, len(infos))
        d = ca.vertcat(dx, dy)
        function = ca.Function("offsets", [self.x, d], [ca.vertcat(*slacks), ca.vertcat(*scales)])
        # dy of pivot N + 1: what receives the object from N
        names = (tuple(f"dx{K}" for K in range(1, N + 1)) + tuple(f"dy{K}" for K in range(1, N + 1))
                 + ("dy_receiver",))
        return Scenario(function, names, {"dx": tuple(range(N)), "dy": tuple(range(N, 2 * N + 1))},
                        tuple(infos))

    # -- many samples, streamed -----------------------------------------------------------------
    def stream(self, x, required: dict[str, float], offsets, samples: int,
               parked: int | None = None) -> dict:
        """The smallest excess margin (slack / scale - requirement) over every row of every
        stage for `samples` offset vectors, pushed through the stage maps together.
        offsets(K) -> (dx_K, dy_K) arrays of `samples` values (pivot K = 1 .. N + 1), asked for
        once each, in order. parked: the palms behind that can reach the object at this design
        (`manipulators.parked_rows` at it; default the formulation's, for its whole box).
        Returns the worst excess, where (the row's label), at which stage and which sample;
        memory: the state and P + 2 offsets per sample, whatever the row's length."""
        with self._lock:
            return self._stream(x, required, offsets, samples, parked)

    def _stream(self, x, required, offsets, samples, parked):
        N, P, S = self.N, self.P, samples
        xs = np.ascontiguousarray(np.broadcast_to(np.asarray(x, dtype=float).ravel(),
                                                  (S, self.x.numel())))
        # (samples, n) in C order is CasADi's (n, samples) in column order: no copies
        wdx, wdy = np.zeros((S, P + 2)), np.zeros((S, P + 2))
        worst = {"value": np.inf, "label": "", "sample": 0, "stage": 0}
        wdx[:, P], wdy[:, P] = offsets(1)
        wdx[:, P + 1], wdy[:, P + 1] = offsets(2)
        fn, rows = self.start
        slack, scale, u, o = self._run(fn, S, [xs, wdx[:, P].copy(), wdy[:, P].copy()])
        _worse(worst, slack, scale, rows, required, 1)
        for K in range(1, N + 1):
            fn, rows = self.stage(K, parked)
            slack, scale, u, o = self._run(fn, S, [xs, u, o, wdx, wdy])
            _worse(worst, slack, scale, rows, required, K)
            if K < N:  # slide the window one pivot on
                wdx[:, :-1], wdy[:, :-1] = wdx[:, 1:].copy(), wdy[:, 1:].copy()
                wdx[:, -1], wdy[:, -1] = offsets(K + 2)
        return worst

    def _run(self, fn, count: int, args):
        """fn mapped over `count` samples, evaluated in place on numpy arrays (CasADi's buffer
        interface: converting its results cost as much as evaluating them). Returns fresh
        arrays (samples x outputs)."""
        key = (id(fn), count)
        if key not in self._maps:
            mapped = fn.map(count)
            buffer, call = mapped.buffer()
            outs = [np.zeros((count, mapped.size1_out(i))) for i in range(mapped.n_out())]
            for i, out in enumerate(outs):
                buffer.set_res(i, memoryview(out))
            self._maps[key] = (fn, buffer, call, outs)
        _, buffer, call, outs = self._maps[key]
        kept = [np.ascontiguousarray(a, dtype=float) for a in args]
        for i, a in enumerate(kept):
            buffer.set_arg(i, memoryview(a))
        call()
        return [out.copy() if out.shape[1] > 1 else out[:, 0].copy() for out in outs]


class Bound:
    """A generic row's stage maps (Stages with scene parameters) at one spec's numbers: what
    solve/check.py and the linearised sets ask of Stages, x without the numbers."""

    def __init__(self, stages: Stages, numbers: np.ndarray, spec):
        self.stages, self.numbers, self.spec = stages, numbers, spec
        self.N, self.P = stages.N, stages.P

    def __call__(self) -> Scenario:
        sc = self.stages.scenario()
        x = ca.SX.sym("x", self.stages.x.numel() - self.numbers.size)
        d = ca.SX.sym("d", sc.function.size1_in(1))
        slack, scale = sc.function(ca.vertcat(x, self.numbers), d)
        return replace(sc, function=ca.Function("offsets", [x, d], [slack, scale]))

    def reach(self, values: dict) -> int:
        """Stages.reach at this spec's scene."""
        from . import parked_rows

        return parked_rows(self.spec.scene, values, {}, self.N)

    def stream(self, x, *args, **kwargs) -> dict:
        x = np.concatenate([np.asarray(x, dtype=float).ravel(), self.numbers])
        return self.stages.stream(x, *args, **kwargs)


def _whole_carry_rows(add, m, scene, u, th, o, where, lift_off):
    """The carry's lift-off, slip and tip rows over the whole carry from -alpha at u to the
    handover th (real links or pivots): the NLP's rows over the carry's cells with the
    curvature bound (physics.carry_contact_nodes, rows._inside_rows), at this one carry."""
    g, l, mu = m.g, m.l, scene.palm.friction
    d, W, half_h = scene.body.width / 2, scene.palm.width, scene.body.height / 2
    nodes, bend = phys.carry_contact_nodes(
        u, m.a, start=m.a, end=th, fastest_u2=u**2, gravity=g, carry_gravity=m.gc,
        friction=m.f, link_length=l, cells=CARRY_CELLS)
    inside = f"{where}, during the carry"
    for c1, c2, key, what, scale in (
            (1.0, 0.0, lift_off, "", g), (mu, -1.0, "slip_carry", "sliding back", mu * g),
            (mu, 1.0, "slip_carry", "sliding forward", mu * g),
            (d, half_h, "tip_carry", "object's front edge", d * g),
            (d, -half_h, "tip_carry", "object's rear edge", d * g),
            (W / 2 - o, half_h, "tip_carry", "palm's front edge", (W / 2 - o) * g),
            (W / 2 + o, -half_h, "tip_carry", "palm's rear edge", (W / 2 + o) * g)):
        for i, value in enumerate(phys.carry_row_cells(nodes, c1, c2, bend)):
            add(key, join(inside, what, f"cell {i + 1} of {CARRY_CELLS}"), value, scale)


def _worse(worst: dict, slack, scale, rows, required, K: int) -> None:
    """Fold one stage's rows (samples x rows) into the running worst excess margin."""
    r = np.array([required.get(key, 0.0) if kind == MARGIN else 0.0
                  for key, _, _, _, kind in rows])
    with np.errstate(divide="ignore", invalid="ignore"):
        excess = slack / np.where(scale != 0, scale, 1.0) - r[None, :]
    excess = np.where(np.isfinite(excess), excess, -np.inf)
    j, i = np.unravel_index(np.argmin(excess), excess.shape)
    if excess[j, i] < worst["value"]:
        worst.update(value=float(excess[j, i]), label=_label(rows[i], K), sample=int(j), stage=K)


def _adder(rows: list):
    def add(key, where, slack, scale=1.0, kind=MARGIN):
        rows.append((key, where, slack, scale, kind))
    return add


def _stack(rows, column):
    return ca.vertcat(*[ca.SX(r[column]) if not isinstance(r[column], ca.SX) else r[column]
                        for r in rows])


def _where(template: str, K: int) -> str:
    return template.format(K=K, K1=K + 1, **{f"K_{n}": K - n for n in range(1, K)})


def _label(row, K: int) -> str:
    return f"{row[0]} ({_where(row[1], K)})"


def _infos(rows, K: int, start: int) -> list[ConditionInfo]:
    return [ConditionInfo(start + i, key, (key,), _where(where, K), kind, False)
            for i, (key, where, _, _, kind) in enumerate(rows)]


def scenario(spec, model, m) -> Scenario:
    """The whole row's conditions as one Function of every offset."""
    return Stages(spec, model, m).scenario()


def _parked_clearance(spec, m):
    """physics.parked_palm_clearance of one parked palm as a CasADi Function of (theta_end,
    pitch_x, pitch_y, offset, alpha, link_length): built once and called at every stage and
    palm back, it is copied in C++; built there from the formula, a row of 100 stages took 1.4
    s (up to 16 parked palms a stage)."""
    th, px, py, o, a, l = (ca.SX.sym(name) for name in ("th", "px", "py", "o", "a", "l"))
    body, palm = spec.scene.body, spec.scene.palm
    gap = phys.parked_palm_clearance(1, alpha=a, theta_end=th, link_length=l,
                                     front_stop=palm.front_stop, pitch_x=px, pitch_y=py,
                                     offset_lo=o, offset_hi=o, reach=(body.width + palm.width) / 2,
                                     depth=palm.thickness + body.height)
    return ca.Function("parked_palm_clearance", [th, px, py, o, a, l], [gap])
