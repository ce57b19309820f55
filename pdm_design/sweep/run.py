"""Running a sweep: every grid point solved through `pdm_design.api.design`, in parallel local
worker processes or on a Dask distributed cluster, rows appended to the CSV as they finish,
`resume` continuing an interrupted sweep, the final tables and plots written at the end.

Warm starts: the grid is cut into chains along the last axis (`grid.chains`); a chain's points
are solved in order, the first from every start as `optimize` solves it, each later one from
the local optima the point before reached (solve.optimize's `continued`; every start again when
one of those runs fails) and the design found there as an extra start. The spec's `initial`,
which picks one design of a flat optimum (solve/tiebreak.py), is left as it is. The swept
numbers are the NLP's parameters where they can be (formulation/parametric.py): one NLP, its
solvers and stage maps, serve every point. Chains run in parallel. The chains do not depend on
the number of workers or on the scheduler, so neither do the results (docs/tables.md).

Verification: a row simulates a quarter of the spec's random builds (`table_verification`).

Files in the output folder:
    table.csv     one row per grid point; appended row by row while the sweep runs (a row is a
                  whole line or absent), rewritten in grid order at the end
    table.md      the design table in Markdown (written at the end)
    optimum.png/.svg, tolerance.png/.svg   plots (written at the end)
    sweep.json    what the table was made from (spec digest, sweeps, columns): `resume`
                  refuses a folder made from another spec or other sweeps

Order of a run: everything that can fail on the input (the spec, the sweeps, a folder that does
not match on resume, the workers, the scheduler's address) is checked, and the workers started
or the Dask scheduler reached, before anything in the folder changes: a run that fails before
solving leaves the folder as it was. Only then is the folder started (a fresh table: sweep.json
and a header-only table.csv, the old table.md and plots removed; on resume: table.csv rewritten
with its whole, non-error rows).

Ctrl-C (any number of presses, at any moment): the sweep stops within a fraction of a second,
local workers are terminated mid-point (only finished rows are ever written) and the pool shut
down, and KeyboardInterrupt is raised with table.csv holding whole rows only; see
`interrupts`.
"""

from __future__ import annotations

import json
import os
import shlex
import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future
from concurrent.futures import wait as wait_futures
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..errors import SpecError
from ..io import write_atomic
from ..progress import progress_bar
from ..spec import parse_spec, read_spec_data
from ..spec.loader import content_digest
from ..status import Status
from . import tables
from .grid import GridPoint, SweepAxis, chains, grid_points, point_data, sweep_axes
from .interrupts import interrupt_guard

SCHEMA = "pdm-design/table/1"
CSV_NAME, MARKDOWN_NAME, META_NAME = "table.csv", "table.md", "sweep.json"
PLOT_NAMES = tuple(f"{n}.{e}" for n in ("optimum", "tolerance") for e in ("png", "svg"))
DEFAULT_CHAIN = 4
TABLE_SAMPLE_DIVISOR = 4  # a row's random builds: the spec's / 4 (table_verification)
WARM_STATUSES = ("optimal", "evaluated", "acceptable")
DASK_CONNECT_TIMEOUT = 5  # seconds to reach the Dask scheduler before --scheduler is refused
POLL_SECONDS = 0.1  # how often the main process looks for a Ctrl-C while local workers solve
TERMINATE_GRACE = 5  # seconds for terminated workers to end before they are killed


@dataclass(frozen=True)
class PointTask:
    """Everything a worker needs to solve one grid point (plain data: it travels by pickle)."""

    data: dict
    source: str
    paths: tuple[tuple[str, ...], ...]
    values: tuple[float, ...]
    warm: dict[str, float] | None = None
    # the local optima of the point before (OPTIMA of its result): solved again from them,
    # the starts only when that fails (solve.optimize's `continued`)
    continued: tuple = ()


OPTIMA = "optima"  # the key of a point's local optima in solve_point's answer (not a cell)


