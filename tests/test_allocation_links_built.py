"""Worst-case allocation of the link lengths on the device as built (docs/optimizer.md section
4a, `link_length`): on `problems/manipulators_real_links.toml` (two 0.5 kg uniform rods, 0.2 N m
of pivot friction) the carry's q_e, g_e and f are free of a build's link error, so only the
explicit link lengths move. The event simulator passes every pivot corner pattern with the
links all long, all short and alternating either way, and fails some build of a larger box;
the bounds the rows take in the link (the over-the-top need convex in it, the palm's force
affine in its inverse) are checked against brute force over the link's range; what stays
refused is refused in words."""

import math
import subprocess
import sys

import numpy as np
import pytest
from test_allocation_built import BASE, ROOT
from test_allocation_links import _links, allocated

from pdm_design.scenes.manipulators import physics as phys

ALONE = "link_length = { allocate = true }\n"
PIVOTS = "pivot_x = { allocate = true }\npivot_y = { allocate = true }\n"
# a given inertia above m l^2 / 2 (1.0 kg m^2 a 0.5 kg link on 2 m): J > W, g_e below g
INERTIA = BASE.replace("count = 2 ", "inertia = 1.2\ncount = 2 ")


def _allocated(tmp_path_factory, extra, base=BASE):
    return allocated(tmp_path_factory, base + "\n[tolerances]\n" + extra)


@pytest.fixture(scope="module")
def alone(tmp_path_factory):
    return _allocated(tmp_path_factory, ALONE)


@pytest.fixture(scope="module")
def with_pivots(tmp_path_factory):
    return _allocated(tmp_path_factory, PIVOTS + ALONE)


@pytest.fixture(scope="module")
def given_inertia(tmp_path_factory):
    return _allocated(tmp_path_factory, PIVOTS + ALONE, INERTIA)


def _failures(case, scale):
    """(pivot pattern, link pattern, failure) of every build of the scaled box the simulator
    fails, or whose object starts to tip (a margin the box holds; the run may rock on and
    complete): the pivots' 12 corner patterns (none when exact) by the links' 4 patterns."""
    from pdm_design.scenes.manipulators.tolerances import simulate_build
    from pdm_design.verify.tolerance import corner_patterns

    spec, design, value = case
    stages = spec.verification.stages
    patterns = corner_patterns(stages) if "pivot_x" in value else [("exact", None)]
    out = []
    for name, signs in patterns:
        for link, pattern in _links(stages).items():
            dev = {"link_length": (scale * value["link_length"] * pattern)[None, :]}
            if signs is not None:
                for i, q in enumerate(("pivot_x", "pivot_y")):
                    dev[q] = np.array([[s[i] * scale * value[q] for s in signs]])
            run = simulate_build(spec.scene, design, dev, stages)
            if not run.outcome.completed:
                out.append((name, link, run.outcome.failure.kind))
            elif any(e.kind == "rock" for e in run.events):  # the box holds the tip margin
                out.append((name, link, "tip onset"))
    return out


@pytest.mark.parametrize("case", ["alone", "with_pivots", "given_inertia"])
def test_every_corner_of_the_box_passes(case, request):
    setup = request.getfixturevalue(case)
    value = setup[2]
    assert value["link_length"] > 0.01  # a box worth having: over a centimetre
    if case != "alone":  # equal weights: one half-width for the three
        assert value["pivot_x"] == value["pivot_y"] == value["link_length"]
    assert _failures(setup, 1.0) == []


@pytest.mark.parametrize("case, scale", [("alone", 3.0), ("with_pivots", 2.0),
                                         ("given_inertia", 2.0)])
def test_a_larger_box_fails(case, scale, request):
    """Not vacuous: the simulator fails some build of the box scaled up (its own limits,
    bisected, are in docs/optimizer.md 4a)."""
    assert _failures(request.getfixturevalue(case), scale)


def _lowest_v2(u2, a, l, g_e, f, n=20001):
    """Brute force: the smallest v^2 over the carry from -a up to pi/2 on a fine grid."""
    th = np.linspace(-a, math.pi / 2, n)
    return np.min(u2 + 2 * g_e * l * (np.cos(a) - np.cos(th)) - 2 * f * (th + a))


@pytest.mark.parametrize("f", [0.3, 2.5])
def test_over_the_top_need_is_largest_at_an_end_of_the_link(f):
    """The need (the u^2 that keeps the smallest v^2 at 0) is not monotone in the link once
    the friction balance angle passes the stop (f = 2.5: th* > a at l_lo), but convex: its
    largest over [l_lo, l_hi] is at an end (rows.py _top_needs), against brute force."""
    a, g_e, ends = 0.1, 10.5, (1.9, 2.1)
    grid = np.linspace(*ends, 41)
    need = [-_lowest_v2(0.0, a, l, g_e, f) for l in grid]
    closed = [phys.top_speed_squared_needed(a, gravity=g_e, link_length=l, friction=f)
              for l in grid]
    assert np.allclose(need, closed, atol=1e-6)
    assert max(need) <= max(closed[0], closed[-1]) + 1e-9
    star = phys.friction_balance_angle(f, gravity=g_e, link_length=ends[0])
    if star > a:  # the other sign: the need then falls with the link somewhere
        assert np.any(np.diff(closed) < 0.0)


def test_palm_force_is_extreme_at_an_end_of_the_link():
    """Lift-off margin N and friction ratio F / N at a fixed angle, landing speed, g_e and f:
    over the link's range their least and largest are at its ends (N, F affine in 1 / l with
    v^2 / l = u^2 / l + 2 g_e (cos a - cos th) - 2 f (a + th) / l), on a fine grid."""
    rng = np.random.default_rng(17)
    g = 9.81
    for _ in range(200):
        a, th = rng.uniform(0.0, 0.3), rng.uniform(0.3, 1.0)
        g_e, f, u2 = rng.uniform(9.0, 11.0), rng.uniform(0.0, 0.5), rng.uniform(0.0, 10.0)
        grid = np.linspace(1.8, 2.2, 101)
        v2 = phys.carry_speed_squared(np.sqrt(u2), a, th, gravity=g_e, link_length=grid,
                                      friction=f)
        along = phys.carry_along(th, gravity=g, carry_gravity=g_e, friction=f, link_length=grid)
        fr, n = phys.carry_contact_force(th, v2, gravity=g, link_length=grid, along=along)
        for values in (n, np.where(n > 0, fr / np.where(n > 0, n, 1.0), np.nan)):
            if np.isnan(values).any():
                continue
            ends = values[[0, -1]]
            assert values.min() >= ends.min() - 1e-12 and values.max() <= ends.max() + 1e-12


def test_links_with_the_stops_refused_in_words(tmp_path):
    """Links and back stops together on real links: the palm's force at a toleranced stop is
    bounded at the design's link only (carry_box.back_contact), so refused."""
    path = tmp_path / "bad.toml"
    path.write_text(BASE + "\n[tolerances]\n" + ALONE
                    + "back_stop = { allocate = true, weight = 10 }\n")
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 2
    assert "tolerances.link_length" in run.stderr and "the back stops exact" in run.stderr
    assert "Traceback" not in run.stderr
