"""The fake Create 2 over a real pty, checked by an independent byte-level
host (tests/create2/host.py, written from the facts document)."""

from __future__ import annotations

import math
import struct
import time
from collections.abc import Callable

import pytest

from fakes.create2.__main__ import main as fake_main
from fakes.create2.config import CREATE2_TRUTH

from .conftest import Robot
from .host import (
    FULL,
    PAUSE,
    QUERY,
    RESET,
    SAFE,
    SENSORS,
    START,
    STOP,
    STREAM,
    Host,
    delta,
    direct,
    drive,
    split_frames,
)

COUNTS_PER_MM = 508.8 / (math.pi * 72.0)
MODE_WAIT_S = 0.1
"""A host waits this long after Safe or Full (libcreate), s: the OI needs time
to change modes (tests/create2/test_fake_spec.py)."""


def mode_command(h: Host, *opcodes: int) -> None:
    """Send mode commands, then wait for the OI to change modes."""
    h.send(bytes(opcodes))
    time.sleep(MODE_WAIT_S)


def test_mode_state_machine(robot: Callable[..., Robot]) -> None:
    r = robot()
    h = r.host
    assert h.mode() is None  # Off: listens only for Start
    h.send(bytes((START,)))
    assert h.mode() == 1
    mode_command(h, SAFE)
    assert h.mode() == 2
    mode_command(h, FULL)
    assert h.mode() == 3
    h.send(bytes((START,)))
    assert h.mode() == 1
    h.send(bytes((STOP,)))
    assert h.mode() is None
    # the mode right after each command: Safe and Full take effect later
    modes = [rec.mode for rec in r.process.truth().commands]
    assert modes == [1, 1, 2, 1, 0]


def test_drive_direct_counts_forward_and_passive_ignores_it(robot: Callable[..., Robot]) -> None:
    r = robot()
    h = r.host
    h.send(bytes((START,)))
    before = h.encoders()
    h.send(direct(200, 200))  # Passive: ignored
    time.sleep(0.2)
    assert h.encoders() == before
    assert h.requested() == (0, 0)
    mode_command(h, SAFE)
    h.send(direct(200, 200))
    time.sleep(0.1)
    assert h.requested() == (200, 200)
    time.sleep(0.4)
    h.send(direct(0, 0))
    time.sleep(0.05)
    after = h.encoders()
    truth = r.process.truth()
    moved = [delta(b, a) for b, a in zip(before, after, strict=True)]
    # the counts are the truth's (the encoders count what the wheels were told)
    assert moved == [truth.left_counts, truth.right_counts]
    assert moved[0] == moved[1]
    assert 0.4 * 200 * COUNTS_PER_MM < moved[0] < 0.7 * 200 * COUNTS_PER_MM
    # the body really went forward about as far: (1 + E_T) times the encoders'
    # distance, within 4 SD of the fake's travel noise (K_rho x distance)
    counted_m = moved[0] / COUNTS_PER_MM / 1000
    spread_m = 4.0 * math.sqrt(CREATE2_TRUTH.k_rho * counted_m)
    assert truth.true_x_m == pytest.approx((1 + CREATE2_TRUTH.e_t) * counted_m, abs=spread_m)


def test_backwards_through_zero_the_counts_wrap(robot: Callable[..., Robot]) -> None:
    r = robot("--encoder-origin", "5")
    h = r.host
    mode_command(h, START, SAFE)
    assert h.encoders() == (5, 5)
    h.send(direct(-150, -150))
    time.sleep(0.3)
    h.send(direct(0, 0))
    time.sleep(0.05)
    left, _right = h.encoders()
    assert left > 60000  # wrapped below 0
    assert delta(5, left) < 0
    truth = r.process.truth()
    assert delta(5, left) == truth.left_counts - 5
    assert truth.true_x_m < 0


def test_spin_counts_each_wheel_in_its_commanded_direction(robot: Callable[..., Robot]) -> None:
    r = robot()
    h = r.host
    mode_command(h, START, SAFE)
    h.ask(bytes((SENSORS, 20)), 2)  # reset the angle accumulator
    h.send(drive(100, 1))  # spin CCW: right +, left -
    time.sleep(0.3)
    h.send(direct(0, 0))
    time.sleep(0.05)
    left, right = (delta(0, c) for c in h.encoders())
    assert left < 0 < right
    assert left == -right
    (angle,) = struct.unpack(">h", h.ask(bytes((SENSORS, 20)), 2))
    want = math.degrees((right - left) / COUNTS_PER_MM / 235.0)
    assert angle > 0
    assert abs(angle - want) <= 1.5


def test_angle_bug_and_mode_offset(robot: Callable[..., Robot]) -> None:
    r = robot("--angle-bug", "--mode-offset", "1")
    h = r.host
    mode_command(h, START, SAFE)
    assert h.mode() == 3  # Safe reported +1 (the 6xx bug)
    h.ask(bytes((SENSORS, 20)), 2)
    h.send(drive(100, -1))  # spin CW
    time.sleep(0.4)
    h.send(direct(0, 0))
    time.sleep(0.05)
    left, right = (delta(0, c) for c in h.encoders())
    (angle,) = struct.unpack(">h", h.ask(bytes((SENSORS, 20)), 2))
    want = math.degrees((right - left) / COUNTS_PER_MM / 235.0) * 0.324056
    assert angle < 0
    assert abs(angle - want) <= 1.5


