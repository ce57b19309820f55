"""Long rows and one design per spec: the start-up path, the streamed checks, the row limit, the
tie-break on a flat optimum across optimize, table and sheet.

Reference numbers come from other code: scipy's own Sobol' points, the base-code tolerance
definition written afresh in tests/test_optimize.py (`robust_tolerance_grid`), the event
simulator, a brute-force search over the flat optimum's set.
"""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from test_optimize import propagate_offsets, robust_tolerance_grid

from pdm_design.api import design
from pdm_design.formulation import formulate
from pdm_design.sheet.build import sheet_for
from pdm_design.solve import optimize
from pdm_design.solve.check import sampled_offsets_check
from pdm_design.solve.sobol import sobol
from pdm_design.spec import parse_spec
from pdm_design.status import Status
from pdm_design.sweep.run import run_sweep
from pdm_design.verify.tolerance import verify_tolerance

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
ROBUST = PROBLEMS / "manipulators_robust.toml"


def robust_data(stages: int = 6, **design) -> dict:
    data = tomllib.loads(ROBUST.read_text())
    data["verification"]["stages"] = stages
    data["design"].update(design)
    return data


# -- start-up ---------------------------------------------------------------------------------

@pytest.mark.parametrize("dimension", [1, 2, 3, 6, 16])
@pytest.mark.parametrize("seed", [0, 7])
def test_sobol_points_are_scipys_bit_for_bit(dimension, seed):
    from scipy.stats import qmc

    for count in (1, 7, 16):
        expected = qmc.Sobol(d=dimension, scramble=True, seed=seed).random_base2(4)[:count]
        assert np.array_equal(sobol(dimension, count, seed), expected)


def test_optimize_imports_neither_cvxpy_nor_scipy_stats_unless_asked(tmp_path):
    def imported(*extra):
        code = ("import sys; from pdm_design.cli import main\n"
                "try:\n    main([" + ", ".join(repr(a) for a in ("optimize", str(ROBUST), *extra))
                + "], standalone_mode=False)\nexcept SystemExit:\n    pass\n"
                "print('MODULES:', *sorted(m for m in sys.modules if m in "
                "('cvxpy', 'scipy.stats', 'scipy.stats.qmc')))")
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             check=True).stdout
        assert "status: optimal" in out and "confirmed by" in out  # solved and verified
        return out.split("MODULES:")[-1].strip()

    assert imported() == ""
    assert "cvxpy" in imported("--linearised")


def test_the_linearised_sets_are_computed_only_when_asked_and_say_so():
    spec = parse_spec(robust_data())
    plain = optimize(spec, check_samples=0)
    assert plain.linearised.square == 0.0 and not plain.linearised.box
    assert plain.linearised.status.startswith("not computed: not asked for")
    asked = optimize(spec, check_samples=0, linearise=True)
    assert asked.linearised.status == "optimal"
    assert asked.linearised.square == pytest.approx(plain.tolerance["dx"], rel=1e-4)


# -- the streamed check -----------------------------------------------------------------------

@pytest.mark.parametrize("factor, passes", [(1.0, True), (1.6, False)])
def test_the_streamed_check_judges_as_an_independent_propagation(factor, passes):
    """At 40 stages, the worst excess over the streamed samples agrees in sign with the numpy
    stage-by-stage propagation of tests/test_optimize.py on the same fixed patterns."""
    spec = parse_spec(robust_data(40))
    result = optimize(spec, check_samples=0)
    form = formulate(spec)
    tau = factor * result.tolerance["dx"]
    check = sampled_offsets_check(form, result.solution.x, form.parameters(), tau, samples=64)
    N = 40
    alt = np.where(np.arange(N + 1) % 2 == 0, 1.0, -1.0)
    dy = tau * np.vstack([alt, -alt, np.ones(N + 1), -np.ones(N + 1), alt, alt])
    dx = tau * np.vstack([np.zeros(N), np.zeros(N), np.ones(N), -np.ones(N),
                          np.ones(N), -np.ones(N)])
    independent = propagate_offsets(spec.scene, result.design, dx, dy, N).min()
    assert check["passed"] is passes
    assert bool(independent >= -1e-9) is passes


# -- the drift's closed form: a box at least the former one, sound in the simulator -------------

