"""The fake Create 2 where the OI specification says more than "it answers":
stasis, a stream beyond the line rate, the host's line rate and the Baud
command, Passive sleep, and the time a mode change takes. Each is driven by
the independent byte-level host (tests/create2/host.py, written from the
spec, importing nothing from odohil) over a real pty."""

from __future__ import annotations

import time
from collections.abc import Callable

from fakes.create2.line import accepted, reframe

from .conftest import Robot
from .host import (
    BAUD,
    BAUD_CODES,
    LIBCREATE_IDS,
    PAUSE,
    SAFE,
    SENSORS,
    START,
    STREAM,
    Host,
    delta,
    direct,
    drive,
    split_frames,
)

MODE_WAIT_S = 0.1
"""What libcreate waits after a mode command, s."""


def safe(h: Host) -> None:
    """Start, Safe, and the wait a reference host leaves before driving."""
    h.send(bytes((START, SAFE)))
    time.sleep(MODE_WAIT_S)


def test_stasis_is_1_only_while_making_forward_progress(robot: Callable[..., Robot]) -> None:
    # p.32: "returns 1 when the robot is making forward progress and 0 when it
    # is not. It always returns 0 when the robot is turning, driving backward,
    # or not driving"
    h = robot().host
    safe(h)
    readings = {}
    for name, command in (
        ("forward", direct(200, 200)),
        ("backward", direct(-200, -200)),
        ("spin", drive(100, 1)),
        ("arc", direct(250, 150)),
        ("stopped", direct(0, 0)),
    ):
        h.send(command)
        time.sleep(0.06)
        h.stasis()  # answered: the command has reached the OI (however busy the machine)
        time.sleep(0.03)  # values change on 15 ms ticks
        readings[name] = h.stasis()
    assert readings == {"forward": 1, "backward": 0, "spin": 0, "arc": 0, "stopped": 0}


def test_a_stream_beyond_the_line_rate_is_corrupted_not_queued(
    robot: Callable[..., Robot],
) -> None:
    # libcreate's 75-byte frame every 15 ms needs 50 000 baud; at 19200 the line
    # carries 28 bytes a period: p.22, the stream "will eventually become corrupted"
    r = robot("--baud", "19200", pacing=True, host_baud=19200)  # at the line's real rate
    h = r.host
    h.send(bytes((START, STREAM, len(LIBCREATE_IDS), *LIBCREATE_IDS)))
    streamed = h.read_for(1.0)
    h.send(bytes((PAUSE, 0)))
    after_pause = h.read_for(0.6)
    # what is still on its way after the pause is bounded by the robot's send buffer
    # (a few frames), not a backlog that grows while the stream runs
    assert len(after_pause) <= 300, len(after_pause)
    # and the stream reached the host corrupted: far fewer valid frames than periods
    frames = split_frames(streamed + after_pause)
    assert len(frames) < 0.5 * 1.0 / 0.015
    assert sum(len(f) for f in frames) < len(streamed + after_pause)


def test_a_host_at_another_rate_gets_no_answer(robot: Callable[..., Robot]) -> None:
    r = robot(host_baud=9600)  # the robot is at 115200
    h = r.host
    h.send(bytes((START,)))
    reply = h.ask(bytes((SENSORS, 35)), 1, 0.3)
    assert reply != bytes((1,))  # nothing, or garbage
    assert r.process.truth().framing_errors > 0  # what the OI read was not what was sent
    h.set_baud(115200)
    h.send(bytes((START,)))
    assert h.mode() == 1


def test_the_baud_command_changes_the_robots_rate(robot: Callable[..., Robot]) -> None:
    r = robot()
    h = r.host
    h.send(bytes((START,)))
    assert h.mode() == 1
    h.send(bytes((BAUD, BAUD_CODES.index(19200))))
    time.sleep(0.1)  # p.9: wait 100 ms before sending at the new rate
    assert h.ask(bytes((SENSORS, 35)), 1, 0.3) != bytes((1,))  # still at 115200: no answer
    h.set_baud(19200)
    assert h.mode() == 1
    h.send(bytes((SAFE,)))
    time.sleep(MODE_WAIT_S)
    assert h.mode() == 2


def test_passive_sleeps_after_five_minutes_without_commands(
    robot: Callable[..., Robot],
) -> None:
    # p.7: Passive sleeps after 5 min of inactivity; at time scale 300 that is 1 s
    r = robot("--time-scale", "300")
    h = r.host
    h.send(bytes((START,)))
    for _ in range(15):  # commands keep it awake
        time.sleep(0.1)
        assert h.mode() == 1
    time.sleep(1.5)
    assert r.process.truth().asleep
    assert h.mode() is None  # asleep: no answer
    # Safe and Full never sleep
    r.process.event("wake")
    safe(h)
    time.sleep(1.5)
    assert h.mode() == 2
    assert not r.process.truth().asleep


def test_a_drive_sent_with_safe_is_not_obeyed_one_sent_after_the_wait_is(
    robot: Callable[..., Robot],
) -> None:
    r = robot()
    h = r.host
    h.send(bytes((START,)))
    assert h.mode() == 1
    before = h.encoders()
    h.send(bytes((SAFE,)) + direct(200, 200))  # no time to change modes
    time.sleep(0.2)
    assert h.encoders() == before
    assert not r.process.truth().moving
    assert h.mode() == 2
    h.send(direct(200, 200))
    time.sleep(0.1)
    h.send(direct(0, 0))
    moved = [delta(b, a) for b, a in zip(before, h.encoders(), strict=True)]
    assert min(moved) > 0


def test_the_line_model_frames_bits_at_the_readers_rate() -> None:
    data = bytes((128, 131, 145, 0, 200, 0, 200))
    assert reframe(data, 19200, 19200) == [(b, True) for b in data]
    # a Start sent at 9600 lasts 12 bit times at 115200: a low start bit and seven
    # low data bits read as zero bytes without their stop bit, then the high bit
    good, errors = accepted(bytes((128,)), 9600, 115200)
    assert errors >= 8
    assert 128 not in good
    # read 12 times slower the host sees fewer bytes than were sent, none of them right
    slow = [b for b, _ in reframe(data, 115200, 9600)]
    assert len(slow) < len(data)
    assert bytes(slow) != data[: len(slow)]
