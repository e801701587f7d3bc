"""The signals that end a session, as exceptions the engine can stop the robot on.

Every signal whose default action ends the process takes the same way out.
SIGINT (Ctrl-C) is Python's :class:`KeyboardInterrupt`; :func:`signals_raise`
makes every other one (:data:`RAISED_SIGNALS`: SIGTERM, SIGHUP, SIGQUIT,
SIGUSR1, SIGUSR2, SIGALRM, SIGPIPE, SIGXCPU, SIGVTALRM, SIGPROF, SIGPWR, the
real-time signals... as this platform has them) raise
:class:`SignalReceived`, a :class:`KeyboardInterrupt` too. So the engine sends
the robot's stop, waits for the robot to report that it stopped, journals,
and the command exits with 128 + the signal number. While the robot is being
stopped, :func:`signals_held` holds further signals back so that none of them
skips the stop; while a journal record is written, :func:`signals_deferred`
holds them until it is whole and counted (a thread signal mask, and odohil's
handlers waiting for the signals another thread takes).

The signals whose default action suspends the process (:data:`MOTION_SIGNALS`:
SIGTSTP, Ctrl-Z; SIGTTIN and SIGTTOU, a background odohil reading or writing
its terminal) would freeze odohil in the middle of a motion while the robot
drives on (the Create 2 has no watchdog, and the guardian sees nothing: odohil
still lives). So while a motion is under way (:func:`motion_signals_raise`,
entered by the engine around each drive) they raise :class:`SignalReceived`
too and end the session like SIGTERM (exit 128 + N, 148 for SIGTSTP; the
session resumes as after any signal). Outside a motion the robot stands still
and they keep their default: Ctrl-Z at a prompt suspends odohil as usual.
SIGSTOP cannot be caught: only a robot's own watchdog covers it (docs/sessions.md).

The list is computed from the platform (:func:`signal.valid_signals`) less
the signals whose default action does not end a process (ignore, stop,
continue), SIGKILL and SIGSTOP (they cannot be caught), and the four a faulting
instruction raises (SIGSEGV, SIGBUS, SIGFPE, SIGILL: a handler that returns
runs the instruction again). Those, and every end no handler sees (kill -9,
the out-of-memory killer, a crash of the interpreter), are covered by the
driver's guardian process instead (odohil/driver/guardian.py, docs/sessions.md).

A signal someone else already handles (a profiler's SIGPROF, a test runner's
SIGALRM) or ignores (``nohup``'s SIGHUP) is left to them; only signals at their
default action are taken over, and SIGPIPE, which Python itself ignores at
start-up (SIGXFSZ, which it ignores too, stays so: see :data:`_PYTHON_IGNORES`).
"""

from __future__ import annotations

import contextlib
import importlib
import signal
import threading
from collections.abc import Callable, Iterable, Iterator
from types import FrameType

_NOT_ENDING = (
    "SIGKILL",
    "SIGSTOP",
    "SIGCHLD",
    "SIGCLD",
    "SIGCONT",
    "SIGTSTP",
    "SIGTTIN",
    "SIGTTOU",
    "SIGURG",
    "SIGWINCH",
    "SIGINFO",
)
"""Signals whose default action does not end a process (ignore, stop, continue),
and the two that cannot be caught (POSIX and BSD names; those the platform has)."""
_FAULTS = ("SIGSEGV", "SIGBUS", "SIGFPE", "SIGILL")
"""Raised by a faulting instruction: a Python handler returns and the instruction
faults again, so they keep their default action (the guardian covers the crash)."""
_PYTHON_IGNORES = (signal.SIGPIPE,)
"""Ignored by Python at start-up, not by whoever started odohil: taken over too.
Python also ignores SIGXFSZ; that one stays ignored: the kernel sends it to a
process whose own write passes its file-size limit, and that write then fails
with EFBIG, an error that takes the stop path already and says more ("the
journal could not be written: File too large") than the signal would."""


def _ending_signals() -> tuple[int, ...]:
    left_out = {
        int(getattr(signal, name)) for name in (*_NOT_ENDING, *_FAULTS) if hasattr(signal, name)
    }
    return tuple(sorted(int(s) for s in signal.valid_signals() if int(s) not in left_out))


