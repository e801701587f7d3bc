"""The fake Create 2 as a process on a pty, with the independent host
(tests/create2/host.py) opened on it: the fixture of the byte-level tests."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from fakes.create2.process import Create2Process

from .host import Host


class Robot:
    """A running fake and the host on its pty."""

    def __init__(self, process: Create2Process, baud: int) -> None:
        self.process = process
        self.host = Host(process.device, baud)


@pytest.fixture
def robot() -> Iterator[Callable[..., Robot]]:
    """Factory: ``robot(*args, use_cli=False, pacing=False, host_baud=115200)``
    starts ``python -m fakes.create2 --seed 3 ARGS`` (or ``odohil emulate
    --robot create2``; ``--no-pacing`` unless ``pacing``) and opens the host on
    its pty at ``host_baud``."""
    started: list[Robot] = []

    def start(
        *args: str, use_cli: bool = False, pacing: bool = False, host_baud: int = 115200
    ) -> Robot:
        options = ["--seed", "3", *([] if pacing else ["--no-pacing"]), *args]
        process = Create2Process(options, use_cli=use_cli)
        process.__enter__()
        r = Robot(process, host_baud)
        started.append(r)
        return r

    yield start
    for r in started:
        r.host.close()
        r.process.stop()
