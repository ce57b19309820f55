"""Worst-case allocation of the link lengths, every manipulator its own (docs/optimizer.md
section 4a, `link_length`; formulation/manipulators/links.py): the event simulator passes the
allocated box at the pivots' corner patterns with the links all long, all short and
alternating, and at random builds inside it; it fails some build at 1.5 times the box, and its
own limit along those patterns lies between 1 and 1.5 times the box. The landing place's map
the bound is built on is checked against the simulator's landings."""

import itertools
import math

import numpy as np
import pytest
from test_allocation import BASE

from pdm_design.scenes.manipulators.tolerances import simulate_build
from pdm_design.solve import optimize
from pdm_design.spec import load_spec
from pdm_design.verify.tolerance import corner_patterns, verify_tolerance

ALONE = "[tolerances]\nlink_length = { allocate = true }\n"
WITH_PIVOTS = ("[tolerances]\npivot_x = { allocate = true }\npivot_y = { allocate = true }\n"
               "link_length = { allocate = true }\n")


def _allocated(tmp_path_factory, extra):
    return allocated(tmp_path_factory, BASE + "\n" + extra)


def allocated(tmp_path_factory, text):
    """(spec, its optimised design, {quantity: allocated half-width}) of the spec `text`."""
    path = tmp_path_factory.mktemp("links") / "spec.toml"
    path.write_text(text)
    spec = load_spec(path)
    result = optimize(spec)
    assert result.status.value == "optimal"
    design = spec.design_at({n: result.design[n] for n in spec.free_variables})
    return spec, design, {e["quantity"]: e["value"] for e in result.tolerances}


@pytest.fixture(scope="module")
def alone(tmp_path_factory):
    return _allocated(tmp_path_factory, ALONE)


@pytest.fixture(scope="module")
def with_pivots(tmp_path_factory):
    return _allocated(tmp_path_factory, WITH_PIVOTS)


def _links(stages):
    """The links' sign patterns: all long, all short, alternating either way."""
    alternating = np.array([(-1.0) ** k for k in range(stages)])
    return {"+": np.ones(stages), "-": -np.ones(stages), "alt": alternating,
            "-alt": -alternating}


def _completes(spec, design, value, scale, links, signs=None):
    stages = spec.verification.stages
    deviations = {"link_length": (scale * value["link_length"] * links)[None, :]}
    if signs is not None and "pivot_x" in value:
        deviations["pivot_x"] = np.array([[sx * scale * value["pivot_x"] for sx, _ in signs]])
        deviations["pivot_y"] = np.array([[sy * scale * value["pivot_y"] for _, sy in signs]])
    return simulate_build(spec.scene, design, deviations, stages).outcome.completed


def _failures(case, scale):
    """(pivot pattern, link pattern) of every corner of the scaled box the simulator fails."""
    spec, design, value = case
    stages = spec.verification.stages
    return [(name, link) for name, signs in corner_patterns(stages)
            for link, pattern in _links(stages).items()
            if not _completes(spec, design, value, scale, pattern, signs)]


@pytest.mark.parametrize("case", ["alone", "with_pivots"])
def test_every_corner_of_the_link_box_passes(case, request):
    spec, design, value = request.getfixturevalue(case)
    assert value["link_length"] > 0.0
    if case == "with_pivots":  # equal weights: one half-width for all three
        assert value["pivot_x"] == value["pivot_y"] == value["link_length"]
    assert _failures((spec, design, value), 1.0) == []


@pytest.mark.parametrize("case", ["alone", "with_pivots"])
def test_random_builds_inside_the_link_box_pass(case, request):
    """Every manipulator its own link (and pivot), uniform in the box or at a random vertex."""
    spec, design, value = request.getfixturevalue(case)
    stages = spec.verification.stages
    rng = np.random.default_rng(17)
    for i in range(40):
        draw = (lambda: rng.choice([-1.0, 1.0], size=stages)) if i % 2 else (
            lambda: rng.uniform(-1.0, 1.0, size=stages))
        deviations = {q: (value[q] * draw())[None, :] for q in value}
        assert simulate_build(spec.scene, design, deviations, stages).outcome.completed


