"""`pdm-design table`: sweep names and grids, rows against the API and the closed forms, row-by-row
writing, resume after an interruption, local workers and a Dask cluster on the loopback
interface giving the same table."""

import math
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.api import design
from pdm_design.cli import main
from pdm_design.errors import SpecError
from pdm_design.progress import progress_enabled
from pdm_design.spec import parse_spec
from pdm_design.sweep import run as sweep_run
from pdm_design.sweep.grid import point_data, resolve_name
from pdm_design.sweep.run import run_sweep
from pdm_design.sweep.tables import read_csv

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
MANIP = PROBLEMS / "paper_manipulators.toml"
STAIRS = PROBLEMS / "paper_stairs_frictionless.toml"
ROBUST = PROBLEMS / "manipulators_robust.toml"
# 3 x 2 grid: mass ratio and palm friction (0.3 makes the paper design slip: infeasible rows)
GRID = ["mass_ratio=4:16:3", "friction=0.3:0.8:2"]


def raw(path):
    return tomllib.loads(Path(path).read_text())


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


def rows_of(folder):
    return read_csv((Path(folder) / "table.csv").read_text())[1]


# --------------------------------------------------------------------------- names and grids

@pytest.mark.parametrize("path, name, expected", [
    (MANIP, "mass_ratio", ("design", "mass_ratio")),
    (MANIP, "friction", ("scene", "palm", "friction")),
    (STAIRS, "friction", ("scene", "friction")),
    (MANIP, "gravity", ("scene", "gravity")),
    (MANIP, "scene.body.width", ("scene", "body", "width")),
    (STAIRS, "spin", ("initial", "spin")),  # not written in the file: its default is swept
])
def test_sweep_name_resolves_to_one_key(path, name, expected):
    assert resolve_name(raw(path), name) == expected


def test_ambiguous_name_is_bad_input_listing_the_matches(tmp_path):
    code, _, err = run("table", MANIP, "--sweep", "width=1:2:2", "--out", tmp_path)
    assert code == 2
    assert "--sweep" in err and "scene.body.width" in err and "scene.palm.width" in err


def test_unknown_name_is_bad_input_with_close_matches(tmp_path):
    code, _, err = run("table", MANIP, "--sweep", "frction=0.1:0.2:2", "--out", tmp_path)
    assert code == 2
    assert "unknown parameter 'frction'" in err and "friction" in err


def test_malformed_sweep_is_bad_input(tmp_path):
    code, _, err = run("table", MANIP, "--sweep", "mass_ratio=1:2", "--out", tmp_path)
    assert code == 2 and "NAME=START:STOP:COUNT" in err


def test_grid_value_outside_domain_is_bad_input_before_solving(tmp_path):
    out = tmp_path / "t"
    code, _, err = run("table", STAIRS, "--sweep", "restitution=0.5:1.5:3", "--out", out)
    assert code == 2
    assert "design.restitution" in err and "<= 1" in err
    assert not (out / "table.csv").exists()


def test_sweeping_a_free_variable_fixes_it():
    data = point_data(raw(ROBUST), [("design", "alpha")], [0.3])
    spec = parse_spec(data, "robust")
    assert spec.design["alpha"] == 0.3
    assert spec.free_variables == ("beta",)


def test_a_warm_start_is_an_extra_start_and_leaves_the_guess(monkeypatch):
    # the spec's initial settles a flat optimum (solve/tiebreak.py): a warm start must not move it
    from pdm_design.sweep import run as sweep_run

    seen = {}

    def fake_design(spec, **kw):
        seen.update(initial=spec.design["alpha"].initial, start_from=kw.get("start_from"))
        raise RuntimeError("stop here")

    monkeypatch.setattr("pdm_design.api.design", fake_design)
    task = sweep_run.PointTask(raw(ROBUST), "robust", (("design", "link_length"),), (2.5,),
                               warm={"alpha": 0.35, "beta": 0.5})
    assert sweep_run.solve_point(task)["status"] == "error"
    assert seen == {"initial": raw(ROBUST)["design"]["alpha"]["initial"],
                    "start_from": {"alpha": 0.35, "beta": 0.5}}


# --------------------------------------------------------------------------- rows

