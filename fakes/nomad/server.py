"""Serve one fake robot on a pseudo-terminal, with its truth socket beside it.

The slave side of the pty is the robot's serial port as a host sees it (raw,
no echo); the master side belongs to the engine. The truth socket is a
UNIX-domain stream socket answering each line with one JSON line
(:class:`fakes.nomad.truth.TruthSnapshot`).
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import select
import signal
import socket
import termios
import time
import tty
from collections.abc import Callable
from pathlib import Path
from types import FrameType

from fakes.nomad.engine import Disconnect, NomadEngine
from fakes.nomad.pacing import LinePacer

_LOG = logging.getLogger(__name__)

POLL_S = 0.005
"""Longest sleep of the serving loop, wall s (the engine is polled this often)."""

_BAUD_CONSTANTS = {
    4800: termios.B4800,
    9600: termios.B9600,
    19200: termios.B19200,
    38400: termios.B38400,
}


class PtyServer:
    """A running fake robot on a pty (open it with :meth:`start`, then :meth:`run`).

    Args:
        engine: the robot.
        baud: line rate for pacing and the pty's nominal speed.
        pacing: model the line rate in both directions (10 bits per byte):
            requests reach the engine, and replies reach the host, no faster
            than a real serial line at ``baud`` would carry them.
        truth_path: where to create the truth socket.
    """

    def __init__(self, engine: NomadEngine, baud: int, pacing: bool, truth_path: Path) -> None:
        self.engine = engine
        self.baud = baud
        self.pacer = LinePacer(baud if pacing else None)
        self.inbound = LinePacer(baud if pacing else None)
        self.truth_path = truth_path
        self.device = ""
        self._master: int | None = None
        self._slave: int | None = None
        self._listener: socket.socket | None = None
        self._clients: dict[socket.socket, bytes] = {}
        self._unwritten = b""
        self._stop = False

    def start(self) -> None:
        """Open the pty and the truth socket."""
        master, slave = os.openpty()
        tty.setraw(slave)
        attrs = termios.tcgetattr(slave)
        speed = _BAUD_CONSTANTS.get(self.baud, termios.B38400)
        attrs[4] = attrs[5] = speed
        termios.tcsetattr(slave, termios.TCSANOW, attrs)
        os.set_blocking(master, False)
        self._master, self._slave = master, slave
        self.device = os.ttyname(slave)
        with contextlib.suppress(FileNotFoundError):
            self.truth_path.unlink()
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        listener.bind(str(self.truth_path))
        listener.listen(8)
        listener.setblocking(False)
        self._listener = listener

    def stop(self) -> None:
        """Ask :meth:`run` to return (safe from a signal handler)."""
        self._stop = True

    def run(self) -> None:
        """Serve until :meth:`stop`."""
        while not self._stop:
            now = time.monotonic()
            self._wait(now)
            now = time.monotonic()
            self._pump(now)
        self.close()

    def close(self) -> None:
        """Close the pty, the sockets, and remove the socket file."""
        self._cut_line()
        for client in list(self._clients):
            client.close()
        self._clients.clear()
        if self._listener is not None:
            self._listener.close()
            self._listener = None
            with contextlib.suppress(FileNotFoundError):
                self.truth_path.unlink()

    # ---- internals ------------------------------------------------------------
    def _wait(self, now: float) -> None:
        deadlines = [now + POLL_S]
        for t in (
            self.engine.next_output_wall(),
            self.pacer.next_release(),
            self.inbound.next_release(),
        ):
            if t is not None:
                deadlines.append(t)
        timeout = max(0.0, min(deadlines) - now)
        readers: list[int | socket.socket] = list(self._clients)
        if self._master is not None:
            readers.append(self._master)
        if self._listener is not None:
            readers.append(self._listener)
        try:
            ready, _, _ = select.select(readers, [], [], timeout)
        except InterruptedError:
            return
        for item in ready:
            if isinstance(item, int):
                self._read_master()
            elif item is self._listener:
                self._accept()
            else:
                self._serve_client(item)

    def _read_master(self) -> None:
        assert self._master is not None
        try:
            data = os.read(self._master, 4096)
        except BlockingIOError:
            return
        except OSError as exc:
            if exc.errno == errno.EIO:
                # nobody holds the slave open; cannot happen while we keep it
                return
            raise
        self.inbound.push(data, time.monotonic())

    def _pump(self, now: float) -> None:
        arrived = self.inbound.release(now)
        if arrived:
            self.engine.receive(arrived)
        for item in self.engine.take_output(now):
            if isinstance(item, Disconnect):
                _LOG.info("fault disconnect: closing the pty")
                self._cut_line()
            else:
                self.pacer.push(item, now)
        if self._master is None:
            self.pacer.clear()
            return
        self._unwritten += self.pacer.release(now)
        if self._unwritten:
            try:
                written = os.write(self._master, self._unwritten)
            except BlockingIOError:
                written = 0
            self._unwritten = self._unwritten[written:]

    def _cut_line(self) -> None:
        for fd in (self._master, self._slave):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = None
        self._unwritten = b""

    def _accept(self) -> None:
        assert self._listener is not None
        try:
            client, _ = self._listener.accept()
        except BlockingIOError:
            return
        client.setblocking(True)
        self._clients[client] = b""

    def _serve_client(self, client: socket.socket) -> None:
        try:
            chunk = client.recv(4096)
        except OSError:
            chunk = b""
        if not chunk:
            client.close()
            del self._clients[client]
            return
        buf = self._clients[client] + chunk
        while b"\n" in buf:
            line, _, buf = buf.partition(b"\n")
            reply = self._truth_reply(line.decode(errors="replace")) + "\n"
            try:
                client.sendall(reply.encode())
            except OSError:
                client.close()
                del self._clients[client]
                return
        self._clients[client] = buf

    def _truth_reply(self, line: str) -> str:
        """The JSON line (no newline) answering one truth-socket request line.

        The fake Nomad ignores what the line says; a subclass may act on it.
        """
        return self.engine.truth().to_json()


def serve_until_signalled(server: PtyServer, on_ready: Callable[[str, str], None]) -> None:
    """Run ``server`` until SIGINT or SIGTERM; ``on_ready(device, socket)`` once open.

    Shared by every fake robot's pty server (fakes/create2/server.py too).
    """

    def _handler(signum: int, frame: FrameType | None) -> None:
        server.stop()

    previous = {sig: signal.signal(sig, _handler) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        server.start()
        on_ready(server.device, str(server.truth_path))
        server.run()
    finally:
        server.close()
        for sig, old in previous.items():
            signal.signal(sig, old)


def serve(
    engine: NomadEngine,
    *,
    baud: int,
    pacing: bool,
    truth_path: Path,
    on_ready: Callable[[str, str], None],
) -> None:
    """Run a :class:`PtyServer` until SIGINT or SIGTERM; ``on_ready(device, socket)`` once open."""
    serve_until_signalled(PtyServer(engine, baud, pacing, truth_path), on_ready)
