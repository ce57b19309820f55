"""Sobol' indices per toleranced quantity: against the analytic variance shares of a linear
additive model, and on a staircase with one dominant tolerance."""

import math

import numpy as np
import pytest

from pdm_design.scenes.stairs.model import Ball, StairsDesign, StairsInitial, StairsScene
from pdm_design.scenes.stairs.tolerances import run_builds
from pdm_design.tolerances.outcome import BuildOutcome
from pdm_design.tolerances.sensitivity import plot_sensitivity, sobol_indices


def additive(weights):
    """A build map whose output is sum_q w_q * (sum of q's deviations): Var(Y) splits into
    w_q^2 * parts_q * Var(one deviation of q), so each share is known."""

    def run(deviations, stages):
        y = sum(w * (np.sum(deviations[q], axis=1) if deviations[q].ndim == 2 else deviations[q])
                for q, w in weights.items() if q in deviations)
        n = len(y)
        return BuildOutcome(np.zeros(n, dtype=int), np.full(n, "", dtype=object), y,
                            np.ones(n, dtype=bool))

    return run


TOLERANCES = [("rise", "each", 0.3, "normal"), ("launch_speed", "lot", 1.0, "uniform"),
              ("restitution", "lot", 0.6, "normal"), ("friction", "lot", 0.0, "normal")]
WEIGHTS = {"rise": 2.0, "launch_speed": 1.0, "restitution": 0.5, "friction": 7.0}


def analytic_shares(parts):
    variance = {"rise": 4.0 * parts * (0.3 / 3) ** 2,          # normal: sigma = t / 3
                "launch_speed": 1.0 * (2 * 1.0) ** 2 / 12,      # uniform on [-t, t]
                "restitution": 0.25 * (0.6 / 3) ** 2, "friction": 0.0}
    total = sum(variance.values())
    return {q: v / total for q, v in variance.items()}


def test_indices_of_a_linear_additive_model_are_its_variance_shares():
    parts = 5
    rows = sobol_indices(additive(WEIGHTS), TOLERANCES, stages=parts, samples=4096, seed=3)
    shares = analytic_shares(parts)
    assert [r["quantity"] for r in rows] == sorted(shares, key=lambda q: -shares[q])
    for r in rows:
        assert abs(r["index"] - shares[r["quantity"]]) <= max(r["confidence"], 1e-12)
        assert r["first"] == pytest.approx(r["index"], abs=0.02)  # additive: no interactions
    assert rows[-1] == {"quantity": "friction", "index": 0.0, "first": 0.0, "confidence": 0.0}


def test_parts_other_than_stages_and_the_pass_indicator():
    # 3 parts of rise; output "pass": 1 where the build passed (here: y > 0 decides)
    def run(deviations, stages):
        y = additive(WEIGHTS)(deviations, stages).min_margin
        n = len(y)
        return BuildOutcome(np.zeros(n, dtype=int),
                            np.where(y > 0, "", "x").astype(object), y, np.ones(n, dtype=bool))

    rows = sobol_indices(run, TOLERANCES[:2], stages=10, parts=3, samples=512, output="pass")
    assert {r["quantity"] for r in rows} == {"rise", "launch_speed"}
    assert all(0.0 < r["index"] < 1.2 for r in rows)


def test_a_staircase_with_one_dominant_tolerance_ranks_it_first():
    # launch speed +-0.1 m/s moves every landing by ~0.08 m a bounce; the steps' +-0.1 mm
    # errors and a +-1e-5 restitution move them by far less
    scene = StairsScene(initial=StairsInitial(drop_height=1.0), ball=Ball(radius=0.05))
    design = StairsDesign(restitution=0.8, launch_speed=3.0, landing_offset=1.38)
    tolerances = [("rise", "each", 1e-4, "normal"), ("tread", "each", 1e-4, "normal"),
                  ("restitution", "lot", 1e-5, "uniform"),
                  ("launch_speed", "lot", 0.1, "normal")]

    def run(deviations, stages):
        return run_builds(scene, design, deviations, stages)

    rows = sobol_indices(run, tolerances, stages=20, samples=256, seed=1)
    assert rows[0]["quantity"] == "launch_speed" and rows[0]["index"] > 0.9
    assert all(r["index"] < 0.05 for r in rows[1:])


def test_no_variation_gives_zero_indices():
    zero = [("rise", "each", 0.0, "normal"), ("tread", "lot", 0.0, "uniform")]
    rows = sobol_indices(additive(WEIGHTS), zero, stages=4)
    assert [r["index"] for r in rows] == [0.0, 0.0]

    def constant(deviations, stages):
        n = len(next(iter(deviations.values())))
        return BuildOutcome(np.zeros(n, dtype=int), np.full(n, "", dtype=object), np.ones(n),
                            np.ones(n, dtype=bool))

    rows = sobol_indices(constant, TOLERANCES, stages=4, samples=64)
    assert all(r["index"] == 0.0 and r["first"] == 0.0 for r in rows)


@pytest.mark.parametrize("tolerances, kwargs, words", [
    ([("rise", "every", 1.0, "normal")], {}, "applies_to must be one of each, lot"),
    ([("rise", "each", 1.0, "gauss")], {}, "distribution must be one of normal, uniform"),
    ([("rise", "each", -1.0, "normal")], {}, "finite number >= 0"),
    ([("rise", "each", math.inf, "normal")], {}, "finite number >= 0"),
    ([("rise", "each", None, "normal")], {}, "finite number >= 0, not None"),
    ([("rise", "each", 1.0, "normal")] * 2, {}, "given twice"),
    ([("rise", "each", 1.0, "normal")], {"output": "yield"}, "output must be one of"),
    ([("rise", "each", 1.0, "normal")], {"samples": 1}, "samples must be >= 2"),
])
def test_bad_requests_are_refused_in_words(tolerances, kwargs, words):
    with pytest.raises(ValueError, match=words):
        sobol_indices(additive(WEIGHTS), tolerances, stages=3, **kwargs)


def test_objects_with_the_fields_work_like_tuples():
    class Tolerance:
        def __init__(self, quantity, applies_to, value, distribution):
            self.quantity, self.applies_to = quantity, applies_to
            self.value, self.distribution = value, distribution

    as_objects = [Tolerance(*t) for t in TOLERANCES]
    assert (sobol_indices(additive(WEIGHTS), as_objects, stages=3, samples=64, seed=2)
            == sobol_indices(additive(WEIGHTS), TOLERANCES, stages=3, samples=64, seed=2))


def test_the_bar_chart_is_a_png(tmp_path):
    rows = sobol_indices(additive(WEIGHTS), TOLERANCES, stages=3, samples=128)
    path = plot_sensitivity(rows, tmp_path / "sensitivity.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["sensitivity.png"]


def test_the_same_seed_gives_the_same_intervals_seed_0_too():
    for seed in (0, 5):
        a, b = (sobol_indices(additive(WEIGHTS), TOLERANCES, stages=3, samples=64, seed=seed)
                for _ in range(2))
        assert a == b
