"""A bounded cache: the built NLPs and solvers of the specs used last.

Each optimised spec builds its NLP, its IPOPT solvers (one per start count, the tie-break's) and
their derivatives: about 7 MB. Kept for ever, a table's worker held every point's (1.5 GB at 200
points, results/bench_scale.md), and a table of 10 000 points would not fit. A point, a warm
start or a re-solve of one spec reuses them at once, so keeping the last few is enough.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

ENTRIES = 16


class Bounded:
    """A thread-safe mapping that keeps the `size` entries stored or read last."""

    def __init__(self, size: int = ENTRIES):
        self.size = size
        self._items: OrderedDict = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key, default=None):
        with self._lock:
            if key not in self._items:
                return default
            self._items.move_to_end(key)
            return self._items[key]

    def __getitem__(self, key):
        with self._lock:
            self._items.move_to_end(key)
            return self._items[key]

    def __setitem__(self, key, value) -> None:
        with self._lock:
            self._items[key] = value
            self._items.move_to_end(key)
            while len(self._items) > self.size:
                self._items.popitem(last=False)

    def __contains__(self, key) -> bool:
        with self._lock:
            return key in self._items

    def __len__(self) -> int:
        with self._lock:
            return len(self._items)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
