"""Bounded reading: every file odohil reads, and every line of a stream, within a size limit.

A file is read only when it is a regular file (checked with ``os.stat`` before
it is opened, and with ``os.fstat`` on what was opened, which is opened with
``O_NONBLOCK`` so that a FIFO swapped in between cannot hang the open): a FIFO
without a writer, ``/dev/zero``, a terminal or a socket is refused at once, by
name. It is then read in pieces of :data:`CHUNK_BYTES`, and refused as soon as
it holds more than its ``max_bytes`` or a line longer than its
``max_line_bytes`` (counted while reading: a 50 MB single-line file is refused
after its first ``max_line_bytes``, never held whole). The error names the file
and the limit, and is the caller's own error class (a trial file's
TrialFileError, a journal's JournalError, ...), so each command keeps its exit
status (2, bad input).

:class:`LineSplitter` is the same line limit for a byte stream (the
motion-capture socket): lines come out whole, and an over-long one is dropped
up to its newline, counted by the caller, never accumulated.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Generator
from pathlib import Path

import numpy as np

from odohil.errors import OdohilError

CHUNK_BYTES = 1 << 16
"""Bytes read at a time."""
KIB = 1024
MIB = 1024 * KIB
_NEWLINE = 10


def file_kind(mode: int) -> str:
    """A file type in words (``a FIFO``, ``a character device``, ...)."""
    kinds = (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def check_regular_file(
    path: str | Path, what: str, error: type[OdohilError], max_bytes: int | None = None
) -> os.stat_result:
    """``os.stat`` of ``path`` (never opened): a regular file of at most
    ``max_bytes`` bytes, else ``error`` naming ``what``, the file and the limit.

    Raises:
        error: missing or unreadable, not a regular file, or too large.
    """
    try:
        info = os.stat(path)
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    _check_info(info, f"{what} {path}", error, max_bytes)
    return info


def _check_info(
    info: os.stat_result, name: str, error: type[OdohilError], max_bytes: int | None
) -> None:
    if not stat.S_ISREG(info.st_mode):
        raise error(
            f"{name} is {file_kind(info.st_mode)}: odohil reads only regular files "
            "(copy the data into a file first)"
        )
    if max_bytes is not None and info.st_size > max_bytes:
        raise error(
            f"{name} is {info.st_size} bytes: larger than the limit of {_size_text(max_bytes)}"
        )


def read_file_bytes(
    path: str | Path,
    *,
    what: str,
    max_bytes: int,
    error: type[OdohilError],
    max_line_bytes: int | None = None,
) -> bytes:
    """The bytes of the regular file ``path``, read in bounded pieces.

    Args:
        path: the file.
        what: what the file is, for messages (``trial file``, ``robot description``).
        max_bytes: the most bytes accepted.
        error: the error class raised (an OdohilError subclass).
        max_line_bytes: the longest line accepted, bytes without its newline
            (None: no line limit).

    Raises:
        error: the file is missing, not a regular file, larger than
            ``max_bytes``, or has a line longer than ``max_line_bytes``.
    """
    check_regular_file(path, what, error, max_bytes)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY)
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    try:
        _check_info(os.fstat(fd), f"{what} {path}", error, max_bytes)
        return read_fd_bytes(
            fd,
            source=f"{what} {path}",
            max_bytes=max_bytes,
            error=error,
            max_line_bytes=max_line_bytes,
        )
    finally:
        os.close(fd)


def read_file_text(
    path: str | Path,
    *,
    what: str,
    max_bytes: int,
    error: type[OdohilError],
    max_line_bytes: int | None = None,
) -> str:
    """:func:`read_file_bytes` decoded as UTF-8; undecodable bytes raise ``error``."""
    data = read_file_bytes(
        path, what=what, max_bytes=max_bytes, error=error, max_line_bytes=max_line_bytes
    )
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"cannot read {what} {path}: not UTF-8 text ({exc})") from None


def read_fd_bytes(
    fd: int,
    *,
    source: str,
    max_bytes: int,
    error: type[OdohilError],
    max_line_bytes: int | None = None,
) -> bytes:
    """Every byte of the open regular file ``fd`` from its start, in bounded pieces
    (see :func:`read_file_bytes`; ``source`` names it in messages)."""
    try:
        info = os.fstat(fd)
        _check_info(info, source, error, max_bytes)
        os.lseek(fd, 0, os.SEEK_SET)
        chunks: list[bytes] = []
        size = 0
        lines = _LineCounter(max_line_bytes)
        while True:
            chunk = os.read(fd, min(CHUNK_BYTES, max_bytes + 1 - size))
            if not chunk:
                return b"".join(chunks)
            size = _checked(chunk, size, lines, source, max_bytes, error)
            chunks.append(chunk)
    except BlockingIOError:
        raise error(f"{source}: would block; odohil reads only regular files") from None
    except OSError as exc:
        raise error(f"cannot read {source}: {exc.strerror or exc}") from None


def read_file_pieces(
    path: str | Path,
    *,
    what: str,
    max_bytes: int,
    error: type[OdohilError],
    max_line_bytes: int | None = None,
    piece_bytes: int = 4 * MIB,
) -> Generator[bytes, None, None]:
    """The bytes of the regular file ``path`` as pieces of about ``piece_bytes``
    that end with a newline (the last one with the file's end), checked as
    :func:`read_file_bytes` checks them, so that a big file is never held whole.
    Close the iterator (``contextlib.closing``) when leaving it early.

    Raises:
        error: as :func:`read_file_bytes`.
    """
    check_regular_file(path, what, error, max_bytes)
    source = f"{what} {path}"
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY)
    except OSError as exc:
        raise error(f"cannot read {source}: {exc.strerror or exc}") from None
    try:
        _check_info(os.fstat(fd), source, error, max_bytes)
        lines = _LineCounter(max_line_bytes)
        size = 0
        held = b""
        while True:
            try:
                chunk = os.read(fd, min(piece_bytes, max_bytes + 1 - size))
            except BlockingIOError:
                raise error(f"{source}: would block; odohil reads only regular files") from None
            except OSError as exc:
                raise error(f"cannot read {source}: {exc.strerror or exc}") from None
            if not chunk:
                if held:
                    yield held
                return
            size = _checked(chunk, size, lines, source, max_bytes, error)
            end = chunk.rfind(b"\n") + 1
            if end == 0:
                held += chunk
                continue
            piece = held + chunk[:end] if held else chunk[:end]
            held = chunk[end:]
            yield piece
    finally:
        os.close(fd)


def _checked(
    chunk: bytes,
    size: int,
    lines: _LineCounter,
    source: str,
    max_bytes: int,
    error: type[OdohilError],
) -> int:
    """The bytes read so far once ``chunk`` is counted in (its lines checked by
    ``lines``).

    Raises:
        error: the file grew past ``max_bytes`` while being read, or a line is too long.
    """
    size += len(chunk)
    if size > max_bytes:
        raise error(
            f"{source}: more than the limit of {_size_text(max_bytes)} (it grew while being read)"
        )
    problem = lines.feed(chunk)
    if problem is not None:
        raise error(f"{source}: {problem}")
    return size


class _LineCounter:
    """Tracks the length of the line being read; says when one is too long
    (the newlines found by numpy: a piece costs a few passes at C speed)."""

    def __init__(self, max_line_bytes: int | None) -> None:
        self.max_line_bytes = max_line_bytes
        self.line = 1
        self.run = 0

    def feed(self, chunk: bytes) -> str | None:
        if self.max_line_bytes is None:
            return None
        ends = np.flatnonzero(np.frombuffer(chunk, dtype=np.uint8) == _NEWLINE)
        # lengths of the lines ended in this chunk, then the open one's so far
        lengths = np.diff(ends, prepend=-1) - 1
        if lengths.size:
            lengths[0] += self.run
        tail = self.run + len(chunk) if ends.size == 0 else len(chunk) - 1 - int(ends[-1])
        too_long = np.flatnonzero(np.append(lengths, tail) > self.max_line_bytes)
        if too_long.size:
            return (
                f"line {self.line + int(too_long[0])} is longer than the limit of "
                f"{self.max_line_bytes} bytes"
            )
        self.line += int(ends.size)
        self.run = tail
        return None


class LineSplitter:
    """Whole lines out of a byte stream, none longer than ``max_line_bytes``.

    :meth:`feed` returns the complete lines of what has arrived (without their
    newline); what is held between calls never exceeds ``max_line_bytes``. An
    over-long line is dropped up to its newline and counted in
    :attr:`n_too_long` (its caller says so).
    """

    def __init__(self, max_line_bytes: int) -> None:
        if max_line_bytes <= 0:
            raise ValueError(f"max_line_bytes must be positive, got {max_line_bytes!r}")
        self.max_line_bytes = max_line_bytes
        self.n_too_long = 0
        self._pending = b""
        self._skipping = False

    def feed(self, chunk: bytes) -> list[bytes]:
        """The lines completed by ``chunk``, in order; over-long ones left out."""
        pending = self._pending + chunk
        if self._skipping:
            if b"\n" not in pending:
                self._pending = b""
                return []
            pending = pending.split(b"\n", 1)[1]
            self._skipping = False
        *lines, pending = pending.split(b"\n")
        kept = [line for line in lines if len(line) <= self.max_line_bytes]
        self.n_too_long += len(lines) - len(kept)
        if len(pending) > self.max_line_bytes:
            self.n_too_long += 1
            pending, self._skipping = b"", True
        self._pending = pending
        return kept


def _size_text(size: int) -> str:
    if size >= MIB and size % MIB == 0:
        return f"{size // MIB} MiB"
    if size >= KIB and size % KIB == 0:
        return f"{size // KIB} KiB"
    return f"{size} bytes"