def former_optimum(scene, stages):
    """The former definition's box (the drift bound (N-1) min(r(2 tol), r(-2 tol))), maximised
    over alpha and beta by the independent numpy grid of tests/test_optimize.py, refined twice
    around its best cell."""
    lo, hi = np.array([0.0, 0.2]), np.array([0.6, 1.2])  # the spec's bounds
    for cells in (61, 21, 21):
        alpha, beta = np.linspace(lo[0], hi[0], cells), np.linspace(lo[1], hi[1], cells)
        grid = robust_tolerance_grid(scene, alpha, beta, link_length=2.0, mass_ratio=10.0,
                                     stages=stages, iters=40)
        i, j = np.unravel_index(np.argmax(grid), grid.shape)
        step = np.array([alpha[1] - alpha[0], beta[1] - beta[0]])
        centre = np.array([alpha[i], beta[j]])
        lo, hi = np.maximum(centre - step, [0.0, 0.2]), np.minimum(centre + step, [0.6, 1.2])
    return grid.max()


@pytest.mark.parametrize("stages", [6, 20, 100])
def test_the_box_is_at_least_the_former_definitions_optimum(stages):
    spec = parse_spec(robust_data(stages))
    result = optimize(spec, check_samples=0)
    assert result.status is Status.OPTIMAL
    former = former_optimum(spec.scene, stages)
    assert result.tolerance["dx"] >= former - 1e-7
    if stages > 6:  # the alternating drift bound is worth millimetres on longer rows
        assert result.tolerance["dx"] >= former + 1e-3


@pytest.mark.parametrize("stages", [20, 100])
def test_the_box_is_sound_stage_by_stage_where_the_drift_binds(stages):
    """The alternating patterns, which meet the drift bound, pass the independent numpy
    propagation at the box and fail a little beyond it: the closed form is the drift's worst."""
    spec = parse_spec(robust_data(stages))
    result = optimize(spec, check_samples=0)
    N = stages
    alt = np.where(np.arange(N + 1) % 2 == 0, 1.0, -1.0)
    signs_dy = np.vstack([alt, -alt, alt, -alt, np.ones(N + 1), -np.ones(N + 1)])
    signs_dx = np.vstack([np.ones(N), np.ones(N), -np.ones(N), -np.ones(N), np.ones(N),
                          -np.ones(N)])

    def worst(factor):
        tau = factor * result.tolerance["dx"]
        return propagate_offsets(spec.scene, result.design, tau * signs_dx, tau * signs_dy,
                                 N).min()

    assert worst(1.0) >= -1e-9
    assert worst(1.02) < 0


def test_every_corner_pattern_of_a_row_of_100_passes_the_simulator():
    spec = parse_spec(robust_data(100))
    result = optimize(spec, check_samples=0)
    point = spec.design_at({n: result.design[n] for n in spec.free_variables})
    box = verify_tolerance(spec, point, result.tolerance, samples=0)
    assert box["passed"] and box["samples"] == 12
    # and the simulator's worst corners are near: 1.2 times the box fails one
    bigger = {k: 1.2 * v for k, v in result.tolerance.items()}
    assert not verify_tolerance(spec, point, bigger, samples=0)["passed"]


# -- the row's limit ----------------------------------------------------------------------------

def test_an_optimised_row_longer_than_the_limit_is_bad_input(tmp_path):
    path = tmp_path / "long.toml"
    path.write_text(ROBUST.read_text().replace("stages = 6", "stages = 10001"))
    run = subprocess.run([sys.executable, "-m", "pdm_design", "optimize", str(path)],
                         capture_output=True, text=True)
    assert run.returncode == 2
    assert "verification.stages" in run.stderr and "10000" in run.stderr
    assert "Traceback" not in run.stderr


# -- one spec, one design ---------------------------------------------------------------------

FLAT_TEXT = (ROBUST.read_text().replace("mass = 1.0 ", "mass = 0.3 ")
             .replace("stages = 6", "stages = 10")
             .replace("mass_ratio = 10.0 ",
                      "mass_ratio = { min = 2.0, max = 20.0, initial = 10.0 }"))


def flat_data() -> dict:
    """A 0.3 kg box on a row of 10 with the mass ratio free: no row that limits the tolerance
    depends on the mass ratio, so every ratio in an interval is optimal."""
    return tomllib.loads(FLAT_TEXT)


