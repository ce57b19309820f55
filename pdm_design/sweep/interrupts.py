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


@contextmanager
def interrupt_guard() -> Iterator[InterruptGuard]:
    """Install an `InterruptGuard` as the SIGINT handler for the block; the previous handler
    is back when the block ends. Nothing is installed where Ctrl-C is ignored (SIGINT set to
    SIG_IGN, e.g. a background job), handled outside Python, or cannot reach this code (not the
    main thread): there the guard only ever answers `check` with nothing."""
    guard = InterruptGuard()
    previous = signal.getsignal(signal.SIGINT)
    installed = False
    if previous not in (signal.SIG_IGN, None):
        try:
            signal.signal(signal.SIGINT, guard.handle)
            installed = True
        except ValueError:  # not the main thread of the main interpreter
            pass
    try:
        yield guard
    finally:
        if installed:
            signal.signal(signal.SIGINT, previous)
