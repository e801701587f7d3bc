"""``odohil emulate`` and ``python -m fakes.nomad`` start, serve, pace, and stop cleanly."""

from __future__ import annotations

import time

import serial

from fakes.nomad.process import EmulatorProcess
from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.codes import Code

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
