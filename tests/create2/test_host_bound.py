"""Issue 31: the fake Create 2 on a pty runs its motion at most a bound
(fakes/create2/config.py HOST_BOUND_S) past what its host has read, so a
starved host finds its leg ended late, never driven on. The clock and the
engine on an injected clock (no timed asserts), then the pty server in a
thread of this process with a real pty and a pyserial host."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial

from fakes.create2.clock import ReadBoundClock
from fakes.create2.config import HOST_BOUND_S, build_config
from fakes.create2.engine import Create2Engine
from fakes.create2.server import Create2PtyServer
from fakes.create2.truth import Create2TruthClient
from odohil.driver.create2.robot import Create2Robot
from odohil.driver.odometry import DriveSettings, OdometrySample
from odohil.errors import ParameterError
from odohil.science.paths import Design

from .host import SAFE, START, STREAM, direct

SPEED_MM_S = 100
TICK_S = 0.015
DRIVE = DriveSettings(speed_m_s=0.3, step_timeout_s=20.0)


def test_the_clock_holds_at_the_bound_and_resumes_where_it_held() -> None:
    clock = ReadBoundClock(0.05, start=10.0)
    assert clock(10.03) == pytest.approx(0.03)
    assert clock(12.0) == pytest.approx(0.05)  # nothing read since the start
    clock.host_read(seen=12.0, now=12.0)  # caught up: runs on from 0.05
    assert clock(12.02) == pytest.approx(0.07)
    clock.host_read(seen=12.01, now=12.02)  # read only what was written by 12.01
    assert clock(12.5) == pytest.approx(0.11)  # held since 12.06
    assert clock.lost_s(12.5) == pytest.approx(2.39)
    with pytest.raises(ValueError, match="bound_s must be positive"):
        ReadBoundClock(0.0, start=0.0)


def _driving(bound_s: float | None) -> tuple[Create2Engine, list[float]]:
    wall = [0.0]
    engine = Create2Engine(
        build_config(seed=1, mode_change_s=0.0), clock=lambda: wall[0], host_bound_s=bound_s
    )
    engine.receive(bytes((START, SAFE)) + direct(SPEED_MM_S, SPEED_MM_S))
    return engine, wall


def test_a_starved_host_finds_the_wheels_at_most_the_bound_on() -> None:
    engine, wall = _driving(HOST_BOUND_S)
    wall[0] = 134 * TICK_S  # 2.01 s with nothing read
    away = engine.truth()
    assert away.moving
    assert away.travel_m == pytest.approx(SPEED_MM_S * HOST_BOUND_S / 1000.0)
    assert away.motion_lost_s == pytest.approx(134 * TICK_S - HOST_BOUND_S)
    for tick in range(134, 154):  # back, it reads each frame: the wheels drive on
        wall[0] = tick * TICK_S
        engine.host_read(wall[0])
    wall[0] = 154 * TICK_S
    back = engine.truth()
    assert back.travel_m - away.travel_m == pytest.approx(SPEED_MM_S * 20 * TICK_S / 1000.0)
    wall[0] = 300 * TICK_S  # away again: held again at the bound
    assert engine.truth().travel_m - back.travel_m == pytest.approx(SPEED_MM_S * 0.03 / 1000.0)


def test_the_truth_gives_the_wall_clock_its_command_log_is_on() -> None:
    # the command log is stamped in wall seconds since the start; the motion's
    # clock is held while frames lie unread (after a host has gone, for good):
    # a test placing a stop on its own clock needs the wall time, not the motion's
    engine, wall = _driving(HOST_BOUND_S)
    wall[0] = 134 * TICK_S
    engine.receive(direct(0, 0))
    wall[0] = 300 * TICK_S  # the host gone, the stream still on
    snap = engine.truth()
    assert snap.commands[-1].wall_s == pytest.approx(134 * TICK_S)
    assert snap.wall_s == pytest.approx(300 * TICK_S)
    assert snap.sim_time_s < snap.wall_s - 1.0  # the motion's clock is no stand-in


def test_a_host_that_keeps_up_sees_wall_time() -> None:
    engine, wall = _driving(HOST_BOUND_S)
    for tick in range(1, 101):  # it reads each frame 5 ms after its tick
        wall[0] = tick * TICK_S + 0.005
        engine.host_read(tick * TICK_S)
    assert engine.truth().motion_lost_s == 0.0
    assert engine.truth().sim_time_s == pytest.approx(100 * TICK_S)
    unbounded, wall = _driving(None)
    wall[0] = 134 * TICK_S
    assert unbounded.truth().sim_time_s == pytest.approx(134 * TICK_S)
    with pytest.raises(ParameterError, match="host_bound_s must be positive"):
        Create2Engine(build_config(seed=1), host_bound_s=0.0)


def _serve(tmp_path: Path, bound_s: float | None) -> Iterator[Create2PtyServer]:
    engine = Create2Engine(
        build_config(seed=3, mode_change_s=0.0, time_scale=5.0), host_bound_s=bound_s
    )
    server = Create2PtyServer(engine, 115200, pacing=False, truth_path=tmp_path / "t.sock")
    server.start()
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    yield server
    server.stop()
    thread.join(5.0)


@pytest.fixture
def served(tmp_path: Path) -> Iterator[Create2PtyServer]:
    """The pty server in a thread: a real pty, a truth socket, time scale 5."""
    yield from _serve(tmp_path, HOST_BOUND_S)


def test_a_driver_starved_mid_leg_ends_it_late_not_long(served: Create2PtyServer) -> None:
    # odohil's driver stops reading for 0.3 s halfway along a 0.4 m leg (at
    # 0.3 m/s and time scale 5: 0.45 m of driving on a wall clock): the leg
    # ends at its target, later
    starved: list[float] = []

    def starve(sample: OdometrySample) -> None:
        if sample.x_m >= 0.2 and not starved:
            starved.append(sample.x_m)
            time.sleep(0.3)

    with Create2Robot.connect(served.device, open_wait_s=0.05) as robot:
        robot.arm(DRIVE)
        robot.zero()
        motion = robot.drive(Design(0.5, 0.4, "reverse"), DRIVE, starve)
        robot.stop_and_confirm()
    with Create2TruthClient(served.truth_path) as truth:
        held = truth.snapshot()
    assert starved
    assert motion.end_pose[0] == pytest.approx(0.4, abs=0.01)
    assert held.travel_m == pytest.approx(0.4, abs=0.015)
    assert held.motion_lost_s > 0.2


def test_the_pty_server_holds_the_wheels_while_frames_lie_unread(
    served: Create2PtyServer,
) -> None:
    with (
        serial.Serial(served.device, 115200, timeout=0.02) as host,
        Create2TruthClient(served.truth_path) as truth,
    ):
        host.write(bytes((START, SAFE)) + direct(SPEED_MM_S, SPEED_MM_S))
        time.sleep(0.1)  # waiting with nothing to read: up to date, not held
        waiting = truth.snapshot()
        host.write(bytes((STREAM, 2, 43, 44)))
        end = time.monotonic() + 0.25
        while time.monotonic() < end:
            host.read(4096)  # a host reading its frames as they come
        reading = truth.snapshot()
        time.sleep(0.3)  # starved: the frames pile up unread
        away = truth.snapshot()
        host.write(direct(0, 0))
    # 0.1 s waiting and 0.25 s reading at time scale 5 and 100 mm/s: 175 mm
    # driven, nothing held;
    # 0.3 s away: at most the bound's 22.5 mm (and a pump's 5 ms) on
    assert waiting.motion_lost_s < 1e-9
    assert waiting.travel_m > 0.04
    assert reading.motion_lost_s < 0.1  # (a host the machine starves here may meet the bound)
    assert reading.travel_m > 0.1
    assert away.travel_m - reading.travel_m < 0.04
    assert away.motion_lost_s > 0.2
