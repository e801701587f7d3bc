"""Reading log files with a bound on their size.

A log is read whole into memory, so its size is checked first (``os.stat``)
and anything that is not a regular file (a FIFO, a device) is refused before
it is opened: a typo on the command line must not hang or exhaust the machine.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from odohil.errors import RecordingError

MAX_TEXT_BYTES = 512 * 1024 * 1024
"""Largest text log read, bytes (about 5 million rows of a CSV log)."""
MAX_BAG_BYTES = 16 * 1024 * 1024 * 1024
"""Largest bag file read, bytes (a bag is read message by message)."""


def check_regular(path: Path, max_bytes: int) -> int:
    """The size of the regular file ``path`` in bytes.

    Raises:
        RecordingError: no such file, not a regular file, or larger than
            ``max_bytes``; the message names the file.
    """
    try:
        info = os.stat(path)
    except OSError as exc:
        raise RecordingError(f"cannot read {path}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(info.st_mode):
        raise RecordingError(f"cannot read {path}: not a regular file")
    if info.st_size > max_bytes:
        raise RecordingError(
            f"cannot read {path}: {info.st_size} bytes; at most {max_bytes} bytes are read"
        )
    return info.st_size


def read_text(path: Path, max_bytes: int = MAX_TEXT_BYTES) -> str:
    """The UTF-8 text of the regular file ``path``, at most ``max_bytes``.

    Raises:
        RecordingError: see :func:`check_regular`, or the file is not UTF-8 text.
    """
    check_regular(path, max_bytes)
    try:
        with open(path, "rb") as stream:
            data = stream.read(max_bytes + 1)
    except OSError as exc:
        raise RecordingError(f"cannot read {path}: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise RecordingError(f"cannot read {path}: more than {max_bytes} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise RecordingError(f"{path}: not UTF-8 text (byte {exc.start})") from None
