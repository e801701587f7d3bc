"""The addresses a session header journals: ``tcp://HOST:PORT`` (a
motion-capture stream) and the fake's truth socket path.

Both are checked where they are given (``--measure``, ``--truth-socket``) and
again where a journal is read back, so they live below both.
"""

from __future__ import annotations

import os
from pathlib import Path
from urllib.parse import urlsplit

from odohil.errors import ParameterError


def parse_tcp_url(url: str) -> tuple[str, int]:
    """``tcp://HOST:PORT`` as (host, port).

    Raises:
        ParameterError: not of that form (the message names the form).
    """
    form = "tcp://HOST:PORT (e.g. tcp://192.168.1.20:5555)"
    parts = urlsplit(url)
    try:
        port = parts.port
    except ValueError:
        port = None
    if (
        parts.scheme != "tcp"
        or not parts.hostname
        or port is None
        or not 0 < port < 65536
        or parts.path not in ("", "/")
        or parts.query
        or parts.fragment
    ):
        raise ParameterError(f"--measure {url!r}: a motion-capture stream is given as {form}")
    return parts.hostname, port


SOCKET_PATH_MAX = 107
"""Longest UNIX socket path, bytes (sun_path holds 108 with the final NUL)."""


def check_socket_path(path: str) -> None:
    """A UNIX socket (the fake's truth channel) can be made at ``path``.

    Raises:
        ParameterError: the path is empty or longer than
            :data:`SOCKET_PATH_MAX` bytes, or its folder does not exist.
    """
    size = len(os.fsencode(path))
    if not path or size > SOCKET_PATH_MAX:
        raise ParameterError(f"a socket path must be 1 to {SOCKET_PATH_MAX} bytes long, got {size}")
    folder = Path(path).parent
    if not folder.is_dir():
        raise ParameterError(f"folder {str(folder)!r} does not exist")
