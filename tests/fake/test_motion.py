"""The fake robot's motion over a pty: trapezoids, kinematics (C8), limits (C6, C7, C9),
ws (C5), zr (C10) and the watchdog (C4)."""

from __future__ import annotations

import math
import time
from typing import Any

import pytest

from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad import wire_units
from odohil.protocol.nomad.codes import Code
from odohil.protocol.nomad.numbers import decode_s16, decode_u16
from odohil.protocol.nomad.replies import decode_reply
from odohil.protocol.nomad.state import N150_MASK, RobotState
from odohil.science.parameters import NOMAD150


def _state(robot: Any, req: m.Request) -> RobotState:
    reply = decode_reply(robot.link.request(req), req, N150_MASK)
    assert isinstance(reply, RobotState)
    return reply


def _rc(robot: Any) -> tuple[int, int, int, int]:
    p = robot.link.request(m.GetRc()).payload
    x, y, steer, turret = (decode_s16(p[i : i + 2]) for i in range(0, 8, 2))
    return x, y, steer, turret


def _wait_idle(robot: Any, timeout_s: int = 10) -> RobotState:
    return _state(robot, m.Ws(True, True, True, timeout_s))


def _trapezoid(t: float, d: float, v: float, a: float) -> tuple[float, float]:
    """Position and speed of a rest-to-rest trapezoid at time t (written from the textbook)."""
    t1 = v / a
    total = d / v + v / a
    if t <= 0:
        return 0.0, 0.0
    if t < t1:
        return a * t * t / 2, a * t
    if t < total - t1:
        return v * t1 / 2 + v * (t - t1), v
    if t < total:
        left = total - t
        return d - a * left * left / 2, a * left
    return d, 0.0


def test_translation_follows_the_trapezoid_on_the_scaled_clock(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "5")
    _state(robot, m.Sp(200, 450, 450))
    _state(robot, m.Ac(300, 300, 300))
    start = _state(robot, m.Pr(394, 0, 0))
    assert start.motor_status & 1
    t0 = start.timestamp_ms / 1000.0
    samples = []
    while True:
        s = _state(robot, m.Gs())
        samples.append(s)
        if not s.motor_status & 1:
            break
    total = 394 / 200 + 200 / 300
    for s in samples:
        x, v = _trapezoid(s.timestamp_ms / 1000.0 - t0, 394, 200, 300)
        assert abs(s.x - x) <= 1.0 + 200 * 0.001, (s, x)  # rounding + 1 ms timestamp step
        assert abs(s.trans_vel - v) <= 1.0, (s, v)
        moving = bool(s.motor_status & 1)
        elapsed = s.timestamp_ms / 1000.0 - t0
        if abs(elapsed - total) > 0.002:
            assert moving == (elapsed < total), (elapsed, total, s)
    assert len(samples) > 10  # the motion was really observed along the way (5x: 0.53 s wall)
    assert samples[-1].x == 394
    assert samples[-1].y == 0


def test_one_metre_forward_then_turn_and_drive_along_the_steering_angle(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "50")
    _state(robot, m.Sp(200, 450, 450))
    _state(robot, m.Pr(394, 0, 0))  # 1 m = 393.7 wire units
    _wait_idle(robot)
    assert _rc(robot) == (394, 0, 0, 0)
    _state(robot, m.Pr(0, 900, 0))
    _wait_idle(robot)
    _state(robot, m.Pr(100, 0, 0))
    _wait_idle(robot)
    assert _rc(robot) == (394, 100, 900, 0)  # C8: y grows when steering +90 deg
    _state(robot, m.Pr(0, -1800, -900))
    final = _wait_idle(robot)
    assert (final.steer, final.turret) == (2700, 2700)  # C6: -90 deg reported as 2700
    truth = robot.truth()
    assert truth.true_theta_rad == pytest.approx(-math.pi / 2, abs=0.02)
    assert (truth.encoder_x, truth.encoder_y) == (394, 100)


