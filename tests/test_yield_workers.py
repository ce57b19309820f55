"""A yield's simulated builds on local worker processes and on a Dask cluster on the loopback
interface: the same outcomes, build by build, and the same JSON as in one process."""

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main
from pdm_design.commands.yield_ import run_yield, yield_json
from pdm_design.spec import load_spec
from pdm_design.tolerances import parallel
from pdm_design.tolerances.yield_ import simulated

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
# 8 stages, back stops +-0.2 rad: most builds leave the closed forms (palms swinging from rest)
SPEC = PROBLEMS / "manipulators_all_toleranced.toml"
BUILDS = 24
SCALES = (0.5, 1.0, 1.5)


def yield_document(**where):
    spec = load_spec(str(SPEC))
    return yield_json(run_yield(spec, str(SPEC), builds=BUILDS, scales=SCALES, **where))


@pytest.fixture(scope="module")
def serial():
    return yield_document(workers=1)


def test_the_builds_leave_the_closed_forms_so_the_workers_have_work(serial):
    confirmed = json.loads(serial)["confirmed"]
    assert confirmed["left_closed_form"] >= 2 * parallel.MIN_PER_WORKER * 2
    assert confirmed["simulated"] == confirmed["left_closed_form"] + confirmed["random"]


def test_two_local_workers_give_the_same_json(serial):
    assert yield_document(workers=2) == serial


def test_the_pool_answers_each_build_as_the_simulator_does_alone():
    spec = load_spec(str(SPEC))
    point, tolerances = spec.design_at(), spec.tolerances
    run = parallel.BuildRun(spec.scene, point, {1.0: tolerances, 0.5: tolerances.scaled(0.5)},
                            tolerances.seed, spec.verification.stages, "default")
    tasks = [(1.0, i) for i in range(7)] + [(0.5, i) for i in range(3, 8)]
    alone = [simulated(spec.scene, point, run.tolerances[scale], run.seed, i, run.stages,
                       "default") for scale, i in tasks]
    assert parallel.simulate_builds(run, tasks, workers=2) == alone
    assert len(set(alone)) > 1  # not one answer for all: the order is checked too


def test_chunks_keep_the_build_order():
    tasks = [(1.0, i) for i in range(101)]
    for workers in (1, 2, 3, 64):
        chunks = parallel.chunks_of(tasks, workers)
        assert [t for c in chunks for t in c] == tasks
        assert max(map(len, chunks)) <= parallel.MAX_CHUNK


def cli_yield(*options):
    result = CliRunner().invoke(main, ["yield", str(SPEC), "--builds", str(BUILDS), "--format",
                                       "json", *options])
    assert result.exit_code == 0, result.stderr
    return result.stdout


def test_dask_cluster_on_loopback_gives_the_same_json():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol="tcp://", host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0") as cluster:
        on_dask = cli_yield("--scheduler", cluster.scheduler_address)
    assert on_dask == cli_yield("--workers", "1")
    assert json.loads(on_dask)["confirmed"]["left_closed_form"] > 0


def test_workers_in_the_spec_and_on_the_command_line_are_checked(tmp_path):
    text = SPEC.read_text().replace("[tolerances]\n", "[tolerances]\nworkers = 0\n")
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    result = CliRunner().invoke(main, ["yield", str(bad), "--builds", "2"])
    assert result.exit_code == 2 and "tolerances.workers" in result.stderr
    result = CliRunner().invoke(main, ["yield", str(SPEC), "--builds", "2", "--workers", "0"])
    assert result.exit_code == 2 and "--workers" in result.stderr


def test_a_scheduler_that_does_not_answer_is_bad_input():
    pytest.importorskip("distributed")
    result = CliRunner().invoke(main, ["yield", str(SPEC), "--builds", "8", "--scheduler",
                                       "tcp://127.0.0.1:1"])
    assert result.exit_code == 2 and "--scheduler" in result.stderr


def test_a_chunks_deviations_are_each_builds_own_draw():
    import numpy as np

    from pdm_design.tolerances.yield_ import one_build

    spec = load_spec(str(SPEC))
    tolerances = spec.tolerances
    run = parallel.BuildRun(spec.scene, spec.design_at(), {1.0: tolerances,
                                                           2.0: tolerances.scaled(2.0)},
                            5, spec.verification.stages, "default")
    tasks = [(1.0, 3), (1.0, 4), (1.0, 9), (2.0, 0), (2.0, 700), (1.0, 2)]
    for (scale, index), got in zip(tasks, parallel._drawn(run, tasks, span=8)):
        alone = one_build(run.tolerances[scale], 5, index, run.stages, scene=run.scene)
        assert got.keys() == alone.keys()
        for key in alone:
            assert got[key].shape == alone[key].shape
            np.testing.assert_array_equal(got[key], alone[key])


def test_the_map_on_two_workers_is_the_map_in_one_process(monkeypatch):
    # the closed-form map cut into chunks a worker (forced here for a small run): every
    # build's outcome the same, in order, as one process' single chunk
    import numpy as np

    from pdm_design.commands.yield_ import spec_tolerances
    from pdm_design.tolerances import yield_ as yield_module

    spec = load_spec(str(SPEC))
    tolerances = spec_tolerances(spec, str(SPEC))
    design = spec.design_at()
    one = yield_module.map_builds(spec.scene, design, tolerances, 300, 8, 5)
    monkeypatch.setattr(yield_module, "PARALLEL_ENTRIES", 1)
    two = yield_module.map_builds(spec.scene, design, tolerances, 300, 8, 5, workers=2)
    for field in ("stages_passed", "failure", "min_margin", "closed_form"):
        assert np.array_equal(getattr(one, field), getattr(two, field)), field


def test_a_run_given_its_known_verdicts_is_the_run_made_whole(monkeypatch):
    """yield_of(known=...): the simulator's verdicts of a run without the random confirmations,
    given to the same run with them, are not simulated again, and the result is the whole
    run's (the yield target's check at its run at 1)."""
    from pdm_design.tolerances.yield_ import yield_of

    spec = load_spec(str(SPEC))
    args = dict(builds=BUILDS, stages=spec.verification.stages, seed=spec.tolerances.seed,
                scales=(), sensitivity_samples=0, workers=1)
    design = spec.design_at()
    bare = yield_of(spec.scene, design, spec.tolerances, confirm=0, **args)
    whole = yield_of(spec.scene, design, spec.tolerances, confirm=5, **args)
    asked = []
    start = parallel.start_builds
    monkeypatch.setattr(parallel, "start_builds",
                        lambda run, tasks, **kw: asked.extend(tasks) or start(run, tasks, **kw))
    given = yield_of(spec.scene, design, spec.tolerances, confirm=5, known=bare.verdicts,
                     **args)
    assert given.to_json() == whole.to_json() and given.verdicts == whole.verdicts
    assert len(bare.verdicts) >= 5  # builds that left the closed forms, simulated once
    assert not {i for _, i in asked} & set(bare.verdicts)
    assert len(asked) == len(whole.verdicts) - len(bare.verdicts) > 0