@pytest.mark.parametrize("case", ["alone", "with_pivots"])
def test_the_link_box_is_the_right_size(case, request):
    """The simulator's own limit along the corner patterns (bisection on the box's scale) is
    above the box and below 1.5 times it: not vacuous, and not far from the truth."""
    setup = request.getfixturevalue(case)
    assert _failures(setup, 1.5)
    low, high = 1.0, 1.5
    for _ in range(5):
        mid = 0.5 * (low + high)
        low, high = (low, mid) if _failures(setup, mid) else (mid, high)
    assert 1.0 < high <= 1.5


def test_links_and_stops_hold_at_the_corners(tmp_path_factory):
    """Links and back stops together (formulation.manipulators.links.Rest): the pivots' patterns
    with the links and the stops each all high, all low and alternating either way pass; 1.5 times
    the box fails some."""
    spec, design, value = _allocated(tmp_path_factory,
                                     WITH_PIVOTS + "back_stop = { allocate = true, weight = 10 }\n")
    assert value["back_stop"] == pytest.approx(value["link_length"] / 10, rel=1e-12)
    stages = spec.verification.stages
    patterns = _links(stages).values()

    def failures(scale):
        count = 0
        for _, signs in corner_patterns(stages):
            for links, stops in itertools.product(patterns, patterns):
                deviations = {
                    "pivot_x": np.array([[sx * scale * value["pivot_x"] for sx, _ in signs]]),
                    "pivot_y": np.array([[sy * scale * value["pivot_y"] for _, sy in signs]]),
                    "link_length": (scale * value["link_length"] * links)[None, :],
                    "back_stop": (scale * value["back_stop"] * stops)[None, :]}
                run = simulate_build(spec.scene, design, deviations, stages)
                count += not run.outcome.completed
        return count

    assert failures(1.0) == 0
    assert failures(1.5) > 0


def test_lot_of_links_is_bounded_as_each(tmp_path_factory, alone):
    """Every link alike (a lot) is inside the per-part box: the same allocation."""
    _, _, value = alone
    _, _, lot = _allocated(tmp_path_factory,
                           ALONE.replace("allocate = true", "allocate = true, applies_to = "
                                                            '"lot"'))
    assert lot["link_length"] == pytest.approx(value["link_length"], rel=1e-9)


def test_landing_place_map_of_the_links(alone):
    """The map the bound stands on (formulation.manipulators.links): with every link e longer, each
    handover moves the landing on the next palm by G(e, e cos a) + e sin a, and to first
    order by c_m e, c_m = (1 - cos(a + b)) / sin b; the simulator's landings agree."""
    spec, design, _ = alone
    a, b, l = design.alpha, design.beta, design.link_length
    stages = spec.verification.stages
    for e in (1e-4 * l, 0.01 * l, -0.01 * l):
        run = simulate_build(spec.scene, design, {"link_length": np.full((1, stages), e)},
                             stages)
        offsets = [s["landing_offset"] for s in run.stages]
        z = e * math.cos(a)
        step = (math.sqrt((l + e) ** 2 - (l * math.cos(b) + z) ** 2) - l * math.sin(b)
                + e * math.sin(a))
        assert np.diff(offsets) == pytest.approx(step, rel=1e-6, abs=1e-9 * l)
        c_m = (1.0 - math.cos(a + b)) / math.sin(b)
        assert step == pytest.approx(c_m * e, rel=abs(e) / l * 10.0)


def test_optimize_verification_runs_the_link_patterns(with_pivots):
    """verify/tolerance.py runs the links all long, all short and alternating with every
    pivot pattern (12 x 4) and random builds; 1.5 times the box is refuted."""
    spec, design, value = with_pivots
    lots = [{"quantity": q, "value": v} for q, v in value.items()]
    box = {"dx": value["pivot_x"], "dy": value["pivot_y"]}
    checked = verify_tolerance(spec, design, box, samples=4, lots=lots)
    assert checked["passed"] and checked["samples"] == 12 * 4 + 4
    bigger = [{"quantity": q, "value": 1.5 * v} for q, v in value.items()]
    refuted = verify_tolerance(spec, design, {k: 1.5 * v for k, v in box.items()}, samples=0,
                               lots=bigger)
    assert not refuted["passed"]
    assert any("alternating" in f["build"] for f in refuted["failures"])
