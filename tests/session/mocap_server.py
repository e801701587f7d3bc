"""Loopback motion-capture senders for the tests: a tcp server on 127.0.0.1
that sends one line per frame to every client it accepts, bounded in time.

- :class:`FrameServer` sends whatever ``frame(t)`` returns (t: seconds since
  the client connected), for the client's error tests;
- :func:`republish_truth` makes the frames of a motion-capture system watching
  the fake robot: its true pose (from the truth socket) in a rotated and
  shifted world frame, with Gaussian noise, at 100 Hz.
"""

from __future__ import annotations

import contextlib
import json
import math
import socket
import threading
import time
from collections.abc import Callable
from types import TracebackType

import numpy as np

Frame = Callable[[float], bytes | None]
"""The line to send at t seconds after connecting (None: send nothing)."""


def pose_line(t: float, x: float, y: float, theta: float, **extra: object) -> bytes:
    """One pose as the stream carries it."""
    return (json.dumps({"t": t, "x": x, "y": y, "theta": theta, **extra}) + "\n").encode()


class FrameServer:
    """Sends ``frame(t)`` at ``rate_hz`` to each client, on 127.0.0.1 only.

    Args:
        frame: the line for time t (s since the client connected).
        rate_hz: frames per second.
        lifetime_s: the server closes everything after this long, s.
    """

    def __init__(self, frame: Frame, rate_hz: float = 100.0, lifetime_s: float = 60.0) -> None:
        self.frame = frame
        self.period_s = 1.0 / rate_hz
        self.lifetime_s = lifetime_s
        self._listener = socket.create_server(("127.0.0.1", 0))
        self._listener.settimeout(0.1)
        self.port = self._listener.getsockname()[1]
        self.url = f"tcp://127.0.0.1:{self.port}"
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self.clients = 0

    def __enter__(self) -> FrameServer:
        self._deadline = time.monotonic() + self.lifetime_s
        accept = threading.Thread(target=self._accept, daemon=True)
        accept.start()
        self._threads.append(accept)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._stop.set()
        # wakes the accept thread at once (accept() fails on a listener shut
        # down) instead of at its next 0.1 s timeout
        with contextlib.suppress(OSError):
            self._listener.shutdown(socket.SHUT_RDWR)
        for thread in list(self._threads):
            thread.join(timeout=5.0)
        self._listener.close()

    def _alive(self) -> bool:
        return not self._stop.is_set() and time.monotonic() < self._deadline

    def _accept(self) -> None:
        while self._alive():
            try:
                conn, _ = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:  # shut down by __exit__
                return
            self.clients += 1
            thread = threading.Thread(target=self._serve, args=(conn,), daemon=True)
            thread.start()
            self._threads.append(thread)

    def _serve(self, conn: socket.socket) -> None:
        with conn:
            t0 = time.monotonic()
            n = 0
            while self._alive():
                line = self.frame(time.monotonic() - t0)
                try:
                    if line:  # no SIGPIPE when odohil in this process hangs up
                        conn.sendall(line, socket.MSG_NOSIGNAL)
                except OSError:
                    return
                n += 1
                time.sleep(max(0.0, t0 + n * self.period_s - time.monotonic()))


def republish_truth(
    true_pose: Callable[[], tuple[float, float, float]],
    *,
    rotation_rad: float,
    shift_m: tuple[float, float],
    sigma: tuple[float, float, float],
    seed: int,
) -> Frame:
    """Frames of a motion-capture system watching the fake robot: its true pose
    (x m, y m, heading rad, from ``true_pose``) in a world frame rotated by
    ``rotation_rad`` and shifted by ``shift_m``, plus independent Gaussian
    noise of standard deviations ``sigma`` (x m, y m, theta rad, world axes)
    in every frame, the heading wrapped to [-pi, pi) as a capture system sends it."""
    rng = np.random.default_rng(seed)
    c, s = math.cos(rotation_rad), math.sin(rotation_rad)
    lock = threading.Lock()

    def frame(t: float) -> bytes:
        with lock:  # one truth client and one generator, shared by the senders
            x, y, theta = true_pose()
            noise = rng.normal(0.0, 1.0, 3) * np.array(sigma)
        wx = shift_m[0] + c * x - s * y + noise[0]
        wy = shift_m[1] + s * x + c * y + noise[1]
        heading = (theta + rotation_rad + noise[2] + math.pi) % (2.0 * math.pi) - math.pi
        return pose_line(round(t, 6), wx, wy, heading, frame=int(t * 100), body="robot")

    return frame
