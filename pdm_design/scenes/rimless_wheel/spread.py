"""The robust rows over a box that also holds the spokes' lengths and the hub's mass
(docs/rimless_wheel.md, section 9, "Spokes and hub in the box").

A build's spoke j is l + e_j, |e_j| <= t_l (each spoke its own; a lot: one e for all), and its
hub's mass M + e_M, |e_M| <= t_M (a lot). The mass moves k^2 = (M k_h^2 + S l^2 / 3) / (M + S)
(S = n m_s) monotonically, dk^2/dM = S (k_h^2 - l^2 / 3) / (M + S)^2, so a build's k^2 lies
between its values at M -+ t_M (`k2_ends`); with S = 0 it is k_h^2 whatever M.

A step stands on spoke a and lands spoke b (a corner: a, b in {l - t_l, l + t_l}; a lot: a = b).
Its stance energy E (the squared speed where spoke a is vertical) maps to the next stance's on b
    E' = q E + c,   q = eta_ab^2,   c = rate_a eta_ab^2 vers(phi1) - rate_b vers(phi1 - 2 alpha),
phi1 = theta0(a, b) + beta the impact angle. Every map is increasing in E, so the energies of
every build lie above the iterates of L(y) = min over the corners of (q y + c) from the lowest
first stance, and those rise or fall monotonically to L's fixed point, min_i c_i / (1 - q_i)
(the lowest of the corner wheels' orbits); above likewise with max. The corners stand for the
box where each of q, c is monotone in each spoke and in k^2 over it (a box small against the
spokes: tests/test_rimless_wheel_leg_box.py checks interior builds against the corners).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import casadi as ca

from . import physics as phys
from .physics import cos, fabs, fmax, fmin, sin, sqrt, versine

ARC_ROWS = 9
ITERATIONS = 12  # of the spokes' energy bounds (`Spread.energies`): the gap shrinks by eta^2


class Box(NamedTuple):
    """Half-widths: the chord's (slope on a ramp, rise on stairs), the tread's, the start
    speed's, each spoke's length and the hub's mass; each: the spokes each their own."""

    chord: object
    tread: object
    speed: object
    leg: object
    mass: object
    each: bool


class Corner(NamedTuple):
    ends: tuple[int, int, int]  # (a's end, b's end, k^2's end): 0 low, 1 high
    a: object
    b: object
    k2: object
    rate_a: object
    rate_b: object
    eta: object
    loss: object  # 1 - eta^2
    theta0: object


def k2_ends(wheel, spokes, leg, t_mass):
    """k^2 at the hub's mass M - t_M and M + t_M (the spokes' mass distribution as designed)."""
    return [phys.gyration_squared(wheel.mass + s * t_mass, wheel.gyration, wheel.spoke_mass,
                                  spokes, leg) for s in (-1.0, 1.0)]


def mass_moves_nothing(wheel, leg) -> bool:
    """Whether k^2 is the same at every hub mass: no spoke mass, or k_h^2 = l^2 / 3."""
    return wheel.spoke_mass == 0.0 or wheel.gyration**2 == leg**2 / 3.0


def corner(a, b, k2, alpha, gravity, ends=(0, 0, 0)):
    """The closed forms of a step from spoke a to spoke b at k^2, without cancellation at
    a = b: 1 - eta = b (2 b sin^2 alpha + (b - a) cos 2 alpha) / (k^2 + b^2),
    tan theta0 = ((a - b) + 2 b sin^2 alpha) / (b sin 2 alpha)."""
    s2, c2 = math.sin(alpha) ** 2, math.cos(2.0 * alpha)
    drop = b * (2.0 * b * s2 + (b - a) * c2) / (k2 + b**2)
    eta = 1.0 - drop
    theta0 = ca.atan(((a - b) + 2.0 * b * s2) / (b * math.sin(2.0 * alpha)))
    return Corner(ends, a, b, k2, phys.stance_rate(gravity, k2, a),
                  phys.stance_rate(gravity, k2, b), eta, drop * (2.0 - drop), theta0)


def chord_between(a, b, alpha):
    """|tip a - tip b| = sqrt((a - b)^2 + 4 a b sin^2 alpha)."""
    return sqrt((a - b) ** 2 + 4.0 * a * b * math.sin(alpha) ** 2)


