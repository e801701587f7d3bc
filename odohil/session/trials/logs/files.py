"""Reading log files with a bound on their size.

A log is read whole into memory, so its size is checked first (``os.stat``)
and anything that is not a regular file (a FIFO, a device) is refused before
it is opened: a typo on the command line must not hang or exhaust the machine.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from pathlib import Path

from odohil.errors import RecordingError
from odohil.session.bounded_io import check_regular_file, read_file_pieces, read_file_text

MAX_TEXT_BYTES = 512 * 1024 * 1024
"""Largest text log read, bytes (about 5 million rows of a CSV log)."""
MAX_LINE_BYTES = 64 * 1024
"""Longest line of a text log read, bytes."""
MAX_BAG_BYTES = 16 * 1024 * 1024 * 1024
"""Largest bag file read, bytes (a bag is read message by message)."""


def check_regular(path: Path, max_bytes: int) -> int:
    """The size of the regular file ``path`` in bytes (never opened).

    Raises:
        RecordingError: no such file, not a regular file, or larger than
            ``max_bytes``; the message names the file.
    """
    return check_regular_file(path, "log", RecordingError, max_bytes).st_size


def read_text(path: Path, max_bytes: int = MAX_TEXT_BYTES) -> str:
    """The UTF-8 text of the regular file ``path``, at most ``max_bytes``, read
    in bounded pieces (odohil/session/bounded_io.py).

    Raises:
        RecordingError: see :func:`check_regular`, a line longer than
            :data:`MAX_LINE_BYTES`, or the file is not UTF-8 text.
    """
    return read_file_text(
        path, what="log", max_bytes=max_bytes, error=RecordingError, max_line_bytes=MAX_LINE_BYTES
    )


def read_pieces(
    path: Path, max_bytes: int = MAX_TEXT_BYTES, piece_bytes: int = 4 * 1024 * 1024
) -> Generator[bytes, None, None]:
    """The bytes of the regular file ``path`` in pieces of whole lines, checked
    as :func:`read_text` checks them (but for UTF-8: the reader decodes).

    Raises:
        RecordingError: as :func:`read_text`.
    """
    return read_file_pieces(
        path,
        what="log",
        max_bytes=max_bytes,
        error=RecordingError,
        max_line_bytes=MAX_LINE_BYTES,
        piece_bytes=piece_bytes,
    )


def finite_number(path: Path, line: int, name: str, text: str) -> float:
    """The finite number ``text`` of field ``name`` on line ``line`` of ``path``.

    Raises:
        RecordingError: not a number, or not finite; the message names the
            file, the line and the field.
    """
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise RecordingError(f"{path} line {line}: {name}: not a finite number: {text.strip()!r}")
    return value
