"""Each injected fault shows the documented byte-level behaviour (protocols/nomad/README.md)."""

from __future__ import annotations

import itertools
import time
from typing import Any

import pytest
import serial

from fakes.nomad.engine import (
    GARBAGE,
    LATE_EXTRA_S,
    NOISE_PERIOD_S,
    NOISE_SENTENCES,
    SPLIT_PAUSE_S,
    WRONG_TYPE,
)
from fakes.nomad.faults import parse_fault
from odohil.errors import ChecksumError, ParameterError, UnexpectedReplyError
from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.codes import Code
from odohil.protocol.nomad.framing import DecodeFault, Packet, PacketDecoder, parse_packet
from odohil.protocol.nomad.numbers import decode_s16
from odohil.protocol.nomad.replies import NAK_BYTES, decode_reply
from odohil.protocol.nomad.state import N150_MASK

GS = m.encode_request(m.Gs())
GS_REPLY_LEN = 48


def _timed_chunks(robot: Any, seconds: float) -> list[tuple[float, bytes]]:
    """Every read that returned bytes within ``seconds``, with its arrival time."""
    chunks = []
    start = time.monotonic()
    while time.monotonic() - start < seconds:
        robot.port.timeout = 0.01
        data = robot.port.read(4096)
        if data:
            chunks.append((time.monotonic() - start, data))
    return chunks


def test_fault_syntax() -> None:
    spec = parse_fault("drop:get_rc@3")
    assert (spec.name, spec.code, spec.nth) == ("drop", Code.GET_RC, 3)
    assert parse_fault("late:7").code == Code.GS
    assert parse_fault("stuck").matches(Code.PR)
    assert not parse_fault("stuck").matches(Code.GS)
    assert parse_fault("nak").matches(Code.GS)
    for bad in ("explode", "drop:nosuch", "drop@0", "drop@x"):
        with pytest.raises(ParameterError):
            parse_fault(bad)


