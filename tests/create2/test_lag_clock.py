"""The in-process fake Create 2 with ``max_gap_ms``: a host that is away does
not let the wheels drive on (the demo's guard against a busy machine)."""

from __future__ import annotations

import time

import pytest
import serial

import fakes
from fakes.create2.clock import LagAbsorbingClock
from odohil.protocol.create2 import commands

fakes.register_url_handlers()


def test_gaps_longer_than_the_bound_are_cut() -> None:
    wall = [100.0]
    clock = LagAbsorbingClock(0.015, lambda: wall[0])
    start = clock()
    wall[0] += 0.010
    assert clock() - start == pytest.approx(0.010)
    wall[0] += 0.500  # the host was descheduled for half a second
    assert clock() - start == pytest.approx(0.025)
    assert clock.lost_s == pytest.approx(0.485)
    with pytest.raises(ValueError, match="max_gap_s must be positive"):
        LagAbsorbingClock(0.0)


def _travel_while_away(query: str, away_s: float) -> float:
    """Metres the fake drives at 100 mm/s while its host sleeps ``away_s``."""
    port = serial.serial_for_url(
        f"fakecreate2://?seed=1&time_scale=10{query}", baudrate=115200, timeout=0.1
    )
    with port:
        port.write(commands.start() + commands.safe())
        deadline = time.monotonic() + 1.0
        while port.truth().mode != 2 and time.monotonic() < deadline:
            time.sleep(0.005)  # the OI takes time to change modes
        before = port.truth().travel_m
        port.write(commands.drive_direct(100, 100))
        time.sleep(away_s)
        travel = float(port.truth().travel_m - before)
        port.write(commands.drive_direct(0, 0))
    return travel


def test_a_host_away_does_not_drive_the_wheels_on() -> None:
    # wall clock: 0.3 s away at time scale 10 is 3 s of driving, 0.3 m
    assert _travel_while_away("", 0.3) > 0.2
    # bounded: at most one 15 ms step (0.15 s simulated, 15 mm) per host call,
    # whatever the machine's load
    assert _travel_while_away("&max_gap_ms=15", 0.3) < 0.03
