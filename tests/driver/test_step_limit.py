"""The overall time limit of a leg or turn (odohil/driver/step_limit.py), on both
robots, and the Create 2's refusal of an encoder change it cannot tell from a
wrap-around (issue 17, item 3).

Before: a leg was bounded only by ``step_timeout_s`` (120 s), and the Create 2
driver took each frame's count change mod 65536 the short way round: on
``fakecreate2://?time_scale=2000`` the wheels turn about 33,700 counts between
two 15 ms frames, read as 31,800 counts *backwards*, so the leg's remaining
distance grew frame after frame and the robot was reported 110 km behind its
start when the 120 s ran out.

At time scale 2000 the fake's Passive mode sleeps after 150 ms of wall time
without a command (5 simulated minutes): a host descheduled that long between
Start and its first request found the robot asleep ("does not answer", CI at
stop 35). The URLs here say ``passive_sleep_s=0`` (never): what they test is the
wrap-around, not the sleep (tests/create2 test the sleep).
"""

from __future__ import annotations

import math
import re
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

import fakes
from odohil.cli.app import app
from odohil.driver.create2.robot import Create2Robot
from odohil.driver.odometry import DriveSettings
from odohil.driver.step_limit import LIMIT_MARGIN_S, profile_time_s, step_limit
from odohil.errors import MotionError, OdohilTimeoutError, ParameterError
from odohil.science.paths import Design
from odohil.session.robots.registry import open_robot

fakes.register_url_handlers()

SETTINGS = DriveSettings()  # 0.5 m/s, 0.5 m/s^2, step_timeout_s 120 s
BRISK = DriveSettings(acceleration_m_s2=2.0)
"""The legs that run into their limit: 0.5 m/s reached in 0.25 s, so that the
limit (2 x the profile + 3 s) is little more than its margin; the wait for
it is the check."""


def test_the_limit_follows_the_speed_profile_and_is_capped() -> None:
    # 1 m at 0.5 m/s, 0.5 m/s^2: 1 s accelerating and braking + 1.5 s cruising
    assert profile_time_s(1.0, 0.5, 0.5) == pytest.approx(3.0)
    # 0.1 m never reaches 0.5 m/s: a triangle, 2 sqrt(d / a)
    assert profile_time_s(-0.1, 0.5, 0.5) == pytest.approx(2 * math.sqrt(0.2))
    limit = step_limit("leg 1 m", 1.0, 0.5, 0.5, 120.0)
    assert limit.limit_s == pytest.approx(2 * 3.0 + LIMIT_MARGIN_S)
    assert "leg 1 m not done within its time limit of 9.0 s" in limit.expired_text()
    # a turn of pi at 45 deg/s and 30 deg/s^2: 4 s turning + 1.5 s speeding up and down
    turn = step_limit("turn 3.14159 rad", -math.pi, math.pi / 4, math.pi / 6, 120.0)
    assert turn.profile_s == pytest.approx(5.5)
    assert turn.limit_s == pytest.approx(2 * 5.5 + LIMIT_MARGIN_S)
    capped = step_limit("leg 1 m", 1.0, 0.5, 0.5, 4.0)
    assert capped.limit_s == 4.0
    assert "step timeout" in capped.expired_text()
    with pytest.raises(ParameterError, match="positive speed"):
        step_limit("leg 1 m", 1.0, 0.0, 0.5, 120.0)


def test_a_create2_leg_that_cannot_end_is_stopped_at_its_limit() -> None:
    """The fake's wheels turn at 5 % of the commanded speed (``drag``): the
    0.3 m leg would take 12 s; its limit is 2 x (0.6 + 0.25) + 3 s."""
    with Create2Robot.connect("fakecreate2://?seed=1&fault=drag", open_wait_s=0.0) as robot:
        robot.arm(BRISK)
        robot.zero()
        started = time.monotonic()
        with pytest.raises(OdohilTimeoutError) as raised:
            robot.drive(Design(0.5, 0.3, "reverse"), BRISK)
        took = time.monotonic() - started
        truth = robot.transport.truth()  # type: ignore[attr-defined]
        assert not truth.moving  # stopped, and the stop confirmed before the error
    message = str(raised.value)
    assert "leg 0.3 m (step 1 of 1) not done within its time limit of 4.7 s" in message, message
    assert "stop confirmed" in message
    assert 4.65 <= took < 8.6  # the limit is 4.7 s
    assert truth.travel_m < 0.3


