"""No failed run counts as passed: a palm flown over fails by name (skipped_palm) unless the
spec allows skips, a palm handing the object back does not count, stages_passed stays below
the row's length for every failure, and the yield's passes are the completed runs."""

import math
from pathlib import Path
from types import SimpleNamespace

import pytest

from pdm_design.errors import SpecError
from pdm_design.scenes.manipulators.sim import simulate_manipulators
from pdm_design.spec.loader import load_spec, parse_spec, read_spec_data
from pdm_design.tolerances import Tolerance, Tolerances
from pdm_design.tolerances.yield_ import simulate_one, yield_of

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
PAPER = PROBLEMS / "paper_manipulators.toml"
STAGES = 4
# palm 3 moved 2.8 m along the row and 0.5 m down: beyond palm 4 and below it
BACK = [SimpleNamespace(manipulator=3, dx=2.8, dy=-0.5)]


@pytest.fixture(scope="module")
def paper():
    spec = load_spec(PAPER)
    return spec.scene, spec.design_at()


def _rest_top(design, k, dx=0.0, dy=0.0):
    """Palm k's (1-based) top centre resting on its back stop, its pivot moved by (dx, dy)."""
    a, b, l = design.alpha, design.beta, design.link_length
    px = design.first_pivot_x + (k - 1) * l * (math.sin(a) + math.sin(b)) + dx
    py = design.first_pivot_y - (k - 1) * l * (math.cos(a) - math.cos(b)) + dy
    return px - l * math.sin(a), py + l * math.cos(a), px


def test_a_backward_handover_on_the_last_palm_never_counts_the_row_passed(paper):
    scene, design = paper
    result = simulate_manipulators(scene, design, stages=STAGES, offsets=BACK, allow_skips=True)
    hand = [e for e in result.events if e.kind in ("landing", "handover")]
    # palm 2 throws the object over palm 3 onto palm 4's top at rest; palm 4 carries it into
    # palm 3's top, which lies beyond palm 4's pivot: a handover from palm 4 back to palm 3
    x4, y4, _ = _rest_top(design, 4)
    assert hand[2].kind == "landing" and hand[2].after["palm"] == 4
    assert hand[2].after["y"] == pytest.approx(y4, abs=1e-9)
    x3, y3, px3 = _rest_top(design, 3, 2.8, -0.5)
    assert px3 > _rest_top(design, 4)[2]
    assert hand[3].kind == "handover" and hand[3].after["palm"] == 3
    assert hand[3].after["y"] == pytest.approx(y3, abs=1e-9)
    assert abs(hand[3].after["x"] - x3) < 0.5 * (scene.body.width + scene.palm.width)
    # the run fails: palms 1 and 2 handed on, palm 3 flown over counts (skips allowed), palm 4
    # did not hand on in order
    assert not result.outcome.completed and result.outcome.failure is not None
    assert result.outcome.stages_passed == 3 < STAGES


def test_a_palm_flown_over_is_a_failure_by_name(paper):
    scene, design = paper
    result = simulate_manipulators(scene, design, stages=STAGES, offsets=BACK)
    failure = result.outcome.failure
    assert failure.kind == "skipped_palm" and failure.stage == 3
    assert "flew over palm 3" in failure.detail and "onto palm 4" in failure.detail
    _, y4, _ = _rest_top(design, 4)
    assert failure.before["y"] == pytest.approx(y4, abs=1e-9)  # where it comes onto palm 4
    assert result.outcome.stages_passed == 2 and not result.outcome.completed


def test_allow_skips_restores_the_pass_of_a_flight_over_a_low_palm(paper, tmp_path):
    # the paper's eq. 43 (palm 2 0.4 m low): fails by default, completes with allow_skips
    data = read_spec_data(PAPER)
    data["verification"] = {**data.get("verification", {}), "stages": 6,
                            "offsets": [{"manipulator": 2, "dx": 0.0, "dy": -0.4}]}
    strict = parse_spec(data, "strict.toml")
    assert strict.verification.allow_skips is False
    data["verification"]["allow_skips"] = True
    lenient = parse_spec(data, "lenient.toml")
    assert lenient.verification.allow_skips is True
    from pdm_design.verify import simulate_spec

    design = strict.design_at()
    assert simulate_spec(strict, design).outcome.failure.kind == "skipped_palm"
    assert simulate_spec(lenient, design).outcome.completed


def test_allow_skips_must_be_a_boolean_and_is_for_manipulators():
    data = read_spec_data(PAPER)
    data["verification"] = {**data.get("verification", {}), "allow_skips": "yes"}
    with pytest.raises(SpecError, match="allow_skips"):
        parse_spec(data, "bad.toml")
    stairs = read_spec_data(PROBLEMS / "paper_stairs_frictionless.toml")
    stairs["verification"] = {**stairs.get("verification", {}), "allow_skips": True}
    with pytest.raises(SpecError, match="allow_skips"):
        parse_spec(stairs, "stairs.toml")


@pytest.mark.parametrize("allow_skips", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_the_yield_passes_exactly_the_completed_runs(paper, allow_skips):
    # pivots +-0.45 m down the row: some builds fly over a palm; every build simulated one by
    # one, its outcome compared with the yield's count
    scene, design = paper
    tols = Tolerances((Tolerance("pivot_y", "each", 0.45), Tolerance("pivot_x", "each", 0.3)))
    builds, stages = 150, STAGES
    r = yield_of(scene, design, tols, builds=builds, stages=stages, seed=2, confirm=0,
                 scales=(), sensitivity_samples=0, allow_skips=allow_skips)
    runs = [simulate_one(scene, design, tols, 2, i, stages, allow_skips=allow_skips).outcome
            for i in range(builds)]
    assert round(r.estimate * builds) == sum(o.completed for o in runs)
    assert all(o.stages_passed < stages for o in runs if not o.completed)
    skipped = sum(o.failure is not None and o.failure.kind == "skipped_palm" for o in runs)
    assert (skipped > 0) != allow_skips
