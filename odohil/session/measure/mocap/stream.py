"""A motion-capture pose stream over tcp: newline-delimited JSON world poses.

The sender (a motion-capture system's bridge, a total station, a ROS node)
listens on ``tcp://HOST:PORT``; odohil connects and reads lines, each a JSON
object ``{"t": s, "x": m, "y": m, "theta": rad}`` in the capture system's
world frame (other keys are ignored). See docs/motion-capture.md.

Clocks: every pose is stamped on arrival with this computer's monotonic clock
(``received_s``, :func:`time.monotonic`); staleness and the still window are
judged on that clock. The sender's ``t`` is its own clock, in seconds,
never compared with ours in absolute terms; from one accepted pose to the
next it must increase (a repeated or older ``t`` is a replayed or reordered
frame), and by no more than the host's clock advanced plus
:data:`MAX_T_LEAD_S` (a frame stamped far in the future: a corrupt stamp, a
clock glitch). A frame that breaks either is dropped and counted as a bad
time stamp; it does not become the reference the next frames are judged by,
so one bad stamp never poisons the stream. When :data:`REANCHOR_FRAMES`
frames in a row break it but follow each other by the same rule, the
sender's clock stepped (or the first frame's stamp was the bad one): they
become the reference.

While a trial runs the stream also tracks how far the robot goes from its
start (:meth:`PoseStream.track_from`, :meth:`PoseStream.excursion_between`),
so a stream that says the robot never moved is caught even on a closed path.

A line that is not such an object (not JSON, a missing or non-finite member,
longer than :data:`MAX_LINE_BYTES`) is counted with its reason and dropped;
it never stops the stream.
"""

from __future__ import annotations

import json
import math
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from types import TracebackType
from typing import Any

from odohil.errors import ConnectionFailedError
from odohil.session.addresses import parse_tcp_url
from odohil.session.bounded_io import LineSplitter

MAX_LINE_BYTES = 4096
"""Longest line accepted; a longer one is counted malformed and skipped."""
MAX_T_LEAD_S = 1.0
"""How much further the sender's ``t`` may advance between two accepted
frames than this computer's clock did, s; a frame beyond is dropped."""
REANCHOR_FRAMES = 10
"""Frames in a row with a bad time stamp that follow each other by the rule
above, after which they are taken as the sender's new time line."""
EXCURSION_FILTER = 5
"""The excursion is the largest running median of this many successive
distances from the start (one stray frame does not make it)."""
PATH_FRAMES = 32768
"""How many tracked distances from the start are kept (5.5 min at 100 Hz)."""
BUFFER_S = 10.0
"""How many seconds of poses the client keeps (host clock)."""
DEFAULT_CONNECT_TIMEOUT_S = 5.0
_POLL_S = 0.1
"""How often the reader thread checks whether it should stop, s."""


@dataclass(frozen=True)
class StreamedPose:
    """One pose as received.

    Attributes:
        received_s: this computer's monotonic clock at arrival, s.
        t_s: the sender's time stamp, s (its own clock).
        x_m, y_m: position in the capture system's world frame, m.
        theta_rad: heading in that frame, rad (as sent).
    """

    received_s: float
    t_s: float
    x_m: float
    y_m: float
    theta_rad: float


@dataclass(frozen=True)
class StreamStatus:
    """What the reader thread has seen so far.

    Attributes:
        n_poses: poses accepted since connecting.
        n_malformed: lines dropped (bad JSON, members or length).
        last_malformed: the reason for the last dropped line ("" if none).
        n_bad_time: frames dropped for their time stamp (not increasing, or
            far ahead of this computer's clock).
        last_bad_time: the reason for the last of them ("" if none).
        last_received_s: monotonic arrival time of the newest pose (None: none yet).
        connected_s: monotonic time of the connection.
        closed: why the connection ended ("" while it is open).
    """

    n_poses: int
    n_malformed: int
    last_malformed: str
    last_received_s: float | None
    connected_s: float
    closed: str
    n_bad_time: int = 0
    last_bad_time: str = ""