def test_corrupt_flips_one_byte_so_the_checksum_fails(pty_robot: Any) -> None:
    robot = pty_robot("--fault", "corrupt:gs@2")
    robot.link.request(m.Gs())  # first gs: intact
    robot.link.send(GS)
    raw = robot.link.read_for(0.4)
    assert len(raw) == GS_REPLY_LEN
    with pytest.raises(ChecksumError):
        parse_packet(raw)
    repaired = bytearray(raw)
    repaired[GS_REPLY_LEN // 2] ^= 0xFF
    assert parse_packet(bytes(repaired)).type == Code.GS
    assert robot.link.request(m.Gs()).type == Code.GS  # third gs: intact again


def test_drop_executes_the_request_but_sends_nothing(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "50", "--fault", "drop:pr")
    robot.link.request(m.Sp(200, 450, 450))
    robot.link.send(m.encode_request(m.Pr(394, 0, 0)))
    assert robot.link.read_for(1.2) == b""  # longer than the host's 1 s wait
    truth = robot.truth()
    assert truth.encoder_x == 394  # the motion happened all the same (C11 trap)
    assert [r.command for r in truth.motion_log] == ["pr"]


def test_late_reply_arrives_after_the_host_gave_up(pty_robot: Any) -> None:
    robot = pty_robot("--fault", "late:gs@1")
    robot.link.send(GS)
    chunks = _timed_chunks(robot, 1.0 + LATE_EXTRA_S + 0.5)
    assert chunks
    assert chunks[0][0] >= 1.0 + LATE_EXTRA_S - 0.05
    assert parse_packet(b"".join(c for _, c in chunks)).type == Code.GS


def test_split_reply_comes_in_three_chunks_with_pauses(pty_robot: Any) -> None:
    robot = pty_robot("--fault", "split:gs")
    robot.link.send(GS)
    chunks = _timed_chunks(robot, 3 * SPLIT_PAUSE_S + 0.4)
    data = b"".join(c for _, c in chunks)
    assert parse_packet(data).type == Code.GS
    times = [t for t, _ in chunks]
    assert times[-1] - times[0] >= 2 * SPLIT_PAUSE_S - 0.05
    assert all(b - a < 1.0 for a, b in itertools.pairwise(times))  # below Ndirect's 1 s
    assert len(chunks) >= 3


def test_merge_writes_the_reply_and_another_packet_together(pty_robot: Any) -> None:
    robot = pty_robot("--fault", "merge:gs@1")
    robot.link.send(GS)
    raw = robot.link.read_for(0.4)
    assert raw[GS_REPLY_LEN:] == NAK_BYTES
    assert parse_packet(raw[:GS_REPLY_LEN]).type == Code.GS


def test_garbage_comes_before_the_reply(pty_robot: Any) -> None:
    robot = pty_robot("--fault", "garbage:gs@1")
    robot.link.send(GS)
    raw = robot.link.read_for(0.4)
    items = PacketDecoder().feed(raw)
    assert items[0] == DecodeFault("garbage", GARBAGE)
    assert isinstance(items[1], Packet)
    assert items[1].type == Code.GS
    assert len(items) == 2


def test_nak_replaces_the_reply_and_the_request_is_not_executed(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "50", "--fault", "nak:pr@1")
    robot.link.request(m.Sp(200, 450, 450))
    robot.link.send(m.encode_request(m.Pr(394, 0, 0)))
    assert robot.link.read_for(0.4) == NAK_BYTES
    truth = robot.truth()
    assert truth.motion_log == ()
    assert not truth.moving
    assert truth.encoder_x == 0


def test_wrong_type_reply_is_well_framed_but_answers_nothing(pty_robot: Any) -> None:
    robot = pty_robot("--fault", "wrong-type:gs@1")
    reply = robot.link.request(m.Gs())
    assert reply.type == WRONG_TYPE
    assert len(reply.payload) == GS_REPLY_LEN - 6
    with pytest.raises(UnexpectedReplyError):
        decode_reply(reply, m.Gs(), N150_MASK)


def test_stuck_motion_reports_moving_until_stopped(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "50", "--fault", "stuck")
    robot.link.request(m.Sp(200, 450, 450))
    robot.link.request(m.Pr(100, 0, 0))
    t = time.monotonic()
    reply = decode_reply(
        robot.link.request(m.Ws(True, True, True, 1)), m.Ws(True, True, True, 1), N150_MASK
    )
    assert time.monotonic() - t >= 0.95  # ws ran into its timeout
    assert reply.motor_status & 1  # type: ignore[union-attr]
    assert reply.x == 100  # type: ignore[union-attr]
    stopped = decode_reply(robot.link.request(m.St()), m.St(), N150_MASK)
    assert stopped.motor_status == 0  # type: ignore[union-attr]


def test_disconnect_cuts_the_line_mid_motion(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "5", "--fault", "disconnect:pr@1")
    robot.link.request(m.Sp(200, 450, 450))
    robot.link.request(m.Pr(394, 0, 0))
    robot.port.timeout = 2.0
    with pytest.raises(serial.SerialException):
        robot.port.read(1000)  # the reply came already; nothing more until the cut
    truth = robot.truth()
    assert truth.disconnected
    assert 0 < truth.encoder_x < 394 or truth.moving  # cut while the robot was moving
    deadline = time.monotonic() + 3.0
    while robot.truth().moving and time.monotonic() < deadline:
        time.sleep(0.02)
    assert robot.truth().encoder_x == 394  # the robot finished on its own and stopped


def test_watchdog_fault_stops_the_robot_short(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "20", "--fault", "watchdog:pr@1")
    robot.link.request(m.Sp(200, 450, 450))
    robot.link.request(m.Pr(394, 0, 0))
    robot.link.request(m.Ws(True, True, True, 5))
    x = decode_s16(robot.link.request(m.GetRc()).payload[:2])
    # fired at half the planned time, i.e. half way (symmetric trapezoid), then braked
    # from full speed 200 at 300: 197 + 200**2 / 600
    assert x == round(197 + 200**2 / 600)
    assert any("watchdog fault" in line for line in robot.truth().faults_fired)


def test_disconnect_in_process_raises_serial_exception(fake_port: Any) -> None:
    port = fake_port("time_scale=5&fault=disconnect")
    port.write(m.encode_request(m.Sp(200, 450, 450)))
    port.write(m.encode_request(m.Pr(394, 0, 0)))
    port.timeout = 2.0
    with pytest.raises(serial.SerialException):
        port.read(1000)
    assert port.truth().disconnected


def test_noise_takes_the_line_over_with_nmea_sentences(pty_robot: Any) -> None:
    robot = pty_robot("--fault", "noise:gs@2")
    robot.link.request(m.Gs())  # first gs: answered
    robot.link.send(GS)
    chunks = _timed_chunks(robot, 1.2)
    raw = b"".join(data for _, data in chunks)
    assert 0x01 not in raw  # nothing that could start a packet: no reply ever again
    assert raw.startswith(NOISE_SENTENCES[0])
    sentences = raw.count(b"\r\n")
    assert abs(sentences - 1.2 / NOISE_PERIOD_S) <= 2, sentences
    gaps = [b[0] - a[0] for a, b in itertools.pairwise(chunks)]
    assert max(gaps) < 1.0  # never a silence that would end a reply by itself
    assert "noise on gs" in robot.truth().faults_fired
