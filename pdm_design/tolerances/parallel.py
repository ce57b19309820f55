"""The event simulator over many builds of a yield run: in this process, in local worker
processes (default: one per core), or on a Dask distributed cluster.

A build's outcome depends on its seed, index and tolerances only (tolerances.draw draws it
alone, reproducibly), so the builds are cut into chunks in their order, the chunks run anywhere,
and the answers are put back in that order: the same outcomes, and the same JSON, whatever
the number of workers or the scheduler.

The run's fixed part (scene, design, the tolerances of every scale, seed, stages, accuracy) is
sent once to each worker (a local pool's initializer; scattered to a Dask cluster's workers);
a chunk travels as a tuple of (scale, build index) pairs and comes back as a list of
(stages passed, failure name) pairs. The builds of a chunk are drawn together (_drawn).
"""

from __future__ import annotations

from dataclasses import dataclass

CHUNKS_PER_WORKER = 8  # chunks per worker: small enough to even out slow builds at the end
MAX_CHUNK = 32  # builds in one chunk, at most
MIN_PER_WORKER = 2  # builds per worker below which they run in this process


@dataclass(frozen=True)
class BuildRun:
    """What every build of a yield run shares (plain data: it travels by pickle)."""

    scene: object
    design: object
    tolerances: dict  # scale -> the Tolerances drawn at that scale
    seed: int
    stages: int
    accuracy: object
    allow_skips: bool = False


def simulate_builds(run: BuildRun, tasks, *, workers=None, scheduler=None,
                    progress=None) -> list[tuple[int, str]]:
    """(stages passed, failure name or "") of every (scale, index) in `tasks`, in their order
    (start_builds, then its answers)."""
    return start_builds(run, tasks, workers=workers, scheduler=scheduler,
                        progress=progress).answers()


def start_builds(run: BuildRun, tasks, *, workers=None, scheduler=None, progress=None):
    """The builds of `tasks` ((scale, index) pairs) started on the workers: a Started whose
    answers() waits for them (this process is free meanwhile; with one worker they run in
    answers()). workers: local processes (None: the machine's cores, or 1 in a process that is
    itself a worker; 1: this process); scheduler: the address of a Dask scheduler to run on
    instead; progress: called once a build."""
    tasks = list(tasks)
    if scheduler:
        return _on_dask(run, tasks, scheduler, progress)
    workers = local_workers(workers)
    if workers == 1 or len(tasks) < MIN_PER_WORKER * workers:
        return Started(lambda: [_chunk(run, tasks, progress)], progress=None)
    return _on_pool(run, tasks, workers, progress)


def local_workers(workers=None) -> int:
    """The local worker processes to run on: `workers`, or by default one per core (1 in a
    process that is itself a worker: a table's row, a Dask worker, whose siblings have the
    other cores)."""
    if workers is None:
        import multiprocessing

        from ..sweep.run import default_workers

        workers = default_workers() if multiprocessing.parent_process() is None else 1
    workers = int(workers)
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    return workers


def map_chunks(fn, tasks: list, workers: int) -> list:
    """[fn(task) for task in tasks], on `workers` local processes (a pool of the context
    _context picks) when more than one; in order either way."""
    if workers <= 1 or len(tasks) < 2:
        return [fn(task) for task in tasks]
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=min(workers, len(tasks)),
                             mp_context=_context()) as pool:
        return list(pool.map(fn, tasks))


_INHERITED: dict = {}  # forked_map's callables, by key: a forked child inherits them


def forked_map(fn, parts: list, workers: int) -> list:
    """[fn(part) for part in parts], on `workers` forked processes where this process can
    fork (no other thread), else here. fn may be any callable, a closure over objects that do
    not pickle (CasADi Functions with Python callbacks): each child inherits it; `parts` and
    the results must pickle."""
    if workers <= 1 or len(parts) < 2 or _context().get_start_method() != "fork":
        return [fn(part) for part in parts]
    key = id(fn)
    _INHERITED[key] = fn
    try:
        return map_chunks(_inherited, [(key, part) for part in parts], workers)
    finally:
        _INHERITED.pop(key, None)


def _inherited(task):
    key, part = task
    return _INHERITED[key](part)


def _context():
    """A forked pool (fast start, the modules already imported) when this process runs no
    other thread, else one started from a fork server (or spawned)."""
    import multiprocessing
    import threading

    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        return multiprocessing.get_context("forkserver")
    return multiprocessing.get_context("spawn")


