"""Fixtures: the fake robot as a pty subprocess, and as an in-process port."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack

import pytest
import serial

import fakes  # noqa: F401  (registers fakerobot://)
from fakes.nomad.process import EmulatorProcess
from fakes.nomad.truth import TruthSnapshot
from odohil.protocol.nomad.messages import Lp, St, encode_request

from .link import RawLink

FAST = ["--no-pacing", "--seed", "7"]


class PtyRobot:
    """A running emulator process and a raw link to its pty."""

    def __init__(self, process: EmulatorProcess, port: serial.Serial) -> None:
        self.process = process
        self.port = port
        self.link = RawLink(port)

    def truth(self) -> TruthSnapshot:
        """The robot's true pose and logs."""
        return self.process.truth()


@pytest.fixture
def pty_robot() -> Iterator[Callable[..., PtyRobot]]:
    """Factory: ``pty_robot(*args)`` starts ``python -m fakes.nomad`` with ``args``.

    On teardown the robot is told to stop and must report itself stopped.
    """
    with ExitStack() as stack:
        robots: list[PtyRobot] = []

        def start(*args: str) -> PtyRobot:
            process = stack.enter_context(EmulatorProcess([*FAST, *args]))
            port = serial.serial_for_url(process.device, baudrate=38400, timeout=0.1)
            stack.callback(port.close)
            robot = PtyRobot(process, port)
            robots.append(robot)
            return robot

        yield start
        for robot in robots:
            snapshot = robot.truth()
            if snapshot.disconnected:
                continue
            robot.link.send(encode_request(St()))
            robot.link.read_packet(1.0)
            assert not _settled_moving(robot), "robot still moving after st"


def _settled_moving(robot: PtyRobot) -> bool:
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline:
        if not robot.truth().moving:
            return False
        time.sleep(0.02)
    return True


@pytest.fixture
def fake_port() -> Iterator[Callable[[str], serial.Serial]]:
    """Factory: ``fake_port("seed=1&time_scale=100")`` opens fakerobot://?... in process."""
    ports: list[serial.Serial] = []

    def open_port(query: str) -> serial.Serial:
        port = serial.serial_for_url(f"fakerobot://?{query}", timeout=0.5)
        ports.append(port)
        return port

    yield open_port
    for port in ports:
        if port.is_open and not port.truth().disconnected:
            port.write(encode_request(Lp()))
            assert not port.truth().moving
        port.close()
