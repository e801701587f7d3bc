"""A serial link that cannot hang or be fooled (issue 9, item 3), through the
real driver and the fake robot's pyserial port: a noise line ends every read
within its deadline, a stray packet is drained, a stale reply is never used,
and a motion below the wire's resolution is refused before anything is sent."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import pytest

from odohil.driver.nomad.link import open_port
from odohil.driver.nomad.motion import drive_trial
from odohil.driver.nomad.robot import NomadRobot
from odohil.errors import ConnectionFailedError, OdohilTimeoutError, ParameterError
from odohil.protocol.nomad.limits import (
    MAX_LEG_M,
    MIN_LEG_M,
    WIRE_LENGTH_M,
    check_leg_length_m,
    leg_to_wire,
)
from odohil.science.paths import Design

from .helpers import fake_robot

HANG_S = 10.0
"""A call that has not returned after this long (wall s) counts as a hang."""


def _within(seconds: float, call: Callable[[], Any]) -> BaseException | None:
    """Run ``call`` in a thread; fail the test if it has not ended in ``seconds``;
    return what it raised (None if it returned)."""
    outcome: list[BaseException | None] = []

    def target() -> None:
        try:
            call()
        except BaseException as exc:
            outcome.append(exc)
        else:
            outcome.append(None)

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(seconds)
    assert outcome, f"hung: still waiting after {seconds} s"
    return outcome[0]


def test_a_noise_line_is_refused_at_connect_naming_the_port() -> None:
    url = "fakerobot://?seed=1&time_scale=50&fault=noise"
    port: Any = open_port(url, 38400)
    started = time.monotonic()
    error = _within(HANG_S, lambda: NomadRobot.from_port(port))
    assert isinstance(error, ConnectionFailedError), error
    assert time.monotonic() - started < 5.0
    assert "not the robot's protocol" in str(error)
    assert "$GP" in str(error)  # the foreign bytes are quoted
    assert url in str(error)


def test_noise_mid_session_ends_each_read_within_its_deadline() -> None:
    with fake_robot("seed=1&time_scale=50&fault=noise:gs@3") as fake:
        fake.robot.state()
        started = time.monotonic()
        error = _within(HANG_S, fake.robot.state)
        elapsed = time.monotonic() - started
        assert isinstance(error, OdohilTimeoutError), error
        assert "not the robot's protocol" in str(error)
        # the request's 1 s and the gs resync's 1 s (plus its quiet wait)
        assert elapsed < 3.5, elapsed


@pytest.mark.parametrize("fault", ["merge", "merge:gs@2", "merge:pr@1"])
def test_a_stray_packet_on_a_paced_line_is_drained(fault: str) -> None:
    with fake_robot(f"seed=1&time_scale=50&pacing=1&fault={fault}") as fake:
        fake.robot.set_speeds(0.5, 1.0, 1.0)
        fake.robot.set_accelerations(0.5, 1.0, 1.0)
        for _ in range(20):
            fake.robot.state()
        fake.robot.move_relative(0.2, 0.0)
        end = fake.robot.poll_until_stopped(10.0)
        assert abs(end.x_m - 0.2) < 0.003
        assert fake.truth().faults_fired
        assert fake.commands("pr") == 1


def test_a_stale_reply_is_discarded_never_used() -> None:
    # gs 1 is the connect's; gs 3 is answered 2 s late, gs 5 not at all: the late
    # answer to 3 arrives while 5 waits and must not be taken for it
    with fake_robot("seed=1&time_scale=50&fault=late:gs@3&fault=drop:gs@5") as fake:
        fake.robot.state()
        asked = time.monotonic()
        with pytest.raises(OdohilTimeoutError):
            fake.robot.state()  # gs 3 times out; gs 4 resynchronises
        before = fake.robot.last_sample
        assert before is not None
        time.sleep(max(0.0, asked + 1.5 - time.monotonic()))
        with pytest.raises(OdohilTimeoutError, match=r"1 repl\(ies\) discarded as not this"):
            fake.robot.state()  # gs 5: only the stale reply comes
        after = fake.robot.last_sample
        assert after is not None
        assert after.robot_time_s >= before.robot_time_s
        assert fake.robot.link.stats.rejected_replies == 1
        assert "late on gs" in fake.truth().faults_fired


def test_wire_limits_of_a_leg() -> None:
    assert pytest.approx(0.00254) == WIRE_LENGTH_M
    assert pytest.approx(32767 * 0.00254) == MAX_LEG_M
    assert leg_to_wire(1.0) == 394
    assert leg_to_wire(-1.0) == -394
    check_leg_length_m(MIN_LEG_M)
    check_leg_length_m(-MAX_LEG_M)
    for bad in (0.001, 0.0, -0.02, MAX_LEG_M + 0.002, 100.0, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match="leg length"):
            check_leg_length_m(bad)


@pytest.mark.parametrize("design", [Design(k=1, l_m=0.001), Design(k=0.5, l_m=0.001)])
def test_legs_below_the_wire_resolution_are_refused_before_anything_moves(
    design: Design,
) -> None:
    with fake_robot("seed=1&time_scale=50") as fake:
        with pytest.raises(ParameterError, match=r"50\.0 mm"):
            drive_trial(fake.robot, design)
        with pytest.raises(ParameterError, match="rounds to 0"):
            fake.robot.move_relative(0.001, 0.0)
        with pytest.raises(ParameterError, match="would not move"):
            fake.robot.move_relative_wire(0, 0, 0)
        assert fake.commands("pr") == 0
