"""The Create 2 backend against the fake over a real pty: modes, legs closed
on the encoders (wrap-safe), odometry, safety stops, stop on every failure."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator

import pytest

from fakes.create2.process import Create2Process
from fakes.create2.truth import Create2Truth
from odohil.driver.create2.robot import Create2Robot
from odohil.driver.odometry import DriveSettings, OdometrySample
from odohil.errors import (
    ConnectionFailedError,
    DisconnectedError,
    MotionError,
    ParameterError,
    SafetyError,
    SafetyStopError,
)
from odohil.protocol.create2 import commands
from odohil.protocol.create2.opcodes import Opcode
from odohil.science.diff_drive import DiffDriveGeometry
from odohil.science.paths import Design

SETTINGS = DriveSettings(speed_m_s=0.3, step_timeout_s=20.0)
COUNTS_PER_M = 508.8 / (math.pi * 0.072)

Connect = Callable[..., tuple[Create2Process, Create2Robot]]


@pytest.fixture
def connect() -> Iterator[Connect]:
    """Factory: a fake Create 2 process with ``args`` and a robot connected to it."""
    opened: list[tuple[Create2Process, Create2Robot]] = []

    def start(*args: str, **kwargs: object) -> tuple[Create2Process, Create2Robot]:
        process = Create2Process(["--seed", "5", "--time-scale", "4", *args])
        process.__enter__()
        try:
            robot = Create2Robot.connect(process.device, open_wait_s=0.05, **kwargs)  # type: ignore[arg-type]
        except BaseException:
            process.stop()
            raise
        opened.append((process, robot))
        return process, robot

    yield start
    for process, robot in opened:
        robot.close()
        process.stop()


def settled(process: Create2Process, timeout_s: float = 1.0) -> Create2Truth:
    """The truth once the robot has taken in what was written (the pty and the
    fake's line pacing delay bytes by a few ms)."""
    deadline = time.monotonic() + timeout_s
    while True:
        truth = process.truth()
        if not truth.moving or time.monotonic() > deadline:
            return truth
        time.sleep(0.01)


def opcodes(process: Create2Process) -> list[int]:
    return [c.opcode for c in process.truth().commands]


def test_reverse_trial_ends_where_it_started_and_close_leaves_the_oi_off(
    connect: Connect,
) -> None:
    process, robot = connect()
    robot.arm(SETTINGS)
    robot.zero()
    seen: list[OdometrySample] = []
    motion = robot.drive(Design(1, 0.5, "reverse"), SETTINGS, seen.append)
    assert list(motion.samples) == seen
    x, y, th = motion.end_pose
    assert abs(x) < 0.002  # a leg ends within a few counts; the next one makes up for it
    assert y == 0.0
    assert th == 0.0
    assert max(s.x_m for s in motion.samples) == pytest.approx(0.5, abs=0.003)
    truth = process.truth()
    assert not truth.moving
    assert abs(truth.left_counts) < 5
    assert truth.left_counts == truth.right_counts
    sent = opcodes(process)
    # 130 Starts (resync), 150 0 (pause an old stream), Safe, 148 n ids (the
    # driver's stream), then Drive Direct only
    n = commands.RESYNC_STARTS
    assert sent[: n + 3] == [Opcode.START] * n + [
        Opcode.PAUSE_RESUME,
        Opcode.SAFE,
        Opcode.STREAM,
    ]
    assert Opcode.FULL not in sent
    assert set(sent[n + 3 :]) == {Opcode.DRIVE_DIRECT}
    robot.close()
    time.sleep(0.05)
    truth = process.truth()
    assert truth.mode == 0
    assert opcodes(process)[-4:] == [
        Opcode.DRIVE_DIRECT,
        Opcode.PAUSE_RESUME,
        Opcode.START,
        Opcode.STOP,
    ]


def test_full_mode_only_when_asked_and_polling_works(connect: Connect) -> None:
    process, robot = connect(full_mode=True, sampling="poll")
    robot.arm(SETTINGS)
    assert not robot.link.streaming
    motion = robot.drive(Design(0.5, 0.5), SETTINGS)
    assert motion.end_pose[0] == pytest.approx(0.5, abs=0.003)
    assert process.truth().mode == 3
    assert Opcode.FULL in opcodes(process)


@pytest.mark.parametrize(("origin", "backward"), [("65000", False), ("5", True)])
def test_legs_through_the_encoder_wrap(connect: Connect, origin: str, backward: bool) -> None:
    process, robot = connect("--encoder-origin", origin)
    robot.arm(SETTINGS)
    robot.zero()
    # 0.5 m: 1124 counts, past the wrap from either origin
    motion = robot.drive(Design(0.5, 0.5, backward=backward), SETTINGS)
    want = -0.5 if backward else 0.5
    assert motion.end_pose[0] == pytest.approx(want, abs=0.003)
    truth = process.truth()
    counts = truth.left_counts - int(origin)
    assert counts == pytest.approx(want * COUNTS_PER_M, abs=8)
    assert (truth.left_counts % 65536) != truth.left_counts  # the wire value wrapped


def test_odometry_uses_the_description_constants(connect: Connect) -> None:
    geometry = DiffDriveGeometry(508.8, 0.0720 * 1.01, 0.235)
    process, robot = connect(geometry=geometry)
    robot.arm(SETTINGS)
    robot.zero()
    motion = robot.drive(Design(0.5, 0.5), SETTINGS)
    # the robot's own counts say 0.5 m at 1.01 x the diameter
    assert motion.end_pose[0] == pytest.approx(0.5, abs=0.003)
    counts = process.truth().left_counts
    assert counts == pytest.approx(0.5 * COUNTS_PER_M / 1.01, abs=8)


def test_mode_plus_one_robot_is_detected(connect: Connect) -> None:
    process, robot = connect("--mode-offset", "1")
    assert robot.mode_offset == 1
    robot.arm(SETTINGS)
    robot.drive(Design(0.5, 0.3), SETTINGS)
    assert process.truth().mode == 2


@pytest.mark.parametrize(
    ("fault", "mode_after", "words"),
    [
        ("cliff_front_right@0.2", 1, "cliff front right"),
        ("wheel_drop@0.2", 1, "wheel drop right, wheel drop left"),
        ("bump_left@0.2", 2, "bump left"),
        ("charger@0.2", 1, "OI mode PASSIVE instead of SAFE"),
    ],
)
def test_a_safety_event_mid_leg_stops_the_trial(
    connect: Connect, fault: str, mode_after: int, words: str
) -> None:
    process, robot = connect("--fault", fault)
    robot.arm(SETTINGS)
    with pytest.raises(SafetyStopError, match=words):
        robot.drive(Design(0.5, 1.0), SETTINGS)
    truth = settled(process)
    assert not truth.moving
    assert truth.mode == mode_after
    assert 0.2 <= truth.travel_m < 0.6  # stopped within a few readings (a busy host is late)
    with pytest.raises(SafetyError, match="arm"):
        robot.drive(Design(0.5, 1.0), SETTINGS)


def test_a_hazard_at_arm_time_refuses_to_move(connect: Connect) -> None:
    process, robot = connect()
    process.event("wheel_drop_left")
    with pytest.raises(SafetyStopError, match="wheel drop left"):
        robot.arm(SETTINGS)
    with pytest.raises(SafetyError, match="arm"):
        robot.drive(Design(0.5, 1.0), SETTINGS)
    assert process.truth().travel_m == 0.0
    assert process.truth().mode == 1


def test_a_stalled_wheel_stops_with_motion_error(connect: Connect) -> None:
    process, robot = connect("--fault", "stall@0.1")
    robot.arm(SETTINGS)
    with pytest.raises(MotionError, match="have not moved"):
        robot.drive(Design(0.5, 1.0), SETTINGS)
    time.sleep(0.05)
    truth = process.truth()
    assert truth.right_mm_s == 0.0
    assert truth.left_mm_s == 0.0


def test_ctrl_c_in_a_callback_stops_the_robot(connect: Connect) -> None:
    process, robot = connect()
    robot.arm(SETTINGS)

    def interrupt(sample: OdometrySample) -> None:
        if sample.x_m > 0.1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        robot.drive(Design(0.5, 1.0), SETTINGS, interrupt)
    assert not settled(process).moving


def test_a_cut_line_raises_disconnected(connect: Connect) -> None:
    _process, robot = connect("--fault", "disconnect@0.2")
    robot.arm(SETTINGS)
    with pytest.raises(DisconnectedError):
        robot.drive(Design(0.5, 1.0), SETTINGS)
    robot.close()  # does not hang


def test_bad_settings_are_refused_before_anything_moves(connect: Connect) -> None:
    process, robot = connect()
    with pytest.raises(SafetyError, match="arm"):
        robot.drive(Design(0.5, 1.0), SETTINGS)
    with pytest.raises(ParameterError, match="speed_m_s"):
        robot.arm(DriveSettings(speed_m_s=0.7))
    robot.arm(SETTINGS)
    with pytest.raises(ParameterError, match="turn_rate_rad_s"):
        robot.drive(Design(1, 1.0), DriveSettings(speed_m_s=0.3, turn_rate_rad_s=5.0))
    assert process.truth().travel_m == 0.0


def test_silent_robot_fails_to_connect() -> None:
    with Create2Process(["--seed", "1"]) as process:
        process.event("wake")  # not asleep: a no-op
        # a robot that answers nothing: the OI sleeps after Power (133)
        import serial

        with serial.Serial(process.device, 115200) as port:
            port.write(bytes((128, 133)))
        with pytest.raises(ConnectionFailedError, match="does not answer"):
            Create2Robot.connect(process.device, open_wait_s=0.05)