def test_a_flat_optimum_is_settled_nearest_the_guess():
    spec = parse_spec(flat_data())
    tied = optimize(spec, check_samples=0)
    loose = optimize(spec, check_samples=0, tie_break=False)
    assert tied.status is loose.status is Status.OPTIMAL
    assert tied.stats.tie_break_kept
    assert tied.tolerance["dx"] == pytest.approx(loose.tolerance["dx"], rel=2e-6)
    # the set is flat: the ratio the starts found and the one the rule picks are 2x apart
    assert abs(tied.design["mass_ratio"] - loose.design["mass_ratio"]) > 1.0
    # brute force: the ratios on a grid whose box (alpha, beta free) is the optimum, within the
    # rule's slack; the rule's ratio is the one of them nearest the guess 10
    q = tied.design["mass_ratio"]
    ratios = np.linspace(q - 0.5, 10.0, 6)
    boxes = [optimize(parse_spec(robust_data(10, mass_ratio=float(r))
                                 | {"scene": flat_data()["scene"]}),
                      check_samples=0).tolerance["dx"] for r in ratios]
    optimal = [r for r, b in zip(ratios, boxes) if b >= tied.tolerance["dx"] * (1 - 2e-6)]
    assert optimal and min(optimal) < q  # optimal ratios below the rule's ...
    assert all(r <= q + 1e-3 for r in optimal)  # ... and none between it and the guess
    assert q < ratios[-1] == 10.0


def test_optimize_table_and_sheet_give_one_design(tmp_path):
    data = flat_data()
    spec_path = tmp_path / "box.toml"
    spec_path.write_text(FLAT_TEXT)
    alone = design(parse_spec(data))
    # the 0.8 point is warm-started from the 0.7 one along its chain
    rows = run_sweep(spec_path, ["friction=0.7:0.8:2"], tmp_path / "table", workers=1,
                     plots=False).rows
    row = next(r for r in rows if float(r["scene.palm.friction"]) == 0.8)
    sheet = sheet_for(spec_path)
    for name in ("alpha", "beta", "mass_ratio"):
        want = alone.analysis.design[name]
        assert float(row[name]) == pytest.approx(want, rel=1e-6), name
        assert sheet.design[name] == pytest.approx(want, rel=1e-6), name
    assert float(row["tolerance"]) == pytest.approx(alone.tolerance["dx"], rel=1e-7)
    # the row's box is simulated at the 12 corner patterns (4 sign corners x every pivot, the
    # pivots alternating, the second pivot alone) and a quarter of the spec's 16 random builds
    assert "confirmed by 28 simulated builds" in alone.verification["summary"]
    assert "confirmed by 16 simulated builds" in row["verification"]


@pytest.mark.parametrize("asked, kept", [(16, 4), (5, 2), (1, 1), (0, 0)])
def test_a_table_row_simulates_a_quarter_of_the_random_builds(asked, kept):
    from pdm_design.formulation.common import spec_key
    from pdm_design.sweep.run import table_verification

    data = flat_data()
    data["verification"]["samples"] = asked
    spec = parse_spec(data)
    row_spec = table_verification(spec)
    assert row_spec.verification.samples == kept
    assert spec_key(row_spec) == spec_key(spec)  # the same NLP, so the same design


# -- bounded caches -------------------------------------------------------------------------------

def test_the_caches_keep_the_specs_used_last_only():
    """A table's worker solves thousands of specs: the built NLPs and solvers of the last
    ENTRIES are kept (a table of 400 points held 1.5 GB when every one was)."""
    from pdm_design import lru
    from pdm_design.formulation import build
    from pdm_design.solve import ipopt

    first = parse_spec(robust_data(mass_ratio=5.0))
    optimize(first, check_samples=0, starts=1)
    for k in range(lru.ENTRIES + 2):
        optimize(parse_spec(robust_data(mass_ratio=6.0 + 0.1 * k)), check_samples=0, starts=1)
    assert len(build._CACHE) == len(ipopt._SOLVERS) == lru.ENTRIES
    again = optimize(first, check_samples=0, starts=1)
    assert again.status is Status.OPTIMAL and again.stats.build_time > 0.0
