"""The signals that end a session, as exceptions the engine can stop the robot on.

SIGINT (Ctrl-C) is Python's :class:`KeyboardInterrupt`. :func:`signals_raise`
makes SIGTERM, SIGHUP (a dropped SSH session) and SIGQUIT raise
:class:`SignalReceived`, a :class:`KeyboardInterrupt` too, so every way out
takes the same path: the engine sends ``st``, waits for the robot to report
that it stopped, journals, and the command exits with 128 + the signal number.
While the robot is being stopped, :func:`signals_held` holds further signals
back so that none of them skips the stop.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType

HANDLED_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT)
"""Every signal that ends a session cleanly."""
RAISED_SIGNALS = (signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT)
"""The signals :func:`signals_raise` turns into :class:`SignalReceived`."""


class SignalReceived(KeyboardInterrupt):
    """A signal (other than Ctrl-C) asked the process to end.

    Attributes:
        signum: the signal's number.
    """

    def __init__(self, signum: int) -> None:
        super().__init__(f"{signal.Signals(signum).name} received")
        self.signum = int(signum)


def signal_of(exc: BaseException) -> int:
    """The signal an interrupt came from (SIGINT for a plain KeyboardInterrupt)."""
    if isinstance(exc, SignalReceived):
        return exc.signum
    return int(signal.SIGINT)


def _raise(signum: int, frame: FrameType | None) -> None:
    raise SignalReceived(signum)


@contextlib.contextmanager
def signals_raise() -> Iterator[None]:
    """Within: SIGTERM, SIGHUP and SIGQUIT raise :class:`SignalReceived`
    (main thread only; the previous handlers come back afterwards)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.signal(signum, _raise) for signum in RAISED_SIGNALS}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


@contextlib.contextmanager
def signals_held() -> Iterator[list[int]]:
    """Within: every handled signal is held back and only listed (the list is
    yielded); the stop and the journal it guards are bounded in time, and the
    exit status stays that of the first way out."""
    if threading.current_thread() is not threading.main_thread():
        yield []
        return
    received: list[int] = []

    def hold(signum: int, frame: FrameType | None) -> None:
        received.append(signum)

    previous = {signum: signal.signal(signum, hold) for signum in HANDLED_SIGNALS}
    try:
        yield received
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
