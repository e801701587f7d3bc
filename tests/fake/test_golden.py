"""The golden vectors of protocols/nomad/golden_vectors.json hold in the fake robot (over a pty)."""

from __future__ import annotations

import time
from typing import Any

from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.codes import STATE_REPLY_CODES, Code
from odohil.protocol.nomad.framing import Packet, encode_packet, parse_packet
from odohil.protocol.nomad.replies import NAK_BYTES, decode_reply
from odohil.protocol.nomad.state import N150_MASK

from .link import golden

MOTION_LOGGED = {"Pr", "Pa", "Vm", "Mv", "Zr", "St", "Lp"}
STATE_TAIL = 7  # motor status, u32 timestamp, 2 voltage bytes


def _b(hex_text: str) -> bytes:
    return bytes.fromhex(hex_text)


def _stop_and_wait(robot: Any) -> None:
    robot.link.request(m.St())
    deadline = time.monotonic() + 3.0
    while robot.truth().moving and time.monotonic() < deadline:
        time.sleep(0.01)


def test_every_golden_request_is_understood_as_documented(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "1000")
    for vector in golden("request"):
        _stop_and_wait(robot)
        before = len(robot.truth().motion_log)
        robot.link.send(_b(vector["hex"]))
        reply = robot.link.read_packet(timeout=3.0)
        assert reply is not None, vector["name"]
        assert reply.type == vector["code"], vector["name"]  # C2: reply type = request code
        decode_reply(reply, Code(vector["code"]), N150_MASK)  # well-formed for the request
        if vector["message"] in MOTION_LOGGED:
            log = robot.truth().motion_log
            assert len(log) == before + 1, vector["name"]
            record = log[-1]
            assert record.command == Code(vector["code"]).name.lower()
            assert record.args == tuple(int(v) for v in vector["fields"].values())


def test_get_rc_reply_matches_the_documented_bytes(pty_robot: Any) -> None:
    robot = pty_robot()
    robot.link.request(m.Dp(100, -20))
    robot.link.request(m.Da(900, 900))
    vector = next(v for v in golden("reply") if v["message"] == "RcReply")
    robot.link.send(m.encode_request(m.GetRc()))
    raw, _ = robot.link.read_until_packet()
    assert raw == _b(vector["hex"])


def _same_but_tail(actual: bytes, expected: bytes) -> None:
    """Equal except the timestamp and voltage bytes; the checksum must still be right."""
    parse_packet(actual)  # start, LEN, checksum and end byte are valid
    assert len(actual) == len(expected)
    keep = slice(0, len(expected) - 2 - STATE_TAIL + 1)  # up to and including motor status
    assert actual[keep] == expected[keep]


def test_state_replies_match_the_documented_bytes(pty_robot: Any) -> None:
    robot = pty_robot()
    by_name = {v["name"]: v for v in golden("reply")}
    # facts §5 example: x=100, y=-20, steer=turret=900, everything else 0
    robot.link.request(m.Dp(100, -20))
    robot.link.request(m.Da(900, 900))
    gs_vector = by_name["N150 state reply to gs x=100 y=-20 steer=turret=900"]
    reply = robot.link.request(m.Gs())
    actual = Packet(reply.type, reply.payload)
    sonar_free = bytes(16) + actual.payload[16:]  # the fake's sonars read 255 ("no echo")
    assert actual.payload[:16] == bytes([255] * 16)
    assert actual.payload[-2:] == bytes([230, 230])  # C12 voltage bytes
    _same_but_tail(encode_packet(actual.type, sonar_free), _b(gs_vector["hex"]))
    ws_vector = by_name["N150 state reply to ws, stopped"]
    robot.link.request(m.Dp(10, -10))
    robot.link.request(m.Da(0, 0))
    reply = robot.link.request(m.Ws(True, True, True, 0))
    sonar_free = bytes(16) + reply.payload[16:]
    _same_but_tail(encode_packet(reply.type, sonar_free), _b(ws_vector["hex"]))


def test_velocity_and_acceleration_replies_match_the_documented_bytes(pty_robot: Any) -> None:
    robot = pty_robot("--time-scale", "100")
    by_message = {v["message"]: v for v in golden("reply")}
    robot.link.send(m.encode_request(m.GetRa()))  # power-on accelerations are 300
    assert robot.link.read_until_packet()[0] == _b(by_message["RaReply"]["hex"])
    rv = by_message["RvReply"]["fields"]
    robot.link.request(m.Vm(rv["trans"], rv["steer"], rv["turret"]))
    time.sleep(0.05)  # 200/300 s of ramp at 100x: cruising long before this
    robot.link.send(m.encode_request(m.GetRv()))
    assert robot.link.read_until_packet()[0] == _b(by_message["RvReply"]["hex"])


def test_invalid_frames_get_nak_or_silence_as_documented(pty_robot: Any) -> None:
    robot = pty_robot()
    for vector in golden("invalid"):
        robot.link.send(_b(vector["hex"]))
        raw = robot.link.read_for(0.3)
        if vector["fault"] in ("bad_checksum", "bad_end"):
            assert raw == NAK_BYTES, vector["name"]  # C3
        else:
            assert raw == b"", vector["name"]  # not a well-framed packet: skipped
    # the stream is still in sync afterwards
    assert robot.link.request(m.Gs()).type == Code.GS
    assert Code.GS in STATE_REPLY_CODES