ENDING_SIGNALS: tuple[int, ...] = _ending_signals()
"""Every signal on this platform whose default action ends the process and that
a handler can act on, SIGINT included."""
HANDLED_SIGNALS = ENDING_SIGNALS
"""Every signal that ends a session cleanly (held back during the stop)."""
RAISED_SIGNALS = tuple(s for s in ENDING_SIGNALS if s != signal.SIGINT)
"""The signals :func:`signals_raise` turns into :class:`SignalReceived`."""
MOTION_SIGNALS: tuple[int, ...] = tuple(
    int(getattr(signal, name))
    for name in ("SIGTSTP", "SIGTTIN", "SIGTTOU")
    if hasattr(signal, name)
)
"""The catchable signals whose default action suspends the process: they end
the session only during a motion (:func:`motion_signals_raise`)."""
HELD_SIGNALS = (*HANDLED_SIGNALS, *MOTION_SIGNALS)
"""Held back while the robot is stopped and while a journal record is written:
a suspension there would leave the stop or the record half done."""
_HELD_SET = frozenset(HELD_SIGNALS)

_c_signal = importlib.import_module("_signal")
# The C functions under signal.pthread_sigmask, getsignal and signal: the
# wrappers turn each signal of a returned mask (and each handler) into an enum
# member, the 31 real-time signals (and each function) through a ValueError:
# 60 us of a record's 66 us of masking, 50 us for a look at the 52 handlers.
_sigmask: Callable[[int, Iterable[int]], set[int]] = _c_signal.pthread_sigmask
_handler_of: Callable[[int], object] = _c_signal.getsignal
_set_handler: Callable[[int, object], object] = _c_signal.signal

_deferred: list[int] | None = None
"""While :func:`signals_deferred` holds the main thread's signals: the
signals odohil's own handlers took meanwhile, acted on right after; else None."""


def signal_name(signum: int) -> str:
    """A signal's name: ``SIGTERM``; ``SIGRTMIN+3`` for a real-time signal."""
    try:
        return signal.Signals(signum).name
    except ValueError:
        rtmin = getattr(signal, "SIGRTMIN", None)
        if rtmin is not None and signum > rtmin:
            return f"SIGRTMIN+{signum - int(rtmin)}"
        return f"signal {signum}"


class SignalReceived(KeyboardInterrupt):
    """A signal (other than Ctrl-C) asked the process to end.

    Attributes:
        signum: the signal's number.
    """

    def __init__(self, signum: int) -> None:
        super().__init__(f"{signal_name(signum)} received")
        self.signum = int(signum)


def signal_of(exc: BaseException) -> int:
    """The signal an interrupt came from (SIGINT for a plain KeyboardInterrupt)."""
    if isinstance(exc, SignalReceived):
        return exc.signum
    return int(signal.SIGINT)


def _raise(signum: int, frame: FrameType | None) -> None:
    if _deferred is not None:
        _deferred.append(signum)
        return
    raise SignalReceived(signum)


class _Note:
    """A handler that only notes each signal it gets (it never raises)."""

    def __init__(self, received: list[int]) -> None:
        self.received = received

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        self.received.append(signum)


def _ours_to_take(signum: int) -> bool:
    """Whether ``signum`` is at its default action (or ignored by Python's start-up)."""
    handler = signal.getsignal(signum)
    return handler in (signal.SIG_DFL, _raise) or (
        handler == signal.SIG_IGN and signum in _PYTHON_IGNORES
    )


@contextlib.contextmanager
def signals_raise() -> Iterator[None]:
    """Within: every signal of :data:`RAISED_SIGNALS` at its default action (and
    SIGPIPE) raises :class:`SignalReceived` (main thread only; the
    previous handlers come back afterwards)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {
        signum: signal.signal(signum, _raise) for signum in RAISED_SIGNALS if _ours_to_take(signum)
    }
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


@contextlib.contextmanager
def motion_signals_raise() -> Iterator[None]:
    """Within (a motion): every signal of :data:`MOTION_SIGNALS` at its default
    action raises :class:`SignalReceived` instead of suspending odohil while the
    robot drives (main thread only; one someone else handles or ignores is left
    to them; the previous handlers come back afterwards)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {
        signum: signal.signal(signum, _raise)
        for signum in MOTION_SIGNALS
        if signal.getsignal(signum) in (signal.SIG_DFL, _raise)
    }
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