class Spread:
    """The rows of one wheel (formulation._Model m) over a Box."""

    def __init__(self, m, box: Box):
        self.m, self.box = m, box
        alpha, g = m.alpha, m.scene.gravity
        legs = [m.leg - box.leg, m.leg + box.leg]
        pairs = ([(i, j) for i in (0, 1) for j in (0, 1)] if box.each else [(0, 0), (1, 1)])
        self.legs = legs
        self.k2s = k2_ends(m.scene.wheel, m.n, m.leg, box.mass)
        self.corners = [corner(legs[i], legs[j], k2, alpha, g, (i, j, kk))
                        for i, j in pairs for kk, k2 in enumerate(self.k2s)]
        short, long_ = legs
        if box.each:  # theta0 grows with a and falls with b
            self.theta_lo = corner(short, long_, self.k2s[0], alpha, g).theta0
            self.theta_hi = corner(long_, short, self.k2s[0], alpha, g).theta0
        else:
            self.theta_lo = self.theta_hi = alpha
        if m.stairs:  # the chord grows with both spokes: the longest at (l + t, l + t)
            self.c_short = chord_between(short, short, alpha)
            self.c_long = chord_between(long_, long_, alpha)
            self.beta_lo = _asin(m.rise - box.chord, self.c_long)
            self.beta_hi = _asin(m.rise + box.chord, self.c_short)
        else:
            self.beta_lo, self.beta_hi = m.beta - box.chord, m.beta + box.chord

    def beta(self, c: Corner, sign):
        """The chord angle of corner c's step at the low (-1) or high (+1) end."""
        m = self.m
        if m.stairs:
            return _asin(m.rise + sign * self.box.chord, chord_between(c.a, c.b, m.alpha))
        return m.beta + sign * self.box.chord

    def offset(self, c: Corner, beta):
        phi1 = c.theta0 + beta
        return c.rate_a * c.eta**2 * versine(phi1) - c.rate_b * versine(phi1 - 2.0 * self.m.alpha)

    def first(self, sign):
        """{(spoke, k^2 end): the first stance's energy} from the slowest (sign -1) or fastest
        (+1) start on each spoke end at each k^2 end (the wheel starts on the ground as
        designed, its stance spoke at beta - alpha)."""
        m = self.m
        speed = m.scene.initial.speed + sign * self.box.speed
        start = m.beta - m.alpha
        return {(i, j): speed**2 - phys.stance_rate(m.scene.gravity, k2, a) * versine(start)
                for i, a in enumerate(self.legs) for j, k2 in enumerate(self.k2s)}

    def energies(self, sign):
        """{(spoke end, k^2 end): a lower (sign -1) or upper (+1) bound of the energy of every
        stance on a spoke at that end}: Y_b = min(first_b, min_a (q_ab Y_a + c_ab)) from the
        one-step bound min(first, min_ab c_ab / (1 - q_ab)), ITERATIONS times (each keeps it a
        bound of every stance, and it rises towards the lowest orbit a wheel of those spokes
        can follow; max for the upper)."""
        pick = _least if sign < 0 else _most
        first = self.first(sign)
        steps = {}  # (a end, b end, k^2 end): (q, c)
        for c in self.corners:
            steps[c.ends] = (c.eta**2, self.offset(c, self.beta(c, sign)))
        out = {}
        for j in range(len(self.k2s)):
            mine = {(a, b): v for (a, b, jj), v in steps.items() if jj == j}
            one = pick([first[(i, j)] for i in range(len(self.legs))]
                       + [cc / (1.0 - q) for q, cc in mine.values()])
            y = {i: pick([first[(i, j)], one]) for i in range(len(self.legs))}
            for _ in range(ITERATIONS if self.box.each else 1):
                y = {b: pick([first[(b, j)]] + [q * y[a] + cc for (a, bb), (q, cc)
                                                  in mine.items() if bb == b])
                     for b in range(len(self.legs))}
            out.update({(b, j): value for b, value in y.items()})
        return out

    def rows(self, add, validity):
        """Every row (add(key, where, slack, scale, kind=...), validity: the kind of the rows
        that keep the model valid): section 9's "Spokes and hub in the box"."""
        m, box = self.m, self.box
        alpha = m.alpha
        phi0_lo = self.theta_lo + self.beta_lo - 2.0 * alpha
        phi0_hi = self.theta_hi + self.beta_hi - 2.0 * alpha
        phi1_lo, phi1_hi = self.theta_lo + self.beta_lo, self.theta_hi + self.beta_hi
        add("descends", "every step's chord goes down", self.beta_lo - 1e-6, alpha,
            kind=validity)
        add("descends", "the landing spoke meets the ground after the stance spoke leaves it",
            phi1_lo - phi0_hi, alpha, kind=validity)
        mass, speed = m.scene.wheel.mass, m.scene.initial.speed
        for what, value, half in (("every spoke keeps a length", m.leg, box.leg),
                                  ("the hub keeps a mass", mass, box.mass),
                                  ("the slowest start rolls forward", speed, box.speed)):
            if not _nothing(half):
                add(None, what, value * (1.0 - 1e-6) - half, value, kind=validity)
        for c in self.corners:
            add("impact_ratio", "an impact keeps the wheel rolling forward", c.eta, 1.0,
                kind=validity)
        start = m.beta - alpha
        g = m.scene.gravity
        for (i, j), energy in self.first(-1.0).items():
            rate = phys.stance_rate(g, self.k2s[j], self.legs[i])
            self._over(add, "first stance", energy, start, rate)
        low = self.energies(-1.0)
        for (i, j), energy in low.items():
            rate = phys.stance_rate(g, self.k2s[j], self.legs[i])
            self._over(add, "every stance, the lowest spokes' bound", energy, phi0_lo, rate)
        ends = (_least(list(low.values())), _most(list(self.energies(1.0).values())))
        self._forces(add, ends, fmin(phi0_lo, start), fmax(phi1_hi, start))
        self._impacts(add)
        if m.stairs:
            self._stairs(add, validity)

    @staticmethod
    def _over(add, what, energy, phi0, rate):
        """omega+^2 against rate vers(phi0) behind the vertical (E > 0), 0 past it."""
        start2 = phys.speed_squared(energy, phi0, rate)
        demand = rate * versine(fmin(phi0, 0.0))
        add("over_the_top", f"{what}: vaults its spoke", start2 - demand, start2)

    def _forces(self, add, energies, phi0, phi1):
        m = self.m
        g, mu = m.scene.gravity, m.scene.friction
        for a in self.legs:
            for k2 in self.k2s:
                rate = phys.stance_rate(g, k2, a)
                for energy in energies:
                    for _, (fc, fd), (sc, sd) in phys.stance_conditions(
                            energy, phi0, phi1, m.ground, a, g, k2, rate, mu, ARC_ROWS):
                        add("no_flight", "stance, widest arc, every spoke and hub", fc - fd, fc)
                        add("no_slip", "stance, widest arc, every spoke and hub", sc - sd,
                            fmax(sc, 0.0))

    def _impacts(self, add):
        m = self.m
        mu, ground, alpha = m.scene.friction, m.ground, m.alpha
        for c in self.corners:
            for sign, what in ((-1.0, "lowest"), (1.0, "highest")):
                phi1 = c.theta0 + self.beta(c, sign)
                normal = c.a * sin(phi1 - ground) + c.eta * c.b * sin(ground - phi1 + 2 * alpha)
                tangential = (c.eta * c.b * cos(phi1 - 2 * alpha - ground)
                              - c.a * cos(phi1 - ground))
                add("impact_friction", f"impact on the {what} chord, every spoke pair and hub",
                    mu * normal - fabs(tangential), mu * normal)

    def _stairs(self, add, validity):
        """The footholds drift by sqrt(c^2 - rise^2) - tread a step: the longest steps on the
        longest chord (both spokes long) with short rises and treads, the shortest on the
        shortest chord with long ones; the nose's reach at each spoke pair's steepest chord."""
        m, box = self.m, self.box
        tr, tt = box.chord, box.tread
        chord, tread, s0 = m.chord, m.tread, m.s0
        add("spoke_reach", "every rise is below the shortest spokes' chord",
            self.c_short * (1 - 1e-6) - m.rise - tr, chord, kind=validity)
        add("step_down", "every step goes down", m.rise - tr, chord, kind=validity)
        if not _nothing(tt):
            add(None, "every tread keeps a length", tread * (1.0 - 1e-6) - tt, tread,
                kind=validity)
        long_step = sqrt(fmax(self.c_long**2 - (m.rise - tr) ** 2, 0.0)) - tread + tt
        short_step = sqrt(fmax(self.c_short**2 - (m.rise + tr) ** 2, 0.0)) - tread - tt
        # physics.nose_reach_between of each pair at its steepest chord (one corner a pair)
        reaches = [c.a * math.sin(2 * m.alpha)
                   / cos(fmin(c.theta0 + self.beta(c, 1.0) - 2 * m.alpha, 0.0))
                   for c in self.corners[::len(self.k2s)]]
        for k in sorted({1, max(m.stages, 1)}):
            longest = s0 + k * long_step - tt
            shortest_before = s0 + (k - 1) * short_step + (tt if k > 1 else 0.0)
            add("landing", f"foothold {k}, furthest", tread - tt - longest, tread)
            nose = tread + (tt if k > 1 else 0.0) - shortest_before
            for reach in reaches:
                add("nose_clearance", f"step {k}, nearest foothold, a spoke pair", reach - nose,
                    reach)


def _nothing(half) -> bool:
    """Whether a half-width is the number 0 (a quantity the box leaves exact)."""
    return isinstance(half, (int, float)) and half == 0.0


def _asin(x, c):
    return ca.asin(ca.fmin(ca.fmax(x / c, -1.0 + 1e-12), 1.0 - 1e-12))


def _least(values):
    out = values[0]
    for v in values[1:]:
        out = fmin(out, v)
    return out


def _most(values):
    out = values[0]
    for v in values[1:]:
        out = fmax(out, v)
    return out
