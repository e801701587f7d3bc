"""The guardian: a stop for the ends the driving process cannot catch.

kill -9, the kernel's out-of-memory killer and a crash of the interpreter end
odohil without running any of its code, so no handler can stop the robot.
:func:`start_guardian` starts a small process beside it
(``python -m odohil.driver.guardian``) that holds

- a duplicate of the robot's open line (the port's file descriptor,
  inherited: the same open device, pty or socket, its line settings untouched,
  nothing reopened), and
- the read end of a pipe whose only write end odohil holds.

It reads the pipe and nothing else: while odohil lives it sends no byte on the
line. :func:`start_guardian` returns only once the guardian says it is ready
(:data:`READY_WORD` on its stdout, its terminal signals ignored, about to read
the pipe): a guardian still starting would send the stop of a process killed
at once late, into the next session's motion on the same line, and one that
cannot start at all is found before anything moves. When the pipe closes,
either odohil said ``end`` first (:meth:`Guardian.release`: a clean close, the
backend has stopped the robot itself) and the guardian exits without a byte;
or it did not, which means the driving process is gone (the kernel closes
every descriptor of a dead process, however it died), and the guardian writes
the robot's stop bytes (the backend declares them, from its protocol layer) on
the line, waits for them to leave, says so on stderr and exits. It never
outlives the session: it ends when the pipe closes, one way or the other. It
runs in a session of its own, so a Ctrl-C or hang-up of the terminal reaches
odohil, not it.

What it cannot cover: a line without a file descriptor (the in-process fakes
``fakerobot://`` and ``fakecreate2://``, which die with the process, and
``rfc2217://``, whose telnet framing it does not speak), a cut cable, a
powered-off or frozen computer, and the time a crash spends writing a core
dump before the kernel closes the dead process's descriptors.
"""

from __future__ import annotations

import contextlib
import io
import os
import select
import signal
import subprocess
import sys
import termios
import time

from odohil.errors import SafetyError

END_WORD = b"end"
"""What odohil writes on the pipe before closing it cleanly."""
RELEASE_TIMEOUT_S = 1.0
"""How long :meth:`Guardian.release` waits for the guardian to exit, s."""
GUARDIAN_DEADLINE_S = 2
"""The guardian's own bound on sending the stop (a line that never drains), s."""
READY_WORD = b"ready"
"""What the guardian writes on its stdout once it waits on the pipe."""
READY_TIMEOUT_S = 10.0
"""How long :func:`start_guardian` waits for :data:`READY_WORD`, s (an
interpreter's start on a loaded machine takes a second or two)."""


class Guardian:
    """A running guardian process (module docstring).

    Args:
        process: the guardian process.
        pipe_fd: the write end of its pipe (held only by this process).
    """

    def __init__(self, process: subprocess.Popen[bytes], pipe_fd: int) -> None:
        self.process = process
        self._pipe_fd: int | None = pipe_fd

    @property
    def pid(self) -> int:
        """The guardian's process id."""
        return self.process.pid

    @property
    def released(self) -> bool:
        """Whether :meth:`release` has run."""
        return self._pipe_fd is None

    def release(self, timeout_s: float = RELEASE_TIMEOUT_S) -> None:
        """The session ends cleanly: say ``end``, close the pipe, wait (at most
        ``timeout_s``) for the guardian to exit, sending nothing. Idempotent."""
        fd = self._pipe_fd
        if fd is None:
            return
        self._pipe_fd = None
        try:
            with contextlib.suppress(OSError):
                os.write(fd, END_WORD)
        finally:
            os.close(fd)
        try:
            self.process.wait(timeout_s)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


def line_fd(port: object) -> int | None:
    """The file descriptor of an open pyserial port: a device or pty
    (``serialposix``) or ``socket://``; None for a port that has none (the
    fakes' in-process URL handlers, ``loop://``) or whose bytes are framed
    (``rfc2217://``)."""
    if type(port).__module__.endswith("protocol_rfc2217"):
        return None
    fileno = getattr(port, "fileno", None)
    if fileno is None:
        return None
    try:
        fd = fileno()
    except (OSError, ValueError, io.UnsupportedOperation, AttributeError):
        return None
    return fd if isinstance(fd, int) and fd >= 0 else None


