"""The append-only session journal: one folder per session, one JSON line per event.

Each line is a JSON object ``{"seq": N, "kind": K, "time": T, "data": {...},
"crc": "xxxxxxxx"}``: ``seq`` counts from 1 without gaps, ``time`` is wall
seconds since the epoch, ``crc`` is the CRC-32 (hex) of the line's bytes
without the crc member, i.e. of the line up to ``,"crc"`` with ``}`` appended.
Every append is written with one ``write`` call, then ``fsync``-ed before
:meth:`Journal.append` returns, so a record the engine acted on is on disk.

A crash can leave the last line torn (partly written, or not yet synced when
the machine died). Reading tells the two cases apart:

- the first bad line is the last one: a *torn last record*. It is not trusted;
  :func:`read_journal` reports it, and :meth:`Journal.open` copies its bytes
  to ``journal.torn-<seq>.bin`` beside the journal, truncates the journal to
  its valid records and says so in :attr:`JournalContents.torn`;
- a bad line with anything after it: the journal is corrupt,
  :class:`~odohil.errors.JournalError`.

Only one process may append at a time (an exclusive ``flock`` on the journal,
taken by :meth:`Journal.create` and :meth:`Journal.open`; the commands take it
before they open the robot's port, so a second one is refused, "session in
use", before it sends anything).
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import math
import os
import time
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any

from odohil.errors import JournalError
from odohil.session.bounded_io import MIB, read_fd_bytes, read_file_bytes
from odohil.session.journal.events import Event, decode, encode
from odohil.session.signals import signals_deferred

__all__ = [
    "Journal",
    "Record",
    "TornRecord",
    "journal_path",
    "read_journal",
]

JOURNAL_NAME = "journal.jsonl"
"""File name of the journal inside a session folder."""
TORN_PREFIX = "journal.torn-"
MAX_JOURNAL_BYTES = 128 * MIB
"""Largest journal read, bytes (a session of 1,000 trials journals about 2 MiB)."""
MAX_RECORD_BYTES = 4 * MIB
"""Longest journal record (line), bytes (the header carries the robot description)."""

_CRC_OPEN = b',"crc":"'
_CRC_SUFFIX_LEN = len(_CRC_OPEN) + 8 + 2  # ,"crc":"xxxxxxxx"}


@dataclass(frozen=True)
class Record:
    """One journaled event.

    Attributes:
        seq: sequence number, 1 for the first record, no gaps.
        kind: the event type (see odohil/session/journal/events.py).
        time: wall-clock time of the append, seconds since the epoch.
        data: the event's JSON payload.
    """

    seq: int
    kind: str
    time: float
    data: Mapping[str, Any]

    @property
    def event(self) -> Event:
        """The typed event (odohil/session/journal/events.py).

        Raises:
            ValueError: an unknown kind, or data that is not that event's.
        """
        return decode(self.kind, self.data)


@dataclass(frozen=True)
class TornRecord:
    """A last record that was cut off or damaged (typically by a crash).

    Attributes:
        line_number: its 1-based line number in the journal.
        offset: byte offset where it starts (the valid journal's length).
        size: its length in bytes.
        reason: what is wrong with it.
        set_aside: where its bytes were copied by :meth:`Journal.open`, or
            None when only read.
    """

    line_number: int
    offset: int
    size: int
    reason: str
    set_aside: Path | None = None

    def describe(self) -> str:
        """One sentence for the operator."""
        where = f"; kept aside in {self.set_aside}" if self.set_aside else ""
        return (
            f"the journal's last record (line {self.line_number}, {self.size} bytes) is "
            f"torn and was not used: {self.reason}{where}"
        )


@dataclass(frozen=True)
class JournalContents:
    """The trusted records of a journal and, if any, its torn last record."""

    records: tuple[Record, ...]
    torn: TornRecord | None


def journal_path(folder: str | Path) -> Path:
    """The journal file of a session folder."""
    return Path(folder) / JOURNAL_NAME


def encode_record(seq: int, kind: str, data: Mapping[str, Any], when: float) -> bytes:
    """The journal line of one record, newline included.

    Raises:
        ValueError: ``data`` holds something JSON cannot carry exactly (NaN,
            infinity, a non-string key, an unknown type).
    """
    body = json.dumps(
        {"seq": seq, "kind": kind, "time": when, "data": data},
        separators=(",", ":"),
        ensure_ascii=True,
        allow_nan=False,
    ).encode("ascii")
    crc = zlib.crc32(body)
    return body[:-1] + _CRC_OPEN + f"{crc:08x}".encode("ascii") + b'"}\n'


def _decode_line(line: bytes, expected_seq: int) -> Record:
    """Parse and check one line (without its newline); ValueError says what is wrong."""
    if len(line) <= _CRC_SUFFIX_LEN or not line.endswith(b'"}'):
        raise ValueError("no CRC at the end of the line")
    suffix = line[-_CRC_SUFFIX_LEN:]
    if not suffix.startswith(_CRC_OPEN):
        raise ValueError("no CRC at the end of the line")
    try:
        stored = int(suffix[len(_CRC_OPEN) : len(_CRC_OPEN) + 8], 16)
    except ValueError:
        raise ValueError("the CRC is not hexadecimal") from None
    body = line[:-_CRC_SUFFIX_LEN] + b"}"
    actual = zlib.crc32(body)
    if actual != stored:
        raise ValueError(f"CRC mismatch (stored {stored:08x}, computed {actual:08x})")
    try:
        raw = json.loads(body)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"not JSON: {exc}") from None
    if not isinstance(raw, dict):
        raise ValueError("not a JSON object")
    seq, kind, when, data = raw.get("seq"), raw.get("kind"), raw.get("time"), raw.get("data")
    if not isinstance(seq, int) or isinstance(seq, bool):
        raise ValueError("no integer sequence number")
    if seq != expected_seq:
        raise ValueError(f"sequence number {seq} where {expected_seq} was expected")
    if not isinstance(kind, str) or not kind:
        raise ValueError("no event kind")
    if not isinstance(when, int | float) or isinstance(when, bool) or not math.isfinite(when):
        raise ValueError("no time stamp")
    if not isinstance(data, dict):
        raise ValueError("the data member is not an object")
    return Record(seq=seq, kind=kind, time=float(when), data=data)


def parse_journal(content: bytes, source: str = "journal") -> JournalContents:
    """Check and parse a journal's bytes (see the module docstring).

    Raises:
        JournalError: a record before the last one is bad.
    """
    records: list[Record] = []
    offset = 0
    line_number = 0
    while offset < len(content):
        line_number += 1
        end = content.find(b"\n", offset)
        complete = end >= 0
        line = content[offset:end] if complete else content[offset:]
        next_offset = end + 1 if complete else len(content)
        try:
            if not complete:
                raise ValueError("the line has no end (cut off while being written)")
            records.append(_decode_line(line, len(records) + 1))
        except ValueError as exc:
            if next_offset < len(content):
                raise JournalError(
                    f"{source}: record {line_number} is corrupt ({exc}) and "
                    f"{len(content) - next_offset} bytes of journal follow it; "
                    "the session cannot be trusted past this point"
                ) from None
            torn = TornRecord(
                line_number=line_number,
                offset=offset,
                size=len(content) - offset,
                reason=str(exc),
            )
            return JournalContents(tuple(records), torn)
        offset = next_offset
    return JournalContents(tuple(records), None)


def read_journal(folder: str | Path) -> JournalContents:
    """Read a session's journal without changing anything.

    Raises:
        JournalError: no readable journal in ``folder``, or a corrupt record
            before the last one.
    """
    path = journal_path(folder)
    content = read_file_bytes(
        path,
        what="the session journal",
        max_bytes=MAX_JOURNAL_BYTES,
        max_line_bytes=MAX_RECORD_BYTES,
        error=JournalError,
    )
    return parse_journal(content, str(path))


def _fsync_dir(folder: Path) -> None:
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


class Journal:
    """An open journal that records are appended to; use as a context manager.

    Create one with :meth:`create` (a new session) or :meth:`open` (resume).
    """

    def __init__(self, folder: Path, fd: int, next_seq: int) -> None:
        self.folder = folder
        self._fd: int | None = fd
        self._next_seq = next_seq
        self._broken = False

    @property
    def path(self) -> Path:
        """The journal file."""
        return journal_path(self.folder)

    @property
    def next_seq(self) -> int:
        """The sequence number the next record gets."""
        return self._next_seq

    @classmethod
    def create(cls, folder: str | Path) -> Journal:
        """Start a new session folder (created if missing; must hold no journal).

        Raises:
            JournalError: a journal already exists there, or the folder
                cannot be written.
        """
        path = Path(folder)
        try:
            path.mkdir(parents=True, exist_ok=True)
            fd = os.open(
                journal_path(path), os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_EXCL, 0o644
            )
        except FileExistsError:
            cls.check_not_in_use(path)
            raise JournalError(
                f"{path} already holds a session journal; use `odohil resume {path}` "
                "to continue it, or choose another folder"
            ) from None
        except OSError as exc:
            raise JournalError(f"cannot create a session journal in {path}: {exc}") from exc
        try:
            cls._lock(fd, path)
            _fsync_dir(path)
        except BaseException:
            os.close(fd)
            raise
        return cls(path, fd, 1)

    @classmethod
    def open(cls, folder: str | Path) -> tuple[Journal, JournalContents]:
        """Open an existing session for appending, after checking every record.

        A torn last record is copied aside (``journal.torn-<seq>.bin``) and
        cut from the journal; the returned contents say so in ``torn``.

        Raises:
            JournalError: no journal, another process has it open, or a
                corrupt record before the last one.
        """
        path = Path(folder)
        try:
            # O_NONBLOCK and O_NOCTTY: a FIFO or a terminal put there cannot hang
            # the open; read_fd_bytes refuses anything but a regular file
            fd = os.open(journal_path(path), os.O_RDWR | os.O_APPEND | os.O_NONBLOCK | os.O_NOCTTY)
        except OSError as exc:
            raise JournalError(f"cannot open the session journal in {path}: {exc}") from exc
        try:
            cls._lock(fd, path)
            content = read_fd_bytes(
                fd,
                source=f"the session journal {journal_path(path)}",
                max_bytes=MAX_JOURNAL_BYTES,
                max_line_bytes=MAX_RECORD_BYTES,
                error=JournalError,
            )
            os.set_blocking(fd, True)
            contents = parse_journal(content, str(journal_path(path)))
            if contents.torn is not None:
                contents = cls._set_aside(path, fd, content, contents)
        except BaseException:
            os.close(fd)
            raise
        return cls(path, fd, len(contents.records) + 1), contents

    @classmethod
    def check_not_in_use(cls, folder: str | Path) -> None:
        """Whether another odohil uses the session in ``folder``: returns when
        nobody holds its journal's lock (or there is no journal to lock).

        Raises:
            JournalError: ``session in use``: another open journal (another
                process, or another :class:`Journal` of this one) holds the lock.
        """
        folder = Path(folder)
        try:
            fd = os.open(journal_path(folder), os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY)
        except OSError:
            return
        try:
            cls._lock(fd, folder)
        finally:
            os.close(fd)

    @staticmethod
    def _lock(fd: int, folder: Path) -> None:
        """Take the exclusive lock; the caller closes ``fd`` on failure."""
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise JournalError(
                f"session in use: {folder} is locked by another odohil process "
                "(only one run, resume or wizard at a time)"
            ) from None

    @staticmethod
    def _set_aside(
        folder: Path, fd: int, content: bytes, contents: JournalContents
    ) -> JournalContents:
        torn = contents.torn
        assert torn is not None
        seq = len(contents.records) + 1
        target = folder / f"{TORN_PREFIX}{seq}.bin"
        suffix = 1
        while target.exists():
            suffix += 1
            target = folder / f"{TORN_PREFIX}{seq}-{suffix}.bin"
        try:
            target.write_bytes(content[torn.offset :])
            with target.open("rb") as handle:
                os.fsync(handle.fileno())
            os.ftruncate(fd, torn.offset)
            os.fsync(fd)
            _fsync_dir(folder)
        except OSError as exc:
            raise JournalError(f"cannot set the torn last record of {folder} aside: {exc}") from exc
        kept = TornRecord(torn.line_number, torn.offset, torn.size, torn.reason, target)
        return JournalContents(contents.records, kept)

    def write(self, event: Event) -> Record:
        """Journal one event (its JSON through the one codec,
        odohil/session/journal/events.py) and make it durable (see :meth:`append`)."""
        kind, data = encode(event)
        return self.append(kind, data)

    def append(self, kind: str, data: Mapping[str, Any]) -> Record:
        """Append one raw record and make it durable (write, then fsync).
        Sessions journal typed events through :meth:`write`.

        Raises:
            JournalError: the journal is closed or the write failed.
            ValueError: ``data`` cannot be journaled exactly (e.g. NaN).
        """
        if self._fd is None:
            raise JournalError(f"the journal of {self.folder} is closed")
        if self._broken:
            raise JournalError(
                f"an earlier write to {self.path} failed half-way; resume the session to recover"
            )
        when = time.time()
        line = encode_record(self._next_seq, kind, data, when)
        # Ctrl-C (or any other signal that ends a session) is held back until the record
        # is whole and on disk, so that the record and the sequence count never disagree.
        with signals_deferred():
            try:
                view = memoryview(line)
                while view:
                    written = os.write(self._fd, view)
                    view = view[written:]
                os.fsync(self._fd)
            except BaseException as exc:
                self._broken = True
                if isinstance(exc, OSError):
                    raise JournalError(
                        f"cannot write the session journal {self.path}: {exc}"
                    ) from exc
                raise
            seq = self._next_seq
            self._next_seq += 1
        return Record(seq=seq, kind=kind, time=when, data=json.loads(json.dumps(data)))

    def close(self) -> None:
        """Release the journal (idempotent)."""
        if self._fd is not None:
            with contextlib.suppress(OSError):
                os.close(self._fd)
            self._fd = None

    def __enter__(self) -> Journal:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
