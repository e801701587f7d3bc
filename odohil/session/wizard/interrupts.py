"""Ctrl-C beside a moving robot: the interactive session's SIGINT policy.

During a motion the first Ctrl-C is raised at the next encoder sample
(:meth:`Interrupts.check`, so the driver stops the robot at a point where it
can); elsewhere at once. A second Ctrl-C sends one stop to :attr:`Interrupts.robot`
(waiting at most :data:`SECOND_CTRL_C_STOP_S` for the confirmation) and ends
the process at once with the status the caller gave for a confirmed or an
unconfirmed stop. What it says goes through ``say``, which must be safe in a
signal handler (e.g. ``os.write`` to the terminal). :func:`wait_readable`
keeps a prompt's read from holding a signal back.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
from collections.abc import Callable, Iterator
from types import FrameType
from typing import TextIO

from odohil.errors import StopUnconfirmedError
from odohil.session.robots.protocol import Robot

__all__ = [
    "Interrupts",
    "wait_readable",
]

SECOND_CTRL_C_STOP_S = 0.5
"""How long a second Ctrl-C waits for the robot to confirm its stop, s."""


class Interrupts:
    """The SIGINT policy (see the module docstring).

    Args:
        say: writes one message (called from the signal handler).
        exit_stopped, exit_unconfirmed: the process's exit status after a
            second Ctrl-C whose stop the robot confirmed, or did not.
        unconfirmed: the warning said when the stop is not confirmed.
    """

    def __init__(
        self,
        say: Callable[[str], object],
        exit_stopped: int,
        exit_unconfirmed: int,
        unconfirmed: str,
    ) -> None:
        self.say = say
        self.exits = (exit_stopped, exit_unconfirmed)
        self.unconfirmed = unconfirmed
        self.count = 0
        self.in_motion = False
        self.pending = False
        self.robot: Robot | None = None

    @classmethod
    def on_stderr(cls, exit_stopped: int, exit_unconfirmed: int, unconfirmed: str) -> Interrupts:
        """The policy saying what it does on standard error, written straight
        to its file descriptor (safe in a signal handler)."""
        return cls(
            lambda text: os.write(2, text.encode()), exit_stopped, exit_unconfirmed, unconfirmed
        )

    @contextlib.contextmanager
    def installed(self) -> Iterator[None]:
        """Take over SIGINT within; on the way out the handler it found is
        back (an in-process caller, a test, is not left with this one)."""
        previous = signal.signal(signal.SIGINT, self._handler)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, previous)

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.count += 1
        if self.count >= 2:
            self.say("\nsecond Ctrl-C: one stop, then exiting at once\n")
            try:
                if self.robot is None:
                    raise StopUnconfirmedError("no robot to stop")
                self.robot.stop_and_confirm(SECOND_CTRL_C_STOP_S)
            except BaseException:
                self.say(f"WARNING: {self.unconfirmed}\n")
                os._exit(self.exits[1])
            self.say("robot stopped (it reported standing still)\n")
            os._exit(self.exits[0])
        if self.in_motion:
            self.pending = True
            self.say("\nCtrl-C: stopping the robot...\n")
            return
        raise KeyboardInterrupt("Ctrl-C")

    def check(self) -> None:
        """Raise the Ctrl-C deferred during a motion."""
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt("Ctrl-C")


def wait_readable(stream: TextIO, slice_s: float = 0.1) -> None:
    """Wait until ``stream`` has a line, waking every ``slice_s`` seconds so that
    a signal the kernel handed to another thread (numpy's) is acted on at once:
    a read blocked in the main thread would not see it until the next key.
    Only on a terminal, which hands over one line per read (a pipe's lines may
    already sit in the stream's buffer)."""
    try:
        if not stream.isatty():
            return
        fd = stream.fileno()
    except (AttributeError, OSError, ValueError):
        return
    while not select.select([fd], [], [], slice_s)[0]:
        pass