def test_stream_frames_every_15_ms_pause_and_resume(robot: Callable[..., Robot]) -> None:
    r = robot()
    h = r.host
    mode_command(h, START, SAFE)
    h.send(bytes((STREAM, 4, 7, 35, 43, 44)))
    data = h.read_for(0.6)
    frames = split_frames(data)
    assert 25 <= len(frames) <= 45  # 0.6 s / 15 ms = 40
    for frame in frames:
        assert frame[:3] == bytes((19, 10, 7))
        assert frame[4:6] == bytes((35, 2))
        assert frame[6] == 43
        assert frame[9] == 44
    assert b"".join(frames) == data[data.index(frames[0]) :][: len(b"".join(frames))]
    h.send(bytes((PAUSE, 0)))
    time.sleep(0.05)
    h.port.reset_input_buffer()
    assert h.read_for(0.2) == b""
    h.send(bytes((PAUSE, 1)))
    assert len(split_frames(h.read_for(0.2))) >= 5
    h.send(bytes((STREAM, 0)))
    time.sleep(0.05)
    h.port.reset_input_buffer()
    assert h.read_for(0.1) == b""


def test_group_100_offsets(robot: Callable[..., Robot]) -> None:
    r = robot("--encoder-origin", "65000")
    h = r.host
    mode_command(h, START, SAFE)
    group = h.ask(bytes((SENSORS, 100)), 80)
    assert len(group) == 80
    assert group[40] == 2  # 35 mode @40
    assert struct.unpack(">HH", group[52:56]) == (65000, 65000)  # 43, 44 @52
    assert struct.unpack(">H", group[17:19]) == (16028,)  # 22 voltage, mV @17
    assert group[79] == 0  # 58 stasis @79: not moving


def test_cliff_in_safe_stops_and_drops_to_passive_full_ignores(
    robot: Callable[..., Robot],
) -> None:
    r = robot()
    h = r.host
    mode_command(h, START, SAFE)
    h.send(direct(200, 200))
    time.sleep(0.1)
    r.process.event("cliff_front_left")
    assert h.mode() == 1
    still = h.encoders()
    time.sleep(0.1)
    assert h.encoders() == still
    reply = h.ask(bytes((QUERY, 5, 7, 9, 10, 11, 12)), 5)
    assert reply == bytes((0, 0, 1, 0, 0))
    assert h.requested() == (0, 0)
    # Full: no safety stop
    mode_command(h, FULL)
    h.send(direct(200, 200))
    time.sleep(0.05)
    r.process.event("wheel_drop")
    assert h.mode() == 3
    assert h.ask(bytes((SENSORS, 7)), 1) == bytes((0x0C,))
    assert r.process.truth().moving


def test_fault_wheel_drop_at_a_distance(robot: Callable[..., Robot]) -> None:
    r = robot("--fault", "wheel_drop_left@0.05", "--time-scale", "2")
    h = r.host
    mode_command(h, START, SAFE)
    h.send(direct(250, 250))
    time.sleep(0.3)
    truth = r.process.truth()
    assert truth.mode == 1
    assert not truth.moving
    assert 0.05 <= truth.travel_m < 0.06
    assert h.ask(bytes((SENSORS, 7)), 1) == bytes((0x08,))
    assert truth.faults_fired[0].startswith("wheel_drop_left@0.05")


def test_reset_banner_and_partial_command_resync(robot: Callable[..., Robot]) -> None:
    r = robot()
    h = r.host
    h.send(bytes((START,)))
    h.port.reset_input_buffer()
    h.send(bytes((RESET,)))
    banner = h.read_for(0.2)
    assert b"r3-robot/tags/release-3.7.7" in banner
    assert banner.endswith(b"\r\n")
    assert h.mode() is None  # Off after Reset
    h.send(bytes((START, SAFE, 0x91, 0x00)))  # a Drive Direct cut short
    time.sleep(0.1)
    assert [c.opcode for c in r.process.truth().commands][-2:] == [START, SAFE]  # it waits
    h.send(bytes(16) + bytes((START,)))  # facts C10
    assert h.mode() == 1
    last = r.process.truth().commands[-2:]
    assert [(c.opcode, c.data) for c in last] == [(0x91, (0, 0, 0, 0)), (START, ())]


def test_odohil_emulate_robot_create2_prints_two_lines_and_survives_radius_0(
    robot: Callable[..., Robot],
) -> None:
    r = robot(use_cli=True)
    assert r.process.device.startswith("/dev/")
    assert r.process.truth_socket.endswith(".sock")
    r.host.send(bytes((START,)))
    assert r.host.mode() == 1
    assert r.process.truth().mode == 1
    # issue 31: the two Drives with radius 0 that once ended the process (C30)
    mode_command(r.host, SAFE)
    r.host.send(bytes.fromhex("89 00 00 00 00") + bytes.fromhex("89 00 C8 00 00"))
    assert r.host.mode() == 2  # the same process, still answering on its pty
    truth = r.process.truth()
    assert (truth.right_mm_s, truth.left_mm_s) == (200.0, 200.0)
    r.host.send(bytes.fromhex("89 00 00 00 00"))
    assert r.host.mode() == 2
    assert not r.process.truth().moving
    assert r.process.returncode is None


def test_python_m_fakes_create2_refuses_an_unknown_fault(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """As a bad option: usage, the message and exit 2, no traceback (it exited 1
    on an uncaught ParameterError). ``python -m fakes.create2``'s own main, in process."""
    with pytest.raises(SystemExit) as ended:
        fake_main(["--fault", "explode"])
    assert ended.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: python -m fakes.create2"), err
    assert "unknown fault 'explode'" in err
    assert "Traceback" not in err