@contextlib.contextmanager
def signals_held() -> Iterator[list[int]]:
    """Within: every handled signal (and Ctrl-Z, :data:`HELD_SIGNALS`) is held
    back and only listed (the list is yielded); the stop and the journal it
    guards are bounded in time, and the exit status stays that of the first
    way out. Ignored signals stay ignored, and so do handlers set outside
    Python."""
    if threading.current_thread() is not threading.main_thread():
        yield []
        return
    received: list[int] = []
    hold = _Note(received)
    previous = {
        signum: signal.signal(signum, hold)
        for signum in HELD_SIGNALS
        if signal.getsignal(signum) not in (signal.SIG_IGN, None)
    }
    try:
        yield received
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _ctrl_c(signum: int, frame: FrameType | None) -> None:
    if _deferred is not None:
        _deferred.append(signum)
        return
    raise KeyboardInterrupt("Ctrl-C")


@contextlib.contextmanager
def ctrl_c_in_words() -> Iterator[None]:
    """Within: Ctrl-C raises a KeyboardInterrupt that says "Ctrl-C", so what the
    engine journals and what the operator reads name the key, not a class
    (main thread only; the previous handler comes back afterwards)."""
    try:
        previous = signal.signal(signal.SIGINT, _ctrl_c)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _defers(signum: int, handler: object) -> bool:
    """Whether ``handler`` waits by itself while a record is written: odohil's
    own (they note the signal), an ignored signal, one set outside Python, or
    the default action of a signal that suspends the process (the write goes on
    when it continues)."""
    if handler in (_raise, _ctrl_c, signal.SIG_IGN, None) or isinstance(handler, _Note):
        return True
    return handler == signal.SIG_DFL and signum in MOTION_SIGNALS


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Within (a journal record being written and counted): every signal of
    :data:`HELD_SIGNALS` waits, and right after it meets the handler it would
    have met (main thread only: Python runs no handler in another thread).

    The signals are blocked in this thread (:func:`signal.pthread_sigmask`):
    the kernel keeps one sent to the thread (``raise_signal``), or to the
    process while no other thread takes it, until the block ends. But another
    thread may take a signal sent to the process (numpy's BLAS threads, in
    every odohil process, or the motion-capture reader), and Python then runs
    its handler in the main thread at once, block or not. So odohil's own
    handlers (:func:`signals_raise`, :func:`ctrl_c_in_words`,
    :func:`signals_held`) only note a signal while one is deferred, and only
    the other handlers (Python's Ctrl-C in the wizard, someone else's, a
    default action that ends the process) are swapped for the duration: in a
    session none or one, where every record swapped 52 before."""
    global _deferred
    if threading.current_thread() is not threading.main_thread() or _deferred is not None:
        yield
        return
    deferred: list[int] = []
    note = _Note(deferred)
    before = _sigmask(signal.SIG_BLOCK, ())  # the mask as it is (nothing changed yet)
    swapped: dict[int, object] = {}
    try:
        _deferred = deferred  # from here odohil's handlers only note
        _sigmask(signal.SIG_BLOCK, _HELD_SET)
        for signum in HELD_SIGNALS:
            handler = _handler_of(signum)
            if not _defers(signum, handler):
                swapped[signum] = handler  # kept before the swap: restored whatever comes
                _set_handler(signum, note)
        yield
    finally:
        # Unblock first, while every handler only notes: what was held is
        # noted now; then the handlers come back, and no exit leaves the
        # thread blocked or odohil's handlers noting.
        try:
            _sigmask(signal.SIG_SETMASK, before)
            for signum, handler in swapped.items():
                _set_handler(signum, handler)
        finally:
            _deferred = None
        for signum in deferred:
            handler = _handler_of(signum)
            if callable(handler):
                handler(signum, None)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(signum)
