"""Progress of the long stages of reading a recording and fitting it (issue 30).

The session calls a :class:`Progress` with a stage's name and a count that
rises from 0 to the stage's total (bytes read, trials cut, fits done); a call
with ``done == total`` ends the stage, also when the stage fails (the callers
end it in a ``finally``). :func:`stage` is that call pattern.

:class:`TerminalBar` is the one the command line passes
(odohil/cli/recording_options.py): a rich progress bar on stderr, shown only
when stderr is a terminal and a stage has run for 2 s, hidden when it ends;
never on stdout (``--json``'s document stays clean). It lives here, not in
odohil/cli, because the command line's line budget (2,400) is spent.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Protocol, TextIO

from rich.console import Console
from rich.progress import BarColumn, TaskID, TextColumn, TimeElapsedColumn
from rich.progress import Progress as RichProgress

SHOW_AFTER_S = 2.0
"""A stage shorter than this (s) shows no bar."""


class Progress(Protocol):
    """Told how far a stage has gone."""

    def __call__(self, stage: str, done: int, total: int) -> None:
        """``done`` of ``total`` units (bytes, trials, fits) of ``stage``;
        ``done == total`` ends it."""


@contextmanager
def stage(progress: Progress | None, name: str, total: int = 1) -> Iterator[Tell]:
    """A stage of ``total`` units told to ``progress`` (None: to nobody): 0
    done at the start; the body tells how far it is with the :data:`Tell` it
    gets (a total it learns replaces ``total``); all done at the end, also on
    an error."""
    latest = [total]

    def tell(done: int, of: int) -> None:
        latest[0] = of
        if progress is not None:
            progress(name, min(done, of - 1), of)

    if progress is None:
        yield tell
        return
    progress(name, 0, total)
    try:
        yield tell
    finally:
        progress(name, latest[0], latest[0])


Tell = Callable[[int, int], None]
"""(done, total) of the stage :func:`stage` opened; done stays below total."""


class TerminalBar:
    """A :class:`Progress` drawn as a rich progress bar on ``stream``
    (default stderr) when it is a terminal and a stage has run
    ``after_s`` s; a no-op otherwise.

    Args:
        stream: where to draw (stderr when None).
        after_s: how long a stage runs before its bar shows, s.
    """

    def __init__(self, stream: TextIO | None = None, after_s: float = SHOW_AFTER_S) -> None:
        self._stream = stream if stream is not None else sys.stderr
        self._after_s = after_s
        self._lock = threading.Lock()
        self._bar: RichProgress | None = None
        self._task: TaskID | None = None
        self._timer: threading.Timer | None = None
        self._stage = ""
        self._counts = (0, 1)

    @property
    def enabled(self) -> bool:
        """Whether the stream is a terminal (else nothing is ever drawn)."""
        isatty = getattr(self._stream, "isatty", None)
        return bool(isatty is not None and isatty())

    @property
    def showing(self) -> bool:
        """Whether a bar is on the terminal now."""
        return self._bar is not None

    def __call__(self, stage: str, done: int, total: int) -> None:
        """See :class:`Progress`."""
        if not self.enabled:
            return
        with self._lock:
            if done >= total:
                self._end()
                return
            if stage != self._stage:
                self._end()
                self._stage = stage
                self._timer = threading.Timer(self._after_s, self._show)
                self._timer.daemon = True
                self._timer.start()
            self._counts = (done, total)
            self._update()

    def _show(self) -> None:
        with self._lock:
            if not self._stage or self._bar is not None:
                return
            bar = RichProgress(
                TextColumn("{task.description}"),
                BarColumn(),
                TextColumn("{task.percentage:>3.0f} %"),
                TimeElapsedColumn(),
                console=Console(file=self._stream),
                transient=True,
                redirect_stdout=False,
                redirect_stderr=False,
            )
            self._task = bar.add_task(self._stage, total=self._counts[1])
            self._bar = bar
            bar.start()
            self._update()

    def _update(self) -> None:
        if self._bar is not None and self._task is not None:
            self._bar.update(self._task, completed=self._counts[0], total=self._counts[1])

    def _end(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._bar is not None:
            self._bar.stop()
        self._bar, self._task, self._stage = None, None, ""