def test_rows_equal_each_grid_point_solved_through_the_api(tmp_path):
    result = run_sweep(MANIP, GRID, tmp_path, workers=1, plots=False)
    data = raw(MANIP)
    assert len(result.rows) == 6
    for row in result.rows:
        q, mu = float(row["design.mass_ratio"]), float(row["scene.palm.friction"])
        data["design"]["mass_ratio"], data["scene"]["palm"]["friction"] = q, mu
        outcome = design(parse_spec(data, "point"))
        assert row["status"] == outcome.status.value
        assert float(row["handover_speed"]) == outcome.analysis.periodic["handover_speed"]
        assert float(row["margin.slip_carry"]) == outcome.analysis.margins["slip_carry"]
        assert (row["verified"] == "true") == outcome.verification["passed"]


def test_optimised_rows_equal_each_point_optimised_on_its_own(tmp_path):
    # alpha and beta free, max_offset_tolerance: the second point is warm-started from the
    # first, yet must reach the optimum a cold solve of that point reaches
    result = run_sweep(ROBUST, ["mass_ratio=4:12:2"], tmp_path, workers=1, plots=False)
    data = raw(ROBUST)
    for row in result.rows:
        assert row["status"] == "optimal"
        data["design"]["mass_ratio"] = float(row["mass_ratio"])
        alone = design(parse_spec(data, "point"))
        assert float(row["tolerance"]) == pytest.approx(alone.tolerance["dx"], rel=1e-6)
        assert float(row["objective"]) == pytest.approx(alone.objective["value"], rel=1e-6)
        for name in ("alpha", "beta"):
            assert float(row[name]) == pytest.approx(alone.analysis.design[name], abs=1e-5)


def test_rows_match_the_closed_form_handover_speed(tmp_path):
    result = run_sweep(MANIP, ["mass_ratio=2:20:4"], tmp_path, workers=1, plots=False)
    a, b, l, g = 0.2, 0.6, 2.0, 9.81
    for row in result.rows:
        q = float(row["mass_ratio"])
        c = (q / (1 + q) * math.cos(a + b)) ** 2
        speed = math.sqrt(2 * g * l * (math.cos(a) - math.cos(b)) / (1 - c))
        assert float(row["handover_speed"]) == pytest.approx(speed, rel=1e-12)
        assert float(row["palm_mass"]) == pytest.approx(1.0 / q, rel=1e-15)


def test_stairs_rows_follow_the_periodic_rise(tmp_path):
    result = run_sweep(STAIRS, ["restitution=0.5:0.9:3"], tmp_path, workers=1, plots=False)
    for row in result.rows:
        eps = float(row["design.restitution"])
        assert float(row["rise"]) == pytest.approx((1 - eps**2) * 1.0, rel=1e-12)
        tread = 2.0 * (1 + eps) * math.sqrt(2 * 9.81) / 9.81
        assert float(row["tread"]) == pytest.approx(tread, rel=1e-12)


def test_infeasible_rows_carry_the_reason(tmp_path):
    result = run_sweep(MANIP, ["friction=0.3:0.3:1"], tmp_path, workers=1, plots=False)
    (row,) = result.rows
    assert row["status"] == "infeasible"
    # demand tan(beta) = tan(0.6) = 0.684 > 0.3: slip during the carry
    assert "slip_carry" in row["reason"]
    assert float(row["margin.slip_carry"]) == pytest.approx(-(1 - 0.3 / math.tan(0.6)))
    assert "Why points fail" in (tmp_path / "table.md").read_text()


def test_rows_are_appended_as_they_finish(tmp_path):
    seen = []

    def on_row(point, row):
        seen.append(len(rows_of(tmp_path)))

    run_sweep(MANIP, GRID, tmp_path, workers=1, plots=False, on_row=on_row)
    assert seen == [1, 2, 3, 4, 5, 6]


def test_warm_start_passes_each_design_along_its_chain(tmp_path, monkeypatch):
    warm_seen = {}

    def fake_solve(task):
        warm_seen[task.values] = task.warm
        alpha = 0.1 + task.values[0]  # a "design" that depends on the grid point
        return {"status": "optimal", "alpha": repr(alpha), "beta": "0.5"}

    monkeypatch.setattr(sweep_run, "solve_point", fake_solve)
    run_sweep(ROBUST, ["mass_ratio=1:4:4"], tmp_path, workers=1, chain=2, plots=False)
    assert warm_seen[(1.0,)] is None and warm_seen[(3.0,)] is None  # chain heads
    assert warm_seen[(2.0,)] == {"alpha": 1.1, "beta": 0.5}
    assert warm_seen[(4.0,)] == {"alpha": 3.1, "beta": 0.5}