class Started:
    """Builds under way: answers() gathers them chunk by chunk, in order, and closes what ran
    them; close() ends them unanswered (an error meanwhile)."""

    def __init__(self, chunks, progress=None, close=None):
        self._chunks, self._progress, self._close = chunks, progress, close

    def answers(self) -> list[tuple[int, str]]:
        out: list[tuple[int, str]] = []
        try:
            for answers in self._chunks():
                out.extend(answers)
                if self._progress is not None:
                    for _ in answers:
                        self._progress()
        finally:
            self.close()
        return out

    def close(self) -> None:
        if self._close is not None:
            self._close()
            self._close = None


def chunks_of(tasks: list, workers: int) -> list[tuple]:
    """`tasks` cut in order into about CHUNKS_PER_WORKER chunks a worker (MAX_CHUNK at most)."""
    size = max(1, min(MAX_CHUNK, -(-len(tasks) // (CHUNKS_PER_WORKER * workers))))
    return [tuple(tasks[i:i + size]) for i in range(0, len(tasks), size)]


def _chunk(run: BuildRun, tasks, progress=None) -> list[tuple[int, str]]:
    """The builds of `tasks` one by one, their deviations drawn together (_drawn)."""
    from .yield_ import simulated

    out = []
    for (scale, index), deviations in zip(tasks, _drawn(run, tasks)):
        out.append(simulated(run.scene, run.design, run.tolerances[scale], run.seed, index,
                             run.stages, run.accuracy, run.allow_skips, deviations))
        if progress is not None:
            progress()
    return out


def _drawn(run: BuildRun, tasks, span: int = 4 * MAX_CHUNK):
    """Each task's deviations as yield_.one_build draws them (1-row arrays): the builds of one
    scale drawn together from the lowest index to the highest, at most `span` at once, and
    the task's row taken (a build's numbers sit at a fixed place in each stream: the same)."""
    from .draw import draw

    block, first = {}, None
    for scale, index in tasks:
        if first is None or (scale, index) not in block:
            last = max((i for s, i in tasks if s == scale and index <= i < index + span),
                       default=index)
            first, count = index, last - index + 1
            drawn = draw(run.tolerances[scale], count, run.stages, run.seed, scene=run.scene,
                         start=first)
            block = {(scale, first + n): n for n in range(count)}
        n = block[(scale, index)]
        yield {k: v[n:n + 1] for k, v in drawn.items()}


# ------------------------------------------------------------------ local worker processes

_RUN: BuildRun | None = None  # a worker process' run (set by its initializer)


def _start_worker(run: BuildRun) -> None:
    global _RUN
    import signal

    _RUN = run
    # Ctrl-C is the main process' to handle: it shuts the pool down
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _worker_chunk(tasks) -> list[tuple[int, str]]:
    return _chunk(_RUN, tasks)


def _on_pool(run, tasks, workers, progress):
    """A local process pool (_context)."""
    from concurrent.futures import ProcessPoolExecutor

    context = _context()
    if context.get_start_method() == "fork":  # the integrator's tableaux, imported once here
        from ..sim.rk import tableau

        tableau("DOP853"), tableau("RK45")
    chunks = chunks_of(tasks, workers)
    pool = ProcessPoolExecutor(max_workers=min(workers, len(chunks)), mp_context=context,
                               initializer=_start_worker, initargs=(run,))
    futures = [pool.submit(_worker_chunk, chunk) for chunk in chunks]
    return Started(lambda: (f.result() for f in futures), progress,
                   lambda: pool.shutdown(wait=True, cancel_futures=True))


# ------------------------------------------------------------------ a Dask cluster

def _dask_chunk(run: BuildRun, tasks) -> list[tuple[int, str]]:
    return _chunk(run, tasks)


def _on_dask(run, tasks, address, progress):
    """An existing Dask distributed cluster, by its scheduler's address (the run scattered to
    its workers once; chunks gathered in order)."""
    try:
        import distributed
    except ImportError:  # pragma: no cover - a dependency of the package
        from ..errors import SpecError

        raise SpecError("command line", "--scheduler", "Dask distributed installed "
                        "(pip install 'dask[distributed]')", "it is not") from None
    from ..sweep.run import _dask_client

    client = _dask_client(distributed, address)
    try:
        workers = max(1, sum(client.nthreads().values()))  # threads: chunks run at once
        shared = client.scatter(run, broadcast=True)
        futures = [client.submit(_dask_chunk, shared, chunk, pure=False)
                   for chunk in chunks_of(tasks, workers)]
    except BaseException:
        client.close()
        raise
    return Started(lambda: (f.result() for f in futures), progress, client.close)