def test_zero_speed_pr_does_not_move_and_limits_are_clamped(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "100")
    reply = _state(robot, m.Pr(394, 900, 0))  # power-on speeds are 0 (C8)
    assert reply.motor_status == 0
    assert _rc(robot) == (0, 0, 0, 0)
    assert robot.truth().motion_log[-1].command == "pr"
    _state(robot, m.Ac(5000, 5000, 5000))
    ra = robot.link.request(m.GetRa()).payload
    assert [decode_u16(ra[i : i + 2]) for i in (0, 2, 4)] == [300, 300, 300]  # C9
    _state(robot, m.Vm(1000, -1000, 0))
    time.sleep(0.05)  # ramp: 1 s simulated = 10 ms wall
    rv = robot.link.request(m.GetRv()).payload
    assert [decode_s16(rv[i : i + 2]) for i in (0, 2, 4)] == [200, -450, 0]  # C9
    _state(robot, m.Vm(0, 0, 0))
    _wait_idle(robot)
    _state(robot, m.Da(0, 0))
    _state(robot, m.Dp(32700, -32700))
    _state(robot, m.Vm(200, 0, 0))
    time.sleep(0.05)
    x, y, _, _ = _rc(robot)
    assert (x, y) == (32767, -32700)  # C7: clamped, not wrapped


def test_ws_replies_at_once_with_timeout_zero_and_after_its_timeout(pty_robot: Any) -> None:
    robot = pty_robot()
    _state(robot, m.Vm(50, 0, 0))
    t = time.monotonic()
    reply = _state(robot, m.Ws(True, False, False, 0))
    assert time.monotonic() - t < 0.5
    assert reply.motor_status & 1
    t = time.monotonic()
    reply = _state(robot, m.Ws(True, False, False, 1))  # never idle: replies at the timeout
    waited = time.monotonic() - t
    assert 0.95 <= waited < 1.6
    assert reply.motor_status & 1
    reply = _state(robot, m.Ws(False, True, True, 1))  # steering and turret are idle
    assert reply.motor_status & 1


def test_zr_turns_back_zeroes_everything_and_replies_when_done(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "20")
    _state(robot, m.Sp(200, 450, 450))
    _state(robot, m.Pr(0, 900, 450))
    _wait_idle(robot)
    _state(robot, m.Pr(200, 0, 0))
    _wait_idle(robot)
    t = time.monotonic()
    robot.link.send(m.encode_request(m.Zr()))
    reply = robot.link.read_packet(timeout=5.0)
    waited = time.monotonic() - t
    assert reply is not None
    assert reply.type == Code.ZR
    assert waited >= 3.0 / 20  # C10: a few simulated seconds
    assert _rc(robot) == (0, 0, 0, 0)
    truth = robot.truth()
    assert truth.true_theta_rad == pytest.approx(0.0, abs=0.02)  # the wheels really turned back
    # but the robot stays where it drove: 200 wire units at the default 1 + E_T,
    # within 4 standard deviations of the distance noise (K_rho per metre)
    encoder_m = wire_units.wire_to_metres(200)
    spread = 4.0 * math.sqrt(NOMAD150.k_rho * encoder_m)
    assert truth.true_y_m == pytest.approx((1.0 + NOMAD150.e_t) * encoder_m, abs=spread)


def test_watchdog_stops_a_motion_when_the_host_goes_quiet(pty_robot: Any) -> None:
    robot = pty_robot()
    _state(robot, m.Vm(100, 0, 0))  # the watchdog is off until conf_tm
    time.sleep(0.6)
    assert robot.truth().moving
    _state(robot, m.ConfTm(1))
    for _ in range(5):  # any valid packet feeds it
        time.sleep(0.3)
        _state(robot, m.Gs())
    assert robot.truth().moving
    time.sleep(1.0 + 100 / 300 + 0.3)  # timeout, braking at 300, margin
    truth = robot.truth()
    assert not truth.moving
    assert any("watchdog expired" in line for line in truth.faults_fired)
    state = _state(robot, m.Gs())
    assert state.motor_status == 0
    assert state.trans_vel == 0