def parse_pose_line(line: bytes, received_s: float) -> StreamedPose:
    """One line as a pose.

    Raises:
        ValueError: why the line is not a pose (for the malformed count).
    """
    try:
        raw: Any = json.loads(line)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"not JSON ({exc.__class__.__name__})") from None
    if not isinstance(raw, dict):
        raise ValueError("not a JSON object")
    values: list[float] = []
    for key in ("t", "x", "y", "theta"):
        value = raw.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{key!r} is missing or not a number")
        if not math.isfinite(value):
            raise ValueError(f"{key!r} is not finite")
        values.append(float(value))
    return StreamedPose(received_s, values[0], values[1], values[2], values[3])


class PoseStream:
    """The tcp client: a reader thread keeps the last :data:`BUFFER_S` of poses.

    Use as a context manager; leaving it (or :meth:`close`) closes the socket
    and joins the thread.

    Args:
        url: ``tcp://HOST:PORT``.
        connect_timeout_s: how long connecting may take, s.
        clock: the monotonic clock arrival is stamped with (tests may pass another).
    """

    def __init__(
        self,
        url: str,
        connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.host, self.port = parse_tcp_url(url)
        self.url = url
        self.connect_timeout_s = connect_timeout_s
        self.clock = clock
        self._sock: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._lock = threading.Condition()
        self._poses: deque[StreamedPose] = deque()
        self._n_poses = 0
        self._n_malformed = 0
        self._last_malformed = ""
        self._last: StreamedPose | None = None
        self._rival: list[StreamedPose] = []
        self._n_bad_time = 0
        self._last_bad_time = ""
        self._origin: tuple[float, float] | None = None
        self._recent: deque[float] = deque(maxlen=EXCURSION_FILTER)
        self._path: deque[tuple[float, float]] = deque(maxlen=PATH_FRAMES)
        self._connected_s = 0.0
        self._closed = ""

    def __enter__(self) -> PoseStream:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def open(self) -> None:
        """Connect and start reading.

        Raises:
            ConnectionFailedError: nobody listens at the URL (it is named).
        """
        try:
            sock = socket.create_connection((self.host, self.port), self.connect_timeout_s)
        except OSError as exc:
            raise ConnectionFailedError(
                f"motion capture {self.url}: cannot connect ({exc}); is the pose sender "
                "running and listening there?"
            ) from exc
        sock.settimeout(_POLL_S)
        self._sock = sock
        self._connected_s = self.clock()
        self._thread = threading.Thread(target=self._read, name=f"mocap {self.url}", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop the reader and close the socket. Idempotent."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._sock is not None:
            self._sock.close()
            self._sock = None
        with self._lock:
            if not self._closed:
                self._closed = "closed by odohil"
            self._lock.notify_all()

    # -- the reader thread ------------------------------------------------

    def _read(self) -> None:
        assert self._sock is not None
        splitter = LineSplitter(MAX_LINE_BYTES)
        reason = ""
        while not self._stop.is_set():
            try:
                chunk = self._sock.recv(65536)
            except TimeoutError:
                continue
            except OSError as exc:
                reason = f"connection lost ({exc})"
                break
            if not chunk:
                reason = "the sender closed the connection"
                break
            now = self.clock()
            too_long = splitter.n_too_long
            for line in splitter.feed(chunk):
                self._take(line.strip(), now)
            for _ in range(splitter.n_too_long - too_long):
                self._malformed(f"a line longer than {MAX_LINE_BYTES} bytes")
        with self._lock:
            self._closed = self._closed or reason or "closed by odohil"
            self._lock.notify_all()

    def _malformed(self, reason: str) -> None:
        with self._lock:
            self._n_malformed += 1
            self._last_malformed = reason

    def _take(self, line: bytes, now: float) -> None:
        if not line:
            return
        if len(line) > MAX_LINE_BYTES:
            self._malformed(f"a line longer than {MAX_LINE_BYTES} bytes")
            return
        try:
            pose = parse_pose_line(line, now)
        except ValueError as exc:
            self._malformed(f"{exc}: {line[:80]!r}")
            return
        with self._lock:
            bad = None if self._last is None else _time_problem(self._last, pose)
            taken = [pose]
            if bad is not None:
                self._n_bad_time += 1
                self._last_bad_time = bad
                if self._rival and _time_problem(self._rival[-1], pose) is not None:
                    self._rival = []
                self._rival.append(pose)
                if len(self._rival) < REANCHOR_FRAMES:
                    return
                # these frames follow each other: the sender's clock stepped, or
                # the reference was the bad stamp; they are taken after all
                assert self._last is not None
                self._n_bad_time -= len(self._rival) - 1
                self._last_bad_time = (
                    f"'t' stepped from {self._last.t_s:.6g} s to {self._rival[0].t_s:.6g} s; "
                    f"{len(self._rival)} frames followed the new time line, which is kept"
                )
                taken = self._rival
            self._rival = []
            for accepted in taken:
                self._last = accepted
                self._track(accepted)
                self._poses.append(accepted)
                self._n_poses += 1
            while self._poses and self._poses[0].received_s < now - BUFFER_S:
                self._poses.popleft()
            self._lock.notify_all()

    def _track(self, pose: StreamedPose) -> None:
        if self._origin is None:
            return
        self._recent.append(math.hypot(pose.x_m - self._origin[0], pose.y_m - self._origin[1]))
        if len(self._recent) == self._recent.maxlen:
            self._path.append((pose.received_s, sorted(self._recent)[len(self._recent) // 2]))

    # -- what callers read -----------------------------------------------

    def track_from(self, x_m: float, y_m: float) -> None:
        """From now on, track how far the poses go from (x_m, y_m) (world, m)."""
        with self._lock:
            self._origin = (x_m, y_m)
            self._recent.clear()
            self._path.clear()

    def excursion_between(self, begin_s: float, end_s: float) -> tuple[float | None, int]:
        """The farthest the poses that arrived in [begin_s, end_s] (host clock)
        went from the point given to :meth:`track_from`, m (each the running
        median of :data:`EXCURSION_FILTER` successive distances; None when
        none arrived), and how many arrived."""
        with self._lock:
            inside = [d for t, d in self._path if begin_s <= t <= end_s]
        return (max(inside) if inside else None), len(inside)

    def status(self) -> StreamStatus:
        """What the stream has delivered so far."""
        with self._lock:
            return StreamStatus(
                n_poses=self._n_poses,
                n_malformed=self._n_malformed,
                last_malformed=self._last_malformed,
                last_received_s=self._poses[-1].received_s if self._poses else None,
                connected_s=self._connected_s,
                closed=self._closed,
                n_bad_time=self._n_bad_time,
                last_bad_time=self._last_bad_time,
            )

    def poses_between(self, begin_s: float, end_s: float) -> list[StreamedPose]:
        """Poses that arrived in [begin_s, end_s] (host monotonic clock)."""
        with self._lock:
            return [p for p in self._poses if begin_s <= p.received_s <= end_s]

    def wait_for_pose(self, timeout_s: float) -> bool:
        """Wait until at least one pose has arrived, at most ``timeout_s``;
        whether one has (False also when the connection ended)."""
        deadline = self.clock() + timeout_s
        with self._lock:
            while self._n_poses == 0 and not self._closed:
                left = deadline - self.clock()
                if left <= 0:
                    break
                self._lock.wait(min(left, _POLL_S))
            return self._n_poses > 0


def _time_problem(last: StreamedPose, pose: StreamedPose) -> str | None:
    """Why ``pose``'s time stamp cannot follow ``last``'s, or None when it can
    (see the module docstring)."""
    if pose.t_s <= last.t_s:
        return f"'t' {pose.t_s:.6g} s does not increase (last {last.t_s:.6g} s)"
    step = pose.t_s - last.t_s
    elapsed = pose.received_s - last.received_s
    if step > elapsed + MAX_T_LEAD_S:
        return (
            f"'t' {pose.t_s:.6g} s is {step:.3g} s after the previous frame's, which arrived "
            f"{elapsed:.3g} s before it by this computer's clock (more than {MAX_T_LEAD_S:g} s "
            "ahead: a corrupt stamp or a clock glitch)"
        )
    return None