def start_guardian(port: object, stop_bytes: bytes) -> Guardian | None:
    """Start a guardian that sends ``stop_bytes`` on ``port`` if this process
    dies without :meth:`Guardian.release`; None when the port has no file
    descriptor to share (see :func:`line_fd`).

    Raises:
        SafetyError: the guardian process could not be started, or did not
            say it was ready within :data:`READY_TIMEOUT_S`.
    """
    fd = line_fd(port)
    if fd is None or not stop_bytes:
        return None
    read_end, write_end = os.pipe()
    try:
        process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "odohil.driver.guardian",
                str(fd),
                str(read_end),
                stop_bytes.hex(),
                str(os.getpid()),
            ],
            pass_fds=(fd, read_end),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            start_new_session=True,
        )
    except BaseException as exc:
        with contextlib.suppress(OSError):  # a guardian already started sends nothing
            os.write(write_end, END_WORD)
        os.close(write_end)
        if isinstance(exc, OSError):
            raise SafetyError(f"cannot start the guardian process: {exc}; nothing moved") from exc
        raise
    finally:
        os.close(read_end)
    guardian = Guardian(process, write_end)
    try:
        _wait_ready(process)
    except BaseException:
        # ``end``, then its exit awaited (killed after RELEASE_TIMEOUT_S): a
        # guardian that did start sends nothing
        guardian.release()
        raise
    return guardian


def _wait_ready(process: subprocess.Popen[bytes]) -> None:
    """Until the guardian writes :data:`READY_WORD` (its stdout then closed).

    Raises:
        SafetyError: it ended or stayed silent for :data:`READY_TIMEOUT_S`.
    """
    assert process.stdout is not None
    fd = process.stdout.fileno()
    said = b""
    deadline = time.monotonic() + READY_TIMEOUT_S
    try:
        while len(said) < len(READY_WORD):
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise SafetyError(
                    f"the guardian process did not say it was ready within "
                    f"{READY_TIMEOUT_S:g} s; nothing moved"
                )
            chunk = os.read(fd, len(READY_WORD) - len(said))
            if not chunk:
                raise SafetyError(
                    f"the guardian process ended before it was ready (exit "
                    f"{process.poll()}); nothing moved"
                )
            said += chunk
    finally:
        process.stdout.close()
    if said != READY_WORD:
        raise SafetyError(f"the guardian process said {said!r}, not ready; nothing moved")


# -- the guardian process ----------------------------------------------------------


def _send(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        try:
            view = view[os.write(fd, view) :]
        except BlockingIOError:  # the port's descriptor is non-blocking: wait for room
            select.select([], [fd], [], GUARDIAN_DEADLINE_S)
    with contextlib.suppress(OSError, termios.error):
        if os.isatty(fd):
            termios.tcdrain(fd)


def guard(line: int, pipe: int, stop_bytes: bytes) -> bool:
    """Wait until ``pipe`` closes; send ``stop_bytes`` on ``line`` unless
    :data:`END_WORD` came first. Whether it sent them."""
    said = b""
    while chunk := os.read(pipe, 64):
        said = (said + chunk)[-len(END_WORD) :]
    if said == END_WORD:
        return False
    signal.alarm(GUARDIAN_DEADLINE_S)  # a line that never drains must not keep us
    _send(line, stop_bytes)
    return True


def main(argv: list[str]) -> int:
    """``python -m odohil.driver.guardian LINE_FD PIPE_FD STOP_HEX PID``."""
    line, pipe, stop_hex, owner = argv
    for name in ("SIGINT", "SIGHUP", "SIGQUIT", "SIGTSTP"):
        signal.signal(getattr(signal, name), signal.SIG_IGN)
    # SIGPIPE: the owner may be gone before it reads the word (its end closed)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    with contextlib.suppress(OSError):
        os.write(1, READY_WORD)
    os.close(1)
    started = time.monotonic()
    try:
        sent = guard(int(line), int(pipe), bytes.fromhex(stop_hex))
    except OSError as exc:
        sys.stderr.write(f"odohil guardian: could not send the robot's stop: {exc}\n")
        return 1
    if sent:
        sys.stderr.write(
            f"odohil guardian: odohil (pid {owner}) ended without closing the robot's line "
            f"after {time.monotonic() - started:.1f} s: the robot's stop was sent\n"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
