"""A progress bar for long runs (sweeps, Monte-Carlo verification): rich on stderr, shown only
when stderr is a terminal, so logs, pipes and CI output stay clean."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager


def progress_enabled(stream=None) -> bool:
    """Whether a progress bar would be drawn: only on an interactive terminal."""
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # closed or replaced streams
        return False


@contextmanager
def progress_bar(total: int, description: str, *, enabled: bool | None = None,
                 completed: int = 0) -> Iterator[Callable[[int], None]]:
    """Context giving `advance(n=1)`; draws a bar of `total` steps on stderr when enabled
    (default: when stderr is a terminal), and does nothing otherwise."""
    if enabled is None:
        enabled = progress_enabled()
    if not enabled:
        yield lambda n=1: None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
               TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True), transient=False) as bar:
        task = bar.add_task(description, total=total, completed=completed)
        yield lambda n=1: bar.advance(task, n)