def test_a_create2_at_a_time_scale_that_wraps_its_encoders_ends_the_leg_at_once() -> None:
    """The issue's fake: the first frame of the leg shows a change the 16-bit
    counters cannot tell from a wrap-around; the leg ends with that reason
    instead of driving on for 120 s."""
    with Create2Robot.connect(
        "fakecreate2://?seed=1&time_scale=2000&passive_sleep_s=0", open_wait_s=0.0
    ) as robot:
        robot.arm(SETTINGS)
        robot.zero()
        started = time.monotonic()
        # a frame 15 ms after the last shows the ambiguous change; on a busy host
        # readings arrive bunched (the link keeps the newest), and a change that
        # wrapped back into range reads as the leg ending thousands of counts long
        # (the rate, measured from the second reading on, stops it there): either
        # way the leg ends at once with the reason
        with pytest.raises(
            MotionError, match=r"wrap-around of the 16-bit counters|counts from its target"
        ):
            robot.drive(Design(0.5, 1.0, "reverse"), SETTINGS)
        assert time.monotonic() - started < 5.0
        robot.stop_and_confirm()
        assert not robot.transport.truth().moving  # type: ignore[attr-defined]


def test_a_nomad_step_that_never_reports_its_end_is_stopped_at_its_limit() -> None:
    """``stuck``: the fake reports the axis active for ever after the first
    ``pr``; the 0.05 m leg (at 0.5 m/s, 2 m/s^2: 0.316 s) ends at 2 x 0.316 + 3 s."""
    with open_robot("nomad150", "fakerobot://?seed=1&fault=stuck:pr@1") as robot:
        robot.arm(BRISK)
        robot.settle(5.0)
        started = time.monotonic()
        with pytest.raises(OdohilTimeoutError) as raised:
            robot.drive(Design(0.5, 0.05), BRISK)
        took = time.monotonic() - started
        assert not robot.odometry().moving
    message = str(raised.value)
    assert "leg 0.05 m (step 1 of 1) not done within its time limit of 3.6 s" in message, message
    assert "stop confirmed" in message
    assert 3.58 <= took < 7.55  # the limit is 3.6325 s, printed as 3.6 s


def test_the_issues_run_on_a_wrapping_create2_ends_with_a_clear_error(tmp_path: Path) -> None:
    """``odohil run`` on the issue's fake (a plan the estimator can use: the
    issue's ``k=1`` reverse plan is now refused before anything moves, see
    tests/session/test_preflight_estimable.py): exit 1 within seconds, the
    reason named, the stop confirmed, the session journaled for a resume.
    The fake's clock follows the reads (``skip_waits``) but also the host's
    wall time, which at time scale 2000 turns the wheels 2 s a millisecond: which
    of two clear errors ends the leg depends on the host's load (below)."""
    started = time.monotonic()
    result = CliRunner().invoke(
        app,
        [
            "run", "--port", "fakecreate2://?seed=1&time_scale=2000&skip_waits=1&passive_sleep_s=0",
            "--robot", "create2", "--allow-few-trials", "--plan", "k=0.5,l=1,n=3",
            "--measure", "fake", "--session", str(tmp_path / "s"),
        ],
    )  # fmt: skip
    assert time.monotonic() - started < 60.0
    err = " ".join(result.stderr.split())
    assert result.exit_code == 1, err
    # At time scale 2000 a millisecond of the host's wall time turns the wheels
    # 2 s: usually far enough between two frames that the step sees a change
    # it cannot tell from a wrap-around; when the host waits longer for a core
    # (twice in this stop's runs under 4 workers on 2 cores) the counters can
    # wrap to a plausible change, and the leg's end check names the miss instead. Both
    # are the clear error the issue asks for; nothing else is.
    wrap = (
        "leg 1 m (step 1 of 1): the encoders changed by" in err
        and "wrap-around of the 16-bit counters cannot be ruled out" in err
    )
    missed = re.search(r"leg 1 m \(step 1 of 1\) ended [-+]?\d+ \(left\), [-+]?\d+ \(right\) "
                       r"counts from its target", err) is not None  # fmt: skip
    assert wrap or missed, result.stderr
    assert "robot stopped (it reports" in err