# --------------------------------------------------------------------------- resume

def _interrupt_after(n):
    def on_row(point, row):
        on_row.count += 1
        if on_row.count == n:
            raise KeyboardInterrupt
    on_row.count = 0
    return on_row


def test_interrupted_sweep_keeps_its_rows_and_resume_gives_the_same_table(tmp_path):
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    run_sweep(MANIP, GRID, whole, workers=1)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(MANIP, GRID, cut, workers=1, on_row=_interrupt_after(4))
    assert len(rows_of(cut)) == 4 and not (cut / "table.md").exists()
    result = run_sweep(MANIP, GRID, cut, workers=1, resume=True)
    assert (result.computed, result.reused) == (2, 4)
    for name in ("table.csv", "table.md"):
        assert (cut / name).read_text() == (whole / name).read_text()


def test_resume_drops_a_row_cut_short_mid_write(tmp_path):
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    run_sweep(MANIP, GRID, whole, workers=1, plots=False)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(MANIP, GRID, cut, workers=1, plots=False, on_row=_interrupt_after(3))
    with open(cut / "table.csv", "a") as stream:
        stream.write("16.0,0.8,evaluated,0.2,0.6")  # a kill in the middle of a write
    result = run_sweep(MANIP, GRID, cut, workers=1, plots=False, resume=True)
    assert (result.computed, result.reused) == (3, 3)
    assert (cut / "table.csv").read_text() == (whole / "table.csv").read_text()


def test_resume_from_the_command_line_solves_only_the_missing_rows(tmp_path):
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    run_sweep(MANIP, GRID, whole, workers=1)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(MANIP, GRID, cut, workers=1, on_row=_interrupt_after(5))
    code, out, err = run("table", MANIP, *(f"--sweep={g}" for g in GRID), "--out", cut,
                         "--resume", "--workers", "1")
    assert code == 0, err
    assert "1 solved now, 5 kept from before" in out
    assert (cut / "table.md").read_text() == (whole / "table.md").read_text()


def test_resume_solves_again_a_row_edited_to_a_status_or_a_point_it_does_not_have(tmp_path):
    whole, edited = tmp_path / "whole", tmp_path / "edited"
    run_sweep(MANIP, GRID, whole, workers=1, plots=False)
    run_sweep(MANIP, GRID, edited, workers=1, plots=False)
    lines = (edited / "table.csv").read_text().splitlines()
    header = lines[0].split(",")
    status = header.index("status")
    cells = lines[1].split(",")
    cells[status] = "garbage"               # a status no run writes
    off_grid = lines[2].split(",")
    off_grid[0] = "notanumber"              # a sweep value the grid does not have
    (edited / "table.csv").write_text("\n".join([lines[0], ",".join(cells), ",".join(off_grid),
                                                  *lines[3:]]) + "\n")
    result = run_sweep(MANIP, GRID, edited, workers=1, plots=False, resume=True)
    assert (result.computed, result.reused) == (2, 4)
    assert (edited / "table.csv").read_text() == (whole / "table.csv").read_text()


def test_the_regenerate_line_rebuilds_the_same_table(tmp_path):
    spec = tmp_path / "a spec.toml"  # a path the shell would split
    spec.write_text(MANIP.read_text())
    first = tmp_path / "first"
    run_sweep(spec, ["mass_ratio=4:16:3"], first, workers=1, plots=False, chain=2)
    (line,) = [x for x in (first / "table.md").read_text().splitlines()
               if x.startswith("Regenerate: ")]
    words = shlex.split(line.removeprefix("Regenerate: `").removesuffix("`."))
    assert words[:2] == ["pdm-design", "table"] and "--chain" in words
    again = tmp_path / "again"
    code, _, err = run(*words[1:], "--out", again, "--no-plots", "--workers", "1")
    assert code == 0, err
    assert (again / "table.csv").read_text() == (first / "table.csv").read_text()