def solve_point(task: PointTask) -> dict:
    """Solve one grid point; its table cells (no sweep columns) and, under OPTIMA, the local
    optima its next point continues from. Never raises for a bad point: an exception becomes
    a row with status `error` and the exception as its reason."""
    from ..api import design

    try:
        spec = table_verification(parse_spec(point_data(task.data, task.paths, task.values),
                                             task.source))
        # the swept numbers as the NLP's parameters: one NLP, its solvers and stage maps, for
        # every point (formulation/parametric.py)
        spec = replace(spec, nlp_parameters=tuple(".".join(path) for path in task.paths))
        outcome = design(spec, start_from=task.warm, continued=task.continued)
        return tables.outcome_cells(outcome, spec.kind) | {OPTIMA: outcome.optima}
    except Exception as error:  # one point's failure must not end the sweep
        return tables.error_cells(error)


def table_verification(spec):
    """The spec a table row is verified with: the spec's random builds divided by
    TABLE_SAMPLE_DIVISOR (at least one when it asks for any); the nominal run and every corner
    pattern as `optimize` simulates them, and the design itself unchanged (the random builds
    are drawn after it is found). docs/tables.md, "Verification in a table"."""

    asked = spec.verification.samples
    samples = -(-asked // TABLE_SAMPLE_DIVISOR)  # rounded up: 0 stays 0, 1 stays 1
    if samples == asked:
        return spec
    return replace(spec, verification=replace(spec.verification, samples=samples))


@dataclass(frozen=True)
class SweepResult:
    """A finished sweep: its rows in grid order and the files written."""

    folder: Path
    axes: tuple[SweepAxis, ...]
    columns: tuple[str, ...]
    rows: list[dict[str, str]]
    computed: int
    reused: int
    files: tuple[Path, ...] = field(default=())

    @property
    def errors(self) -> int:
        return sum(r.get("status") == tables.ERROR for r in self.rows)


def run_sweep(spec_path: str | os.PathLike, sweeps: list[str] | tuple[str, ...],
              out: str | os.PathLike, *, workers: int | None = None,
              scheduler: str | None = None, resume: bool = False, chain: int = DEFAULT_CHAIN,
              show_progress: bool | None = None, plots: bool = True,
              on_row: Callable[[GridPoint, dict[str, str]], None] | None = None) -> SweepResult:
    """Solve the spec at every point of the grid the `--sweep` texts describe; write the table.

    workers: local worker processes (default: the machine's cores; 1 solves in this process).
    scheduler: address of a Dask distributed scheduler: run the points there instead.
    resume: keep the rows already in `out`/table.csv (made from the same spec and sweeps) and
        solve only the others (rows with status `error` are solved again).
    chain: grid points per warm-start chain. on_row: called after each row is written.
    Raises SpecError for bad input (the spec, a sweep, a grid value out of a parameter's domain,
    a folder that does not match on resume, the workers, a scheduler that does not answer
    within DASK_CONNECT_TIMEOUT seconds), always before the folder is changed.
    """
    source = str(spec_path)
    data = read_spec_data(spec_path)
    base = parse_spec(data, source)  # the spec itself must be valid (a clear error if not)
    axes = sweep_axes(data, list(sweeps))
    points = grid_points(axes)
    paths = tuple(a.path for a in axes)
    labels = [_label(source, axes, p) for p in points]
    for point, label in zip(points, labels):  # every point must be a valid spec, before solving
        parse_spec(point_data(data, paths, point.values), label)
    if chain < 1:
        raise SpecError("command line", "--chain", "an integer >= 1", str(chain))
    sweep_columns = tuple(a.column for a in axes)
    header = tables.columns(base.kind, sweep_columns)
    folder = Path(out)
    meta = {"schema": SCHEMA, "spec": source, "spec_sha256": content_digest(data),
            "sweeps": [a.to_json() for a in axes], "chain": chain, "columns": list(header)}
    kept = _read_folder(folder, meta, header, resume)  # reads only
    keys = {p.key for p in points}  # a row edited off the grid is not one of its points
    done = {key: row for key, row in (kept or {}).items() if key in keys}
    reused = len(done)
    free = [n for n, v in (data.get("design") or {}).items()
            if isinstance(v, dict) and ("design", n) not in paths]

    todo = [p for p in points if p.key not in done]
    all_chains = chains(points, chain)
    csv_path = folder / CSV_NAME
    optima: dict = {}  # grid key -> the local optima its next point continues from
    # Ctrl-C from here until the workers are shut down: noted while the pool starts, runs and
    # stops, raised as KeyboardInterrupt only where the sweep is safe to stop (`interrupts`)
    with interrupt_guard() as guard:
        # the last thing that can fail on the input (--workers, --scheduler): before the
        # folder is touched, so that a failed start leaves it as it was
        executor = _executor(workers, scheduler, len(all_chains)) if todo else None
        with _closing(executor):
            guard.at_once = not isinstance(executor, _ProcessExecutor)
            guard.check()  # pressed while the workers started: the folder is left as it was
            _start_folder(folder, meta, header, kept)
            with open(csv_path, "a", encoding="utf-8", newline="") as stream, \
                    progress_bar(len(points), f"sweep {Path(source).name}",
                                 enabled=show_progress, completed=reused) as advance:

                def record(i: int, cells: dict) -> None:
                    cells = dict(cells)
                    optima[points[i].key] = cells.pop(OPTIMA, ())
                    row = {**dict(zip(sweep_columns, points[i].key)), **cells}
                    stream.write(tables.csv_line([row.get(c, "") for c in header]))
                    stream.flush()
                    done[points[i].key] = row
                    advance(1)
                    if on_row is not None:
                        on_row(points[i], row)

                def task(i: int, warm: dict | None, before) -> PointTask:
                    return PointTask(data, labels[i], paths, points[i].values, warm,
                                     optima.pop(before, ()) if before is not None else ())

                if todo:
                    _execute(executor, all_chains, points, done, free, task, record,
                             guard.check)
            guard.at_once = False  # a Ctrl-C from here is only noted: the close runs whole
        guard.check()  # pressed while the idle workers were shut down: still an interrupt

    rows = [done[p.key] for p in points]
    files = _write_outputs(folder, base, source, axes, header, rows, plots, chain)
    return SweepResult(folder, axes, header, rows, computed=len(todo), reused=reused,
                       files=files)


def _label(source: str, axes, point: GridPoint) -> str:
    where = ", ".join(f"{a.column} = {v:g}" for a, v in zip(axes, point.values))
    return f"{source} (sweep point {where})"


# --------------------------------------------------------------------------- the folder

def _read_folder(folder: Path, meta: dict, header, resume: bool) -> dict | None:
    """The rows (by grid key) kept from the table in `folder` when resuming it; None when the
    run starts a fresh table. Checks the folder (SpecError if it does not fit) but changes
    nothing in it: `_start_folder` does, once nothing else can fail on the input."""
    csv_path, meta_path = folder / CSV_NAME, folder / META_NAME
    if folder.exists() and not folder.is_dir():
        raise SpecError("command line", "--out", "a folder", f"'{folder}' is a file")
    if not (resume and csv_path.exists()):
        return None
    try:
        old = json.loads(meta_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        old = None
    if not isinstance(old, dict):
        raise SpecError("command line", "--resume", f"a table in {folder} with its {META_NAME}",
                        f"no readable {META_NAME} (run without --resume to start it again)")
    if any(old.get(k) != meta[k] for k in ("spec_sha256", "sweeps", "chain", "columns")):
        raise SpecError("command line", "--resume", f"a table in {folder} made from the "
                        "same spec, sweeps and chain length", "one made from others (run "
                        "without --resume to start it again)")
    found, rows = tables.read_csv(csv_path.read_text(encoding="utf-8"))
    if found != list(header):
        raise SpecError("command line", "--resume", f"{csv_path} with this table's "
                        "columns", "other columns")
    width = len(meta["sweeps"])
    kept: dict[tuple[str, ...], dict[str, str]] = {}
    solved = {status.value for status in Status}  # an error or an edited status: solve again
    for row in rows:
        if row.get("status") in solved:
            kept[tuple(row[c] for c in header[:width])] = row
    return kept


def _start_folder(folder: Path, meta: dict, header, kept: dict | None) -> None:
    """Ready the folder for the rows to be appended: on resume, table.csv again with the kept
    rows only (a cut-short last line dropped, errors left out); for a fresh table, sweep.json
    and a header-only table.csv, and the outputs of an earlier run removed."""
    csv_path, meta_path = folder / CSV_NAME, folder / META_NAME
    if kept is not None:
        write_atomic(csv_path, tables.csv_text(header, list(kept.values())))
        return
    write_atomic(meta_path, json.dumps(meta, indent=1) + "\n")
    write_atomic(csv_path, tables.csv_text(header, []))
    for name in (MARKDOWN_NAME, *PLOT_NAMES):
        (folder / name).unlink(missing_ok=True)  # stale outputs of an earlier run


def _write_outputs(folder, spec, source, axes, header, rows, plots,
                   chain) -> tuple[Path, ...]:
    sweep_columns = tuple(a.column for a in axes)
    write_atomic(folder / CSV_NAME, tables.csv_text(header, rows))
    described = [f"Spec: `{source}` ({spec.kind})."]
    for a in axes:
        described.append(f"Swept: `{a.column}` from {a.values[0]:g} to {a.values[-1]:g} "
                         f"({len(a.values)} values).")
    words = ["pdm-design", "table", source]
    for a in axes:
        words += ["--sweep", f"{a.name}={a.values[0]:g}:{a.values[-1]:g}:{len(a.values)}"]
    if chain != DEFAULT_CHAIN:  # the warm starts, and so a non-unique optimum, follow it
        words += ["--chain", str(chain)]
    described.append(f"Regenerate: `{shlex.join(words)}`.")
    title = f"Design table: {spec.name or Path(source).stem}"
    text = tables.markdown(spec.kind, title, described, sweep_columns, rows)
    files = [folder / CSV_NAME, folder / MARKDOWN_NAME]
    write_atomic(files[-1], text)
    if plots:
        from .plots import sweep_figures

        for name, payload in sweep_figures(spec.kind, axes, rows).items():
            write_atomic(folder / name, payload)
            files.append(folder / name)
    from ..plugin import of

    for name, payload in of(spec).table_extras(spec, axes, plots=plots).items():
        write_atomic(folder / name, payload)  # the scene's own (Scene.table_extras)
        files.append(folder / name)
    return tuple(files)


# --------------------------------------------------------------------------- executing chains

def _warm(row: dict[str, str] | None, free: list[str]) -> dict[str, float] | None:
    if not row or not free or row.get("status") not in WARM_STATUSES:
        return None
    warm = {n: tables.number(row.get(n, "")) for n in free}
    return {n: v for n, v in warm.items() if v is not None} or None


@contextmanager
def _closing(executor):
    """Close the executor after the block: at once (workers stopped mid-point) if the block
    raised (Ctrl-C, a full disk), else once its idle workers have exited."""
    try:
        yield executor
    except BaseException:
        if executor is not None:
            executor.close(at_once=True)
        raise
    if executor is not None:
        executor.close()


def _execute(executor, all_chains, points, done, free, task, record, stop) -> None:
    """Solve every point not in `done`, chain by chain, warm-starting along each chain.
    stop: called after every wait; raises (KeyboardInterrupt) to end the sweep there."""
    position = dict.fromkeys(range(len(all_chains)), 0)  # chain -> index of its next point
    pending: dict[object, tuple[int, int]] = {}

    def submit_next(c: int) -> None:
        members = all_chains[c]
        k = position[c]
        while k < len(members) and points[members[k]].key in done:
            k += 1
        position[c] = k
        if k < len(members):
            before = points[members[k - 1]].key if k else None
            future = executor.submit(task(members[k], _warm(done.get(before), free), before))
            pending[future] = (c, members[k])

    try:
        for c in range(len(all_chains)):
            submit_next(c)
        while pending:
            finished = executor.wait(list(pending))
            stop()  # before recording: a point cut short by Ctrl-C is no row
            for future in finished:
                c, i = pending.pop(future)
                record(i, future.result())
                position[c] += 1
                submit_next(c)
    except BaseException:
        executor.cancel(list(pending))
        raise


def _executor(workers, scheduler, chains_count):
    if scheduler:
        return _DaskExecutor(scheduler)
    workers = default_workers() if workers is None else workers
    if workers < 1:
        raise SpecError("command line", "--workers", "an integer >= 1", str(workers))
    workers = min(workers, chains_count)
    return _SerialExecutor() if workers <= 1 else _ProcessExecutor(workers)


def default_workers() -> int:
    """The machine's cores available to this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


class _SerialExecutor:
    """Solves in this process, one point per wait (the oldest submitted first)."""

    def __init__(self):
        self.tasks: dict[Future, PointTask] = {}

    def submit(self, point_task):
        future: Future = Future()
        self.tasks[future] = point_task
        return future

    def wait(self, futures):
        first = futures[0]
        first.set_result(solve_point(self.tasks.pop(first)))
        return [first]

    def cancel(self, futures):
        pass

    def close(self, *, at_once=False):
        pass


class _ProcessExecutor:
    """Local worker processes: forked (fast start) when this process runs no other thread,
    else started from a fork server (never fork a process whose threads may hold locks).
    The workers ignore Ctrl-C; `wait` returns at least every POLL_SECONDS, so that the sweep
    loop sees a Ctrl-C noted by the `interrupts` guard."""

    def __init__(self, workers: int):
        import multiprocessing
        import threading
        from concurrent.futures import ProcessPoolExecutor

        methods = multiprocessing.get_all_start_methods()
        if "fork" in methods and threading.active_count() == 1:
            context = multiprocessing.get_context("fork")
        elif "forkserver" in methods:
            context = multiprocessing.get_context("forkserver")
            context.set_forkserver_preload(["pdm_design.sweep.run", "pdm_design.api"])
        else:
            context = multiprocessing.get_context("spawn")
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                        initializer=_ignore_interrupts)
        try:
            self.pool.submit(int).result()  # start the workers now, before any progress thread
        except BaseException:
            self.close(at_once=True)
            raise

    def submit(self, point_task):
        return self.pool.submit(solve_point, point_task)

    def wait(self, futures):
        return wait_futures(futures, timeout=POLL_SECONDS, return_when=FIRST_COMPLETED).done

    def cancel(self, futures):
        # left to `close` (shutdown with cancel_futures): a future cancelled here but still
        # held by the pool breaks the pool's manager thread when the workers are terminated
        # (Python 3.11 sets BrokenProcessPool on it: InvalidStateError)
        pass

    def close(self, *, at_once=False):
        """Shut the pool down. After the last point its workers are idle and exit when told
        to; at once (Ctrl-C, an error) they are terminated first, mid-point, as Python 3.14's
        ProcessPoolExecutor.terminate_workers does: the points they were solving would give no
        row anyway, and a solve may take long. Either way every worker has exited on return."""
        if at_once:  # the pool's own list of its workers, as terminate_workers reads it
            _terminate(list((getattr(self.pool, "_processes", None) or {}).values()))
        self.pool.shutdown(wait=True, cancel_futures=True)


def _terminate(processes) -> None:
    """Terminate worker processes (SIGTERM); kill those still running TERMINATE_GRACE seconds
    later. Waits on their sentinels, so as not to reap them under the pool's manager thread."""
    from multiprocessing.connection import wait as wait_ended

    running = {}
    for process in processes:
        with suppress(ValueError):  # a process object already closed
            process.terminate()
            running[process.sentinel] = process
    deadline = time.monotonic() + TERMINATE_GRACE
    while running and (left := deadline - time.monotonic()) > 0:
        for sentinel in wait_ended(list(running), timeout=left):
            del running[sentinel]
    for process in running.values():
        process.kill()


def _ignore_interrupts() -> None:
    """Workers leave Ctrl-C to the main process, which stops the sweep and terminates them
    (the rows already written stay); SIGTERM, which that termination sends, ends a worker as
    by default (a forked worker inherits the main process' guard)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


class _DaskExecutor:
    """An existing Dask distributed cluster, by its scheduler's address."""

    def __init__(self, address: str):
        try:
            import distributed
        except ImportError:  # pragma: no cover - a dependency of the package
            raise SpecError("command line", "--scheduler", "Dask distributed installed "
                            "(pip install 'dask[distributed]')", "it is not") from None
        self.client = _dask_client(distributed, address)
        try:
            self.finished = distributed.as_completed(loop=self.client.loop)
        except BaseException:
            self.close()
            raise

    def submit(self, point_task):
        future = self.client.submit(solve_point, point_task, pure=False)
        self.finished.add(future)
        return future

    def wait(self, futures):
        return [next(self.finished)]

    def cancel(self, futures):
        if futures:
            self.client.cancel(futures)

    def close(self, *, at_once=False):
        self.client.close()


def _dask_client(distributed, address: str):
    """A Dask client connected to the scheduler at `address`, within DASK_CONNECT_TIMEOUT
    seconds (Dask retries a refused connection until then); SpecError naming --scheduler if
    the address is malformed or no scheduler answers there. A client whose start failed is
    closed here, at once: left to the garbage collector, it would be closed at interpreter exit,
    after its IO loop had stopped, wait twice the timeout and print a traceback.

    The start runs in a thread the caller waits for at most a little longer than the timeout:
    a port that accepts a connection and never answers held Dask's own start for minutes, and
    one that answered HTTP made it read a frame length of exabytes (MemoryError)."""
    client = distributed.Client.__new__(distributed.Client)  # a reference, should __init__ fail
    failed: list[BaseException] = []

    def start():
        try:
            client.__init__(address, timeout=DASK_CONNECT_TIMEOUT, set_as_default=False)
        except BaseException as error:  # handed to the caller below
            failed.append(error)

    starting = threading.Thread(target=start, name="dask-connect", daemon=True)
    starting.start()
    starting.join(DASK_CONNECT_TIMEOUT + 2.0)
    if starting.is_alive():  # left to its daemon thread: nothing else of this run waits on it
        failed.append(TimeoutError(f"no scheduler answered in {DASK_CONNECT_TIMEOUT} s"))
    elif failed:
        _dispose(client)
    if failed:
        error = failed[0]
        if isinstance(error, KeyboardInterrupt):
            raise error
        why = ("an answer that is not a Dask scheduler's" if isinstance(error, MemoryError)
               else error)  # Dask read a frame length from it
        raise SpecError("command line", "--scheduler", "the address of a running Dask "
                        "scheduler (e.g. tcp://127.0.0.1:8786) that answers within "
                        f"{DASK_CONNECT_TIMEOUT} s", f"'{address}' ({why})") from None
    return client


def _dispose(client) -> None:
    """Close a Dask client whose start failed and stop its IO loop thread (Client.close leaves
    the loop running when the failed start had already closed the client)."""
    with suppress(Exception):
        client.close(timeout=DASK_CONNECT_TIMEOUT)
    runner = getattr(client, "_loop_runner", None)
    if runner is not None:
        with suppress(Exception):
            runner.stop()
