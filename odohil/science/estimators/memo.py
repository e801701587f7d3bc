"""A small, thread-safe memo of estimates by everything they read.

A process often estimates one set of trials again: the test suite's commands
in one process, a library caller's report and export, ``validate`` and the
wizard re-reading a calibration. An estimate is a pure function of its trials
and arguments, so the last few results are kept by a hashable key of them
(arrays by their bytes) and given back unchanged.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

Value = TypeVar("Value")


class ResultMemo(Generic[Value]):
    """The last ``size`` results by key (least recently used dropped first).

    Args:
        size: how many results are kept (positive).
    """

    def __init__(self, size: int) -> None:
        if size < 1:
            raise ValueError(f"size must be positive, got {size!r}")
        self.size = size
        self._kept: OrderedDict[Hashable, Value] = OrderedDict()
        self._lock = threading.Lock()  # a live estimate may run beside the operator's dialogue

    def __len__(self) -> int:
        return len(self._kept)

    def get(self, key: Hashable, compute: Callable[[], Value]) -> Value:
        """The result kept for ``key``, else ``compute()``'s, kept."""
        with self._lock:
            kept = self._kept.get(key)
            if kept is not None:
                self._kept.move_to_end(key)
                return kept
        value = compute()
        with self._lock:
            self._kept[key] = value
            while len(self._kept) > self.size:
                self._kept.popitem(last=False)
        return value
