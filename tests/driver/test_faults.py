"""Every fault of the fake robot: the driver raises a typed error within its
timeout (or copes, for harmless ones), never repeats a motion command, and the
fake ends stopped."""

from __future__ import annotations

import math
import time

import pytest

from odohil.driver.nomad.motion import drive_trial
from odohil.errors import (
    ChecksumError,
    DisconnectedError,
    MotionError,
    NakError,
    OdohilError,
    OdohilTimeoutError,
    UnexpectedReplyError,
)
from odohil.science.paths import Design

from .helpers import FakeLine, fake_robot

REPLY_ERRORS: dict[str, type[OdohilError]] = {
    "corrupt": ChecksumError,
    "drop": OdohilTimeoutError,
    "late": OdohilTimeoutError,
    "nak": NakError,
    "wrong-type": UnexpectedReplyError,
}
HARMLESS = ("split", "merge", "garbage", "stray")
# Ndirect's budget: 1 s for the first byte, plus our gs resync (1 s more at worst).
ERROR_BUDGET_S = 2.5


def _ready(fake: FakeLine) -> None:
    fake.robot.set_speeds(0.5, 1.0, 1.0)
    fake.robot.set_accelerations(0.5, 1.0, 1.0)


@pytest.mark.parametrize(("fault", "error"), REPLY_ERRORS.items())
def test_reply_fault_on_gs_raises_typed_error_then_recovers(
    fault: str, error: type[OdohilError]
) -> None:
    with fake_robot(f"seed=3&time_scale=50&fault={fault}:gs@2") as fake:
        started = time.monotonic()
        with pytest.raises(error, match="resynced with gs"):
            fake.robot.state()
        assert time.monotonic() - started < ERROR_BUDGET_S
        assert not fake.robot.state().moving


@pytest.mark.parametrize("fault", HARMLESS)
def test_harmless_reply_faults_are_absorbed(fault: str) -> None:
    with fake_robot(f"seed=3&time_scale=50&fault={fault}:pr&fault={fault}:gs@2") as fake:
        _ready(fake)
        fake.robot.move_relative(0.1, 0.0)
        end = fake.robot.poll_until_stopped(10.0)
        assert end.x_wire == 39
        assert fake.commands("pr") == 1
        assert len(fake.truth().faults_fired) == 2
    if fault == "garbage":
        assert fake.robot.link.stats.garbage_bytes > 0


@pytest.mark.parametrize(("fault", "error"), REPLY_ERRORS.items())
def test_reply_fault_on_pr_is_never_resent_and_robot_stops(
    fault: str, error: type[OdohilError]
) -> None:
    with fake_robot(f"seed=4&time_scale=50&fault={fault}:pr") as fake:
        _ready(fake)
        started = time.monotonic()
        with pytest.raises(error, match="st sent"):
            fake.robot.move_relative(0.5, 0.0)
        assert time.monotonic() - started < ERROR_BUDGET_S + 1.0
        # A NAKed pr is not executed; any other is executed once, never twice.
        assert fake.commands("pr") == (0 if fault == "nak" else 1)
        log = [r.command for r in fake.truth().motion_log]
        assert log[-1] == "st"
        assert fake.settles()


def test_stuck_motion_times_out_and_stops() -> None:
    with fake_robot("seed=5&time_scale=50&fault=stuck") as fake:
        _ready(fake)
        fake.robot.move_relative(0.5, 0.0)
        started = time.monotonic()
        with pytest.raises(OdohilTimeoutError, match="still moving"):
            fake.robot.poll_until_stopped(0.5)
        assert time.monotonic() - started < 0.5 + ERROR_BUDGET_S
        assert fake.commands("pr") == 1
        assert fake.commands("st") >= 1
        assert fake.settles()


def test_stuck_motion_times_out_with_ws() -> None:
    with fake_robot("seed=5&time_scale=50&fault=stuck") as fake:
        _ready(fake)
        fake.robot.move_relative(0.5, 0.0)
        with pytest.raises(OdohilTimeoutError):
            fake.robot.wait_stopped(1.0)
        assert fake.commands("pr") == 1
        assert fake.settles()


def test_disconnect_mid_motion_raises_disconnected() -> None:
    with fake_robot("seed=6&time_scale=50&fault=disconnect") as fake:
        _ready(fake)
        started = time.monotonic()
        fake.robot.move_relative(1.0, 0.0)
        with pytest.raises(DisconnectedError):
            fake.robot.poll_until_stopped(10.0)
        assert time.monotonic() - started < ERROR_BUDGET_S
        assert fake.commands("pr") == 1
        assert fake.truth().disconnected


def test_watchdog_stop_mid_motion_is_a_motion_error() -> None:
    with fake_robot("seed=7&time_scale=50&fault=watchdog:pr@1") as fake:
        with pytest.raises(MotionError, match="robot stopped"):
            # 1 m at 0.5 m/s and 0.5 m/s^2 cruises, so a stop halfway ends short
            # (for a triangular profile, halfway is where braking starts anyway).
            drive_trial(fake.robot, Design(0.5, 1.0))
        assert fake.commands("pr") == 1
        assert fake.settles()


def test_ctrl_c_during_polling_sends_st_first() -> None:
    def interrupt(_: object) -> None:
        raise KeyboardInterrupt

    with fake_robot("seed=8&time_scale=5") as fake:
        _ready(fake)
        fake.robot.move_relative(1.0, math.radians(10.0))
        with pytest.raises(KeyboardInterrupt):
            fake.robot.poll_until_stopped(10.0, interrupt)
        assert [r.command for r in fake.truth().motion_log] == ["pr", "st"]
        assert fake.settles()


def test_a_reply_to_another_hosts_stop_at_connect_is_skipped() -> None:
    """After a SIGKILL the guardian sends st on the line; the robot's answer can
    reach the next odohil process just after that process's first gs (seen:
    resume failed its pre-flight, "reply type 9 does not answer GS"). The
    stray st reply comes before the gs reply: it is skipped, counted, and the
    connection stands."""
    with fake_robot("seed=3&time_scale=50&fault=stray:gs@1") as fake:
        assert fake.truth().faults_fired  # the connect's gs was the one hit
        assert fake.robot.link.stats.rejected_replies == 1
        assert not fake.robot.state().moving