def test_resume_refuses_a_table_without_its_sweep_json(tmp_path):
    run_sweep(MANIP, ["mass_ratio=4:16:3"], tmp_path, workers=1, plots=False)
    (tmp_path / "sweep.json").unlink()
    with pytest.raises(SpecError, match="no readable sweep.json"):
        run_sweep(MANIP, ["mass_ratio=4:16:3"], tmp_path, workers=1, plots=False, resume=True)


def test_resume_refuses_a_folder_made_by_other_sweeps(tmp_path):
    run_sweep(MANIP, ["mass_ratio=4:16:3"], tmp_path, workers=1, plots=False)
    with pytest.raises(SpecError, match="--resume"):
        run_sweep(MANIP, ["mass_ratio=4:16:4"], tmp_path, workers=1, plots=False, resume=True)


# --------------------------------------------------------------------------- parallel

def test_local_worker_processes_give_the_same_table(tmp_path):
    run_sweep(MANIP, GRID, tmp_path / "one", workers=1, plots=False)
    run_sweep(MANIP, GRID, tmp_path / "two", workers=2, chain=1, plots=False)
    assert (tmp_path / "two" / "table.csv").read_text() == (
        tmp_path / "one" / "table.csv").read_text()


def test_dask_cluster_on_loopback_gives_the_same_table(tmp_path):
    distributed = pytest.importorskip("distributed")
    run_sweep(MANIP, GRID, tmp_path / "local", workers=1, plots=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol="tcp://", host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0") as cluster:
        code, out, err = run("table", MANIP, *(f"--sweep={g}" for g in GRID), "--scheduler",
                             cluster.scheduler_address, "--chain", "1", "--no-plots",
                             "--out", tmp_path / "dask")
    assert code == 0, err
    assert "6 solved now" in out
    assert (tmp_path / "dask" / "table.csv").read_text() == (
        tmp_path / "local" / "table.csv").read_text()


# --------------------------------------------------------------------------- Ctrl-C

def _running_in_group(pgid):
    """Processes of the process group `pgid` still running (zombies are dead: left out)."""
    running = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:  # ended meanwhile
                continue
            state, _, group = stat.rsplit(")", 1)[1].split()[:3]
            if int(group) == pgid and state != "Z":
                running.append(int(entry.name))
    return running


def test_ctrl_c_twice_in_process_stops_the_workers_once_and_restores_the_handler(tmp_path):
    import multiprocessing
    import signal

    # a shell's background job starts with SIGINT ignored, and the guard leaves an ignored
    # signal ignored: press as in a terminal, where Python's own handler is installed
    outer = signal.signal(signal.SIGINT, signal.default_int_handler)

    def press_twice(point, row):  # Ctrl-C twice as the first row is written
        if not press_twice.pressed:
            press_twice.pressed = True
            signal.raise_signal(signal.SIGINT)
            signal.raise_signal(signal.SIGINT)
    press_twice.pressed = False

    try:
        with pytest.raises(KeyboardInterrupt):
            run_sweep(MANIP, GRID, tmp_path, workers=2, plots=False, on_row=press_twice)
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, outer)
    assert multiprocessing.active_children() == []  # the workers were ended, not left to idle
    rows = rows_of(tmp_path)
    assert 1 <= len(rows) < 6 and (tmp_path / "table.csv").read_text().endswith("\n")


