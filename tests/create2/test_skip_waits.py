"""``skip_waits=1`` on a ``fakecreate2://`` URL: a read that waits for the
fake's next stream frame moves the fake's clock to it instead of sleeping
(fakes/create2/clock.py ``skip``), so a session on the fake runs as fast as its
host computes; the frames and their simulated times are what the host would
have read after sleeping."""

from __future__ import annotations

import pytest
import serial

import fakes
from fakes.create2.clock import LagAbsorbingClock
from odohil.protocol.create2 import commands
from odohil.protocol.create2.stream import STREAM_PERIOD_S, StreamDecoder, frame_size

fakes.register_url_handlers()

IDS = (43, 44)
"""Left and right encoder counts."""
PERIOD_SIM_S = STREAM_PERIOD_S * 10
"""Simulated seconds between two frames at time scale 10."""


def test_skip_moves_the_clock_and_gaps_are_still_cut() -> None:
    wall = [100.0]
    clock = LagAbsorbingClock(0.015, lambda: wall[0])
    start = clock()
    clock.skip(0.250)
    assert clock() - start == pytest.approx(0.250)
    wall[0] += 0.500  # the host away: still cut to one step
    assert clock() - start == pytest.approx(0.265)
    clock.skip(-1.0)  # never backwards
    assert clock() - start == pytest.approx(0.265)
    assert clock.skipped_s == pytest.approx(0.250)


def _frames(query: str, count: int, timeout_s: float) -> tuple[int, float, int]:
    """Read ``count`` frames of a fake Create 2 streaming its encoders: the
    empty reads on the way, the fake's simulated seconds, and the frames read."""
    port = serial.serial_for_url(
        f"fakecreate2://?seed=1&time_scale=10{query}", baudrate=115200, timeout=timeout_s
    )
    decoder = StreamDecoder()
    frames = empty = 0
    with port:
        port.write(commands.start() + commands.safe() + commands.stream(IDS))
        start = port.truth().sim_time_s
        while frames < count:
            data = port.read(frame_size(IDS))
            empty += not data
            frames += len(decoder.feed(data))
        return empty, port.truth().sim_time_s - start, frames


def test_frames_come_at_their_simulated_period_without_the_wait() -> None:
    # the port's timeout longer than a frame: every read returns one frame
    empty, sim_s, _ = _frames("&max_gap_ms=15&skip_waits=1", 40, timeout_s=0.1)
    assert empty == 0
    # 40 frames of 15 ms wall each at time scale 10: 6 simulated seconds (and
    # at most one 15 ms gap more per host call on a loaded machine)
    assert 39 * PERIOD_SIM_S <= sim_s <= 80 * PERIOD_SIM_S


def test_a_read_shorter_than_a_frame_times_out_on_the_fakes_clock() -> None:
    # a 5 ms read (the Create 2 link's slice) on a 15 ms frame: the read times
    # out (empty) as it would have after sleeping; the frame comes to a later read
    empty, sim_s, frames = _frames("&max_gap_ms=15&skip_waits=1", 20, timeout_s=0.005)
    assert frames >= 20
    assert empty >= 20  # two empty reads for most frames
    assert 19 * PERIOD_SIM_S <= sim_s <= 60 * PERIOD_SIM_S
