"""Benchmark of the fake robot: gs round trips over the pty (paced and not) and in process.

Run: python bench/fake_robot.py
"""

from __future__ import annotations

import time

import serial

import fakes  # noqa: F401  (registers fakerobot://)
from fakes.nomad.process import EmulatorProcess
from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.framing import Packet, PacketDecoder

GS = m.encode_request(m.Gs())


def _round_trips(port: serial.Serial, seconds: float) -> float:
    """gs requests answered per second (drain, write, read one whole reply)."""
    count = 0
    start = time.monotonic()
    while time.monotonic() - start < seconds:
        port.reset_input_buffer()
        port.write(GS)
        decoder = PacketDecoder()
        done = False
        while not done:
            done = any(isinstance(i, Packet) for i in decoder.feed(port.read(1)))
        count += 1
    return count / (time.monotonic() - start)


def _pty(args: list[str]) -> float:
    with EmulatorProcess(args) as robot:
        port = serial.serial_for_url(robot.device, baudrate=38400, timeout=1)
        try:
            return _round_trips(port, 3.0)
        finally:
            port.close()


def _metre_runs(n: int) -> float:
    """Wall seconds per simulated 1 m run (dp, pr, ws) in process at time scale 1e4."""
    port = serial.serial_for_url("fakerobot://?seed=1&time_scale=10000", timeout=1)
    port.write(m.encode_request(m.Sp(200, 450, 450)))
    start = time.monotonic()
    for _ in range(n):
        for req in (m.Dp(0, 0), m.Pr(394, 0, 0), m.Ws(True, True, True, 5)):
            port.reset_input_buffer()
            port.write(m.encode_request(req))
            decoder = PacketDecoder()
            while not any(isinstance(i, Packet) for i in decoder.feed(port.read(1))):
                pass
    elapsed = time.monotonic() - start
    port.close()
    return elapsed / n


def main() -> None:
    paced = _pty(["--seed", "1"])
    unpaced = _pty(["--seed", "1", "--no-pacing"])
    print(f"pty gs round trips, pacing at 38400 baud: {paced:.0f}/s")
    print(f"pty gs round trips, no pacing:           {unpaced:.0f}/s")
    per_run_ms = 1000 * _metre_runs(300)
    print(f"in process, 1 m run (dp, pr, ws) at time scale 1e4: {per_run_ms:.2f} ms per run")


if __name__ == "__main__":
    main()