def _terminal_sigint():
    """In the child: SIGINT as a terminal's command has it (a shell's background job, a CI
    runner's step, may start it ignored, and the table leaves an ignored signal ignored)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _table_stopped_by(out, grid, workers, stop):
    """Run `table` in a child process (its own process group) until a row is written, then call
    stop(child); returns (the child, its stderr) once it has ended."""
    import os
    import signal
    import time

    child = subprocess.Popen(
        [sys.executable, "-m", "pdm_design", "table", str(ROBUST), *(f"--sweep={g}" for g in grid),
         "--out", str(out), "--workers", str(workers), "--no-plots"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
        preexec_fn=_terminal_sigint)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and child.poll() is None:
            csv_path = out / "table.csv"
            if csv_path.exists() and csv_path.read_text().count("\n") >= 2:  # a row is in
                break
            time.sleep(0.02)
        assert child.poll() is None, "the sweep ended before it could be stopped"
        stop(child)
        _, err = child.communicate(timeout=30)  # a hang guard, not a speed claim
    finally:
        if child.poll() is None:
            os.killpg(child.pid, signal.SIGKILL)
            child.communicate()
    return child, err


@pytest.mark.slow
@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc; signals a process group")
@pytest.mark.parametrize("workers, gap", [(2, 0.05), (2, 0.2), (1, 0.2)])
def test_ctrl_c_twice_ends_the_table_with_exit_1_whole_rows_and_no_worker_left(tmp_path,
                                                                               workers, gap):
    # A terminal's Ctrl-C signals the whole process group (`table` and its workers), here twice,
    # `gap` seconds apart, once rows are being written. With 2 workers the second press used to
    # land in the pool's shutdown and hang the command for ever; in this process (1 worker) it
    # lands while Python shuts down, where it used to kill the command by SIGINT (exit -2).
    import csv
    import io
    import os
    import signal
    import time

    def press_twice(child):
        os.killpg(child.pid, signal.SIGINT)
        time.sleep(gap)
        os.killpg(child.pid, signal.SIGINT)

    out = tmp_path / "t"
    grid = ["mass_ratio=5:20:4", "beta=0.4:0.7:4"]  # 16 points, 4 chains
    child, err = _table_stopped_by(out, grid, workers, press_twice)
    assert child.returncode == 1, err
    assert "interrupted" in err and "Traceback" not in err, err
    assert _running_in_group(child.pid) == []  # no worker left behind
    text = (out / "table.csv").read_text()
    assert text.endswith("\n")  # no line cut short
    header, *lines = list(csv.reader(io.StringIO(text)))
    assert 1 <= len(lines) < 16 and all(len(line) == len(header) for line in lines)
    rows = rows_of(out)
    assert not any(row["status"] == "error" for row in rows)
    result = run_sweep(ROBUST, grid, out, workers=2, plots=False, resume=True)
    assert (result.reused, result.computed) == (len(rows), 16 - len(rows))  # all rows kept


@pytest.mark.slow
@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc; signals a process")
def test_sigterm_to_the_table_ends_its_workers_and_keeps_its_rows(tmp_path):
    # A CI job's timeout or `kill` sends SIGTERM to the main process only: it used to end at
    # once and leave its two workers running, re-parented to init.
    import os
    import signal

    out = tmp_path / "t"
    grid = ["mass_ratio=5:20:4", "beta=0.4:0.7:4"]
    child, err = _table_stopped_by(out, grid, 2, lambda c: os.kill(c.pid, signal.SIGTERM))
    assert child.returncode == 1 and "interrupted" in err, err
    assert _running_in_group(child.pid) == []  # no worker left behind
    rows = rows_of(out)
    assert 1 <= len(rows) < 16 and not any(row["status"] == "error" for row in rows)


# --------------------------------------------------------------------------- a failed start

def _files(folder):
    return {p.name: p.read_bytes() for p in sorted(Path(folder).iterdir())}


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:1", "foo"])
def test_unreachable_scheduler_leaves_the_folder_as_it_was_with_one_error_line(tmp_path,
                                                                               address):
    # a finished table, then another sweep into the same folder on a scheduler that refuses
    # (Dask retries until the connect timeout: a few seconds) or a malformed address; a child
    # process, so that what Python prints at exit (a Dask client closed by the garbage
    # collector) is seen too
    pytest.importorskip("distributed")
    out = tmp_path / "r1"
    run_sweep(MANIP, ["mass_ratio=5:10:2"], out, workers=1)
    before = _files(out)
    assert {"table.md", "optimum.png", "tolerance.svg"} <= set(before)
    done = subprocess.run(
        [sys.executable, "-m", "pdm_design", "table", str(MANIP), "--sweep", "alpha=0.1:0.3:3",
         "--out", str(out), "--scheduler", address],
        capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("error: ") and done.stderr.count("\n") == 1, done.stderr
    assert "--scheduler" in done.stderr and address in done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    assert _files(out) == before


def _listening(answer: bytes | None):
    """A loopback server that accepts connections and answers `answer` to what it reads, or
    nothing (None): not a Dask scheduler. Returns its port."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held = []

    def serve():
        while True:
            conn, _ = server.accept()
            held.append(conn)
            if answer is not None:
                conn.recv(4096)
                conn.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    return server.getsockname()[1]


