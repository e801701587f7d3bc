"""odohil's Create 2 driver speaks only the documented OI: its resynchronisation
is made of defined opcodes, it pauses a stream with Pause/Resume (``150 0``),
and it waits after Safe/Full as the reference hosts do (libcreate 100 ms)
before any Drive. Checked on the fake's record of what reached it, over a pty."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from fakes.create2.process import Create2Process
from odohil.driver.create2.robot import Create2Robot
from odohil.driver.odometry import DriveSettings
from odohil.errors import ConnectionFailedError
from odohil.protocol.create2 import commands
from odohil.science.paths import Design

from .host import DEFINED_OPCODES, DIRECT, PAUSE, SAFE, STREAM

SETTINGS = DriveSettings(speed_m_s=0.3, step_timeout_s=20.0)
LIBCREATE_MODE_WAIT_S = 0.1


@pytest.fixture
def driven() -> Iterator[Create2Process]:
    """A fake Create 2 that odohil connected to, armed, drove one short trial
    on and closed."""
    with Create2Process(["--seed", "4", "--time-scale", "4"]) as process:
        with Create2Robot.connect(process.device, open_wait_s=0.05) as robot:
            robot.arm(SETTINGS)
            robot.zero()
            robot.drive(Design(1, 0.2, "reverse"), SETTINGS)
            robot.stop_and_confirm()
        yield process


def test_the_resynchronisation_is_made_of_defined_opcodes() -> None:
    assert set(commands.RESYNC) <= DEFINED_OPCODES


def test_no_undefined_opcode_reaches_the_robot(driven: Create2Process) -> None:
    assert driven.truth().unknown_opcodes == 0


def test_streams_are_paused_with_pause_resume_never_stream_of_nothing(
    driven: Create2Process,
) -> None:
    sent = [(c.opcode, c.data) for c in driven.truth().commands]
    assert (STREAM, (0,)) not in sent
    first_stream = next(i for i, (op, _) in enumerate(sent) if op == STREAM)
    assert (PAUSE, (0,)) in sent[:first_stream]  # connect pauses an old stream


def test_drive_comes_after_the_wait_that_follows_safe(driven: Create2Process) -> None:
    records = driven.truth().commands
    safe_at = next(c.wall_s for c in records if c.opcode == SAFE)
    first_drive = next(c for c in records if c.opcode == DIRECT and c.wall_s > safe_at)
    assert first_drive.wall_s - safe_at >= LIBCREATE_MODE_WAIT_S
    assert first_drive.mode == 2  # obeyed in Safe


def test_at_9600_baud_the_driver_polls_since_its_frame_would_not_fit() -> None:
    # 21 bytes every 15 ms need 14 000 baud: a stream at 9600 arrives corrupted
    slow = DriveSettings(speed_m_s=0.2, step_timeout_s=20.0)  # a reading takes 25 ms
    with Create2Process(["--seed", "4", "--baud", "9600"]) as process:
        with Create2Robot.connect(process.device, baud=9600, open_wait_s=0.05) as robot:
            robot.arm(slow)
            robot.zero()
            motion = robot.drive(Design(1, 0.2, "reverse"), slow)
            assert robot.link.sampling == "poll"
            assert abs(motion.end_pose[0]) < 0.005
        assert STREAM not in [c.opcode for c in process.truth().commands]


def test_a_host_at_another_rate_than_the_robot_does_not_connect() -> None:
    with Create2Process(["--seed", "4"]) as process:  # the robot at 115200
        with pytest.raises(ConnectionFailedError, match="does not answer"):
            Create2Robot.connect(process.device, baud=19200, open_wait_s=0.05)
        assert process.truth().framing_errors > 0
