"""Opening the in-process fake robot through the driver's real port path."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import fakes  # noqa: F401  (registers the fakerobot:// URL handler)
from fakes.nomad.truth import TruthSnapshot
from odohil.driver.nomad.link import open_port
from odohil.driver.nomad.robot import NomadRobot


class FakeLine:
    """A NomadRobot on ``fakerobot://`` plus the fake's side channel."""

    def __init__(self, query: str, baud: int = 38400) -> None:
        self.port: Any = open_port(f"fakerobot://?{query}", baud)
        self.robot = NomadRobot.from_port(self.port)

    def truth(self) -> TruthSnapshot:
        """The fake's true state and logs (works after a disconnect too)."""
        # The engine outlives the port, so the truth is readable after close().
        snapshot: TruthSnapshot = self.port.engine.truth()
        return snapshot

    def settles(self, within_s: float = 1.0) -> bool:
        """Whether the fake is (or comes to) rest within ``within_s`` wall seconds;
        after ``st`` it still decelerates for a moment."""
        deadline = time.monotonic() + within_s
        while self.truth().moving:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def commands(self, name: str) -> int:
        """How many times the fake executed motion command ``name``."""
        return sum(1 for r in self.truth().motion_log if r.command == name)


@contextmanager
def fake_robot(query: str = "seed=1&time_scale=50") -> Iterator[FakeLine]:
    """A connected fake robot, closed (``st`` sent) afterwards."""
    line = FakeLine(query)
    try:
        yield line
    finally:
        line.robot.close()