@pytest.mark.parametrize("answer", [
    b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n",  # e.g. a dashboard's port
    pytest.param(None, marks=pytest.mark.slow),  # accepts, never answers: Dask waited minutes
])
def test_a_port_with_no_dask_scheduler_is_bad_input_within_the_timeout(tmp_path, answer):
    pytest.importorskip("distributed")
    address = f"tcp://127.0.0.1:{_listening(answer)}"
    done = subprocess.run(
        [sys.executable, "-m", "pdm_design", "table", str(MANIP), "--sweep", "alpha=0.1:0.3:3",
         "--out", str(tmp_path / "t"), "--scheduler", address],
        capture_output=True, text=True, timeout=60)  # a hang guard, not a speed claim
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("error: command line: --scheduler: ") and address in done.stderr
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert not (tmp_path / "t").exists()


def test_bad_workers_on_resume_leaves_the_folder_as_it_was(tmp_path):
    # resume rewrites table.csv without its cut-short last line: not before the run can start
    with pytest.raises(KeyboardInterrupt):
        run_sweep(MANIP, GRID, tmp_path, workers=1, plots=False, on_row=_interrupt_after(3))
    with open(tmp_path / "table.csv", "a") as stream:
        stream.write("16.0,0.8,evaluated,0.2,0.6")
    before = _files(tmp_path)
    with pytest.raises(SpecError, match="--workers"):
        run_sweep(MANIP, GRID, tmp_path, workers=0, plots=False, resume=True)
    assert _files(tmp_path) == before
    with pytest.raises(SpecError, match="--workers"):  # nor a fresh run
        run_sweep(MANIP, ["mass_ratio=4:16:2"], tmp_path, workers=0, plots=False)
    assert _files(tmp_path) == before


def test_a_dask_client_that_failed_to_start_is_closed_at_once(monkeypatch):
    distributed = pytest.importorskip("distributed")
    made = []
    real_init = distributed.Client.__init__

    def init(self, *args, **kwargs):
        made.append(self)
        real_init(self, *args, **kwargs)

    monkeypatch.setattr(distributed.Client, "__init__", init)
    with pytest.raises(SpecError, match="--scheduler"):
        sweep_run._DaskExecutor("tcp://")  # malformed: fails at once, the client half-started
    (client,) = made
    assert client.status == "closed"


# --------------------------------------------------------------------------- the command

def test_table_command_writes_tables_and_plots(tmp_path):
    code, out, err = run("table", STAIRS, "--sweep", "restitution=0.6:0.8:3", "--out", tmp_path,
                         "--workers", "1")
    assert code == 0, err
    assert "3 points (3 evaluated)" in out
    assert err == ""  # no progress bar when stderr is not a terminal
    assert (tmp_path / "table.md").read_text().count("| evaluated |") == 3
    for name in ("optimum", "tolerance"):
        assert (tmp_path / f"{name}.png").read_bytes().startswith(b"\x89PNG")
        assert b"<svg" in (tmp_path / f"{name}.svg").read_bytes()


def test_progress_bar_only_on_a_terminal():
    class Stream:
        def __init__(self, tty):
            self.tty = tty

        def isatty(self):
            return self.tty

    assert progress_enabled(Stream(True)) and not progress_enabled(Stream(False))


def test_a_tie_between_margins_names_the_first_in_the_scenes_list():
    # Frictionless stairs with the derived rise: the launch's nose condition is flight 1's own
    # (docs/optimizer.md, section 2), so the two margins agree to rounding; the table must name
    # nose_clearance every time, not whichever rounding made smaller.
    from pdm_design.sweep.tables import outcome_cells

    for eps in (0.4, 0.5, 0.6, 0.8, 0.95):
        spec = parse_spec({"name": "tie", "scene": {"kind": "stairs", "ball": {"radius": 0.05}},
                           "initial": {"drop_height": 1.0},
                           "design": {"restitution": eps, "launch_speed": 2.0}})
        outcome = design(spec, verify=False)
        m = outcome.analysis.margins
        assert m["first_nose_clearance"] == pytest.approx(m["nose_clearance"], abs=1e-12)
        assert outcome_cells(outcome, "stairs")["min_margin_name"] == "nose_clearance"
