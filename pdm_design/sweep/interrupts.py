"""Ctrl-C during a sweep: the main process alone decides, and only where it is safe to stop.

A terminal's Ctrl-C sends SIGINT to the whole process group: the main process and its local
worker processes. The workers ignore it (`run._ignore_interrupts`, and forked ones inherit the
handler below from their first instant); the main process stops the sweep, terminates the
workers and shuts the pool down, and the rows already written stay.

Why the main process does not simply let KeyboardInterrupt fly while the pool runs: Python
raises it wherever the main thread happens to be, and inside the pool's own start-up or
shutdown it leaves the pool half-made. On Python 3.11 a KeyboardInterrupt that lands in
`Thread.join` (ProcessPoolExecutor.shutdown joins the pool's manager thread) marks that thread
finished while it still runs (CPython issue gh-90882): the interpreter then skips it at exit,
closes the queue the workers wait on and joins the idle workers for ever. That was the hang of
a second Ctrl-C. So while local workers run, a Ctrl-C only notes the request
(`InterruptGuard.check` raises KeyboardInterrupt where the sweep loop asks for it, a fraction
of a second later), and once the sweep is stopping every further Ctrl-C is swallowed until the
pool is shut down: stopping takes well under a second, and a second press cannot break it.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager


class InterruptGuard:
    """The SIGINT handler of a running sweep and what it has seen.

    at_once: raise KeyboardInterrupt from the handler, wherever the main thread is (for work
    done in this process, which has nothing to leave half-made, and for a Dask client); else
    only note the press for `check`. Either way a press after the first changes nothing."""

    def __init__(self) -> None:
        self.pressed = False
        self.at_once = False

    def handle(self, signum, frame) -> None:
        if self.pressed:
            return  # the sweep is already stopping
        self.pressed = True
        if self.at_once:
            raise KeyboardInterrupt

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed (also when a library caught the one
        raised at once and carried on)."""
        if self.pressed:
            raise KeyboardInterrupt


# Ctrl-C, and the SIGTERM a CI job's timeout or `kill` sends: without a handler SIGTERM ended
# the main process at once and left its local workers running, re-parented to init.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextmanager
def interrupt_guard() -> Iterator[InterruptGuard]:
    """Install an `InterruptGuard` as the SIGINT and SIGTERM handler for the block; the
    previous handlers are back when the block ends. Nothing is installed for a signal that is
    ignored (SIG_IGN, e.g. Ctrl-C for a background job) or handled outside Python, nor where no
    handler can reach this code (not the main thread): there the guard only ever answers `check`
    with nothing."""
    guard = InterruptGuard()
    installed = {}
    for signum in STOP_SIGNALS:
        previous = signal.getsignal(signum)
        if previous in (signal.SIG_IGN, None):
            continue
        try:
            signal.signal(signum, guard.handle)
            installed[signum] = previous
        except ValueError:  # not the main thread of the main interpreter
            break
    try:
        yield guard
    finally:
        for signum, previous in installed.items():
            signal.signal(signum, previous)
