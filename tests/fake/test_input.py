"""How the fake robot reads its input: any chunking, garbage, NAK, 1 s silence rule (C3)."""

from __future__ import annotations

import time
from typing import Any

from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.codes import Code
from odohil.protocol.nomad.framing import encode_packet
from odohil.protocol.nomad.replies import NAK_BYTES


def test_requests_in_any_chunking_and_after_garbage_are_answered(pty_robot: Any) -> None:
    robot = pty_robot()
    packet = m.encode_request(m.Dp(1234, -77))
    robot.link.send(b"\x5c\x00\xff")  # garbage: skipped silently
    for byte in packet:
        robot.port.write(bytes([byte]))
        time.sleep(0.002)
    reply = robot.link.read_packet()
    assert reply is not None
    assert reply.type == Code.DP
    rc = robot.link.request(m.GetRc())
    assert rc.payload[:4] == bytes.fromhex("D2 04 4D 80")  # 1234, -77 sign-magnitude


def test_two_requests_in_one_write_get_two_replies(pty_robot: Any) -> None:
    robot = pty_robot()
    robot.link.send(m.encode_request(m.Gs()) + m.encode_request(m.GetRc()))
    first = robot.link.read_packet()
    second = robot.link.read_packet()
    assert first is not None
    assert first.type == Code.GS
    assert second is not None
    assert second.type == Code.GET_RC


def test_unknown_code_and_wrong_length_are_answered_with_nak(pty_robot: Any) -> None:
    robot = pty_robot()
    for bad in (encode_packet(99, b""), encode_packet(Code.PR, b"\x01\x02")):
        robot.link.send(bad)
        assert robot.link.read_for(0.3) == NAK_BYTES


def test_a_partial_packet_is_dropped_after_one_second_of_silence(pty_robot: Any) -> None:
    robot = pty_robot()
    gs = m.encode_request(m.Gs())
    robot.link.send(gs[:3])
    time.sleep(1.3)
    # the stale start would otherwise swallow this gs as its TYPE and payload
    robot.link.send(gs)
    reply = robot.link.read_packet()
    assert reply is not None
    assert reply.type == Code.GS


def test_a_packet_completed_within_one_second_is_kept(pty_robot: Any) -> None:
    robot = pty_robot()
    gs = m.encode_request(m.Gs())
    robot.link.send(gs[:3])
    time.sleep(0.4)
    robot.port.write(gs[3:])
    reply = robot.link.read_packet()
    assert reply is not None
    assert reply.type == Code.GS
