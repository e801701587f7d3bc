"""State polls per second over a pseudo-terminal, against the line-rate ceiling.

Starts ``odohil emulate --baud B`` (the fake paces its bytes at B baud), connects
the driver to its pty and calls ``NomadRobot.state()`` (one ``gs`` exchange:
6 bytes out, 48 in) for a fixed time. The fake paces both directions at B
baud (a request reaches it only when its last byte would have crossed a real
line), so the ceiling is B / 10 bits per byte / 54 bytes per exchange.

Run: python bench/poll_rate.py [--seconds 5] [--baud 9600 --baud 38400]
"""

from __future__ import annotations

import argparse
import time

from fakes.nomad.process import EmulatorProcess
from odohil.driver.nomad.robot import NomadRobot

BYTES_PER_POLL = 6 + 48
BITS_PER_BYTE = 10


def measure(baud: int, seconds: float) -> float:
    """Polls per second at ``baud``."""
    with (
        EmulatorProcess(["--seed", "1", "--baud", str(baud)], use_cli=True) as emu,
        NomadRobot.connect(emu.device, baud) as robot,
    ):
        for _ in range(5):
            robot.state()
        count = 0
        started = time.monotonic()
        while (elapsed := time.monotonic() - started) < seconds:
            robot.state()
            count += 1
    return count / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--baud", type=int, action="append")
    args = parser.parse_args()
    for baud in args.baud or [9600, 38400]:
        rate = measure(baud, args.seconds)
        line = baud / BITS_PER_BYTE / BYTES_PER_POLL
        print(
            f"{baud:>6} baud: {rate:7.2f} polls/s; line-rate ceiling {line:6.2f} "
            f"({100 * rate / line:5.1f}%)"
        )


if __name__ == "__main__":
    main()
