"""``odohil emulate`` and ``python -m fakes.nomad`` start, serve, pace, and stop cleanly."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
import serial

from fakes.create2.process import Create2Process
from fakes.nomad.process import EmulatorProcess, set_launcher
from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.codes import Code
from tests.forked import start_fake

from .link import RawLink


def test_odohil_emulate_serves_a_pty_and_exits_cleanly_on_sigterm() -> None:
    process = EmulatorProcess(["--seed", "3", "--baud", "9600"], use_cli=True)
    with process:
        assert process.device.startswith("/dev/")
        port = serial.serial_for_url(process.device, baudrate=9600, timeout=0.1)
        try:
            link = RawLink(port)
            link.send(m.encode_request(m.Gs()))
            start = time.monotonic()
            raw, end = link.read_until_packet(timeout=2.0)
            assert raw[3] == Code.GS
            # pacing: 48 bytes at 9600 baud take 50 ms on the line
            assert end - start >= 48 * 10 / 9600 - 0.005
        finally:
            port.close()
        truth = process.truth()
        assert not truth.moving
    assert process.returncode == 0


@pytest.fixture
def exec_fakes() -> Iterator[None]:
    """``python -m fakes...`` exec'd, as a user or a benchmark starts it (the
    suite otherwise forks the fakes: tests/conftest.py)."""
    set_launcher(None)
    try:
        yield
    finally:
        set_launcher(start_fake)


@pytest.mark.parametrize("module", ["nomad", "create2"])
@pytest.mark.usefixtures("exec_fakes")
def test_python_m_fakes_exec_serves_a_pty_and_exits_cleanly_on_sigterm(module: str) -> None:
    process = (
        EmulatorProcess(["--seed", "3"]) if module == "nomad" else Create2Process(["--seed", "3"])
    )
    with process:
        assert process.device.startswith("/dev/")
        assert process.truth_socket
        assert not process.truth().moving
    assert process.returncode == 0
