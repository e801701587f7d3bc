"""The codec reproduces every golden vector, both ways."""

from __future__ import annotations

from typing import Any

import pytest

from odohil.errors import NakError
from odohil.protocol.nomad import messages, replies
from odohil.protocol.nomad.codes import Code
from odohil.protocol.nomad.framing import DecodeFault, Packet, PacketDecoder, parse_packet
from odohil.protocol.nomad.messages import decode_request, encode_request
from odohil.protocol.nomad.state import N150_MASK, RobotState

from .golden import golden


def _request(vector: dict[str, Any]) -> messages.Request:
    fields = dict(vector["fields"])
    if vector["message"] == "Ct":
        return messages.Ct(bytes.fromhex(fields["mask_hex"]))
    if "order" in fields:
        fields["order"] = tuple(fields["order"])
    request: messages.Request = getattr(messages, vector["message"])(**fields)
    return request


def _reply(vector: dict[str, Any]) -> replies.Reply:
    fields = dict(vector["fields"])
    if "sonar" in fields:
        fields["sonar"] = tuple(fields["sonar"])
    if vector["message"] == "RobotState":
        return RobotState(**fields)
    reply: replies.Reply = getattr(replies, vector["message"])(**fields)
    return reply


REQUESTS = golden("request")
REPLIES = [v for v in golden("reply") if v["message"] != "NAK"]
NAKS = [v for v in golden("reply") if v["message"] == "NAK"]
INVALID = golden("invalid")


def test_every_facts_document_example_is_a_vector() -> None:
    facts = [v for v in REQUESTS + REPLIES + NAKS if v["source"].startswith("facts")]
    assert len(facts) == 17


@pytest.mark.parametrize("vector", REQUESTS, ids=lambda v: v["name"])
def test_request_encodes_to_golden_bytes(vector: dict[str, Any]) -> None:
    assert encode_request(_request(vector)).hex(" ").upper() == vector["hex"]


@pytest.mark.parametrize("vector", REQUESTS, ids=lambda v: v["name"])
def test_golden_bytes_decode_to_request(vector: dict[str, Any]) -> None:
    packet = parse_packet(bytes.fromhex(vector["hex"]))
    assert packet.type == vector["code"]
    assert decode_request(packet) == _request(vector)


@pytest.mark.parametrize("vector", REPLIES, ids=lambda v: v["name"])
def test_golden_reply_decodes(vector: dict[str, Any]) -> None:
    packet = parse_packet(bytes.fromhex(vector["hex"]))
    request = _request({"message": vector["request"], "fields": {}} | _blank(vector))
    assert replies.decode_reply(packet, request, N150_MASK) == _reply(vector)


def _blank(vector: dict[str, Any]) -> dict[str, Any]:
    # A request of the right type; its fields do not matter for decoding.
    defaults: dict[str, dict[str, Any]] = {
        "Pr": {"trans": 0, "steer": 0, "turret": 0},
        "Ws": {"trans": True, "steer": True, "turret": True, "timeout_s": 1},
    }
    return {"fields": defaults.get(vector["request"], {})}


@pytest.mark.parametrize("vector", REPLIES, ids=lambda v: v["name"])
def test_reply_encodes_to_golden_bytes(vector: dict[str, Any]) -> None:
    reply = _reply(vector)
    if isinstance(reply, RobotState):
        data = replies.encode_state_reply(vector["code"], reply, N150_MASK)
    else:
        encoder = {
            replies.RcReply: replies.encode_rc_reply,
            replies.RvReply: replies.encode_rv_reply,
            replies.RaReply: replies.encode_ra_reply,
            replies.SnReply: replies.encode_sn_reply,
            replies.BpReply: replies.encode_bp_reply,
        }[type(reply)]
        data = encoder(reply)  # type: ignore[operator]
    assert data.hex(" ").upper() == vector["hex"]


@pytest.mark.parametrize("vector", NAKS, ids=lambda v: v["name"])
def test_nak_vector(vector: dict[str, Any]) -> None:
    assert replies.NAK_BYTES.hex(" ").upper() == vector["hex"]
    with pytest.raises(NakError):
        replies.decode_reply(parse_packet(replies.NAK_BYTES), Code.GS, N150_MASK)


def test_n150_state_packet_is_48_bytes_on_the_wire() -> None:
    vector = next(v for v in REPLIES if v["source"].startswith("facts") and v["code"] == 7)
    assert len(bytes.fromhex(vector["hex"])) == 48
    assert N150_MASK.payload_size == 42


@pytest.mark.parametrize("vector", INVALID, ids=lambda v: v["name"])
def test_invalid_frame_gives_fault_first(vector: dict[str, Any]) -> None:
    events = PacketDecoder().feed(bytes.fromhex(vector["hex"]))
    assert events, "the decoder must report the bad frame"
    assert all(isinstance(e, DecodeFault) for e in events)
    first = events[0]
    assert isinstance(first, DecodeFault)
    assert first.kind == vector["fault"]


def test_packet_after_invalid_frame_is_recovered() -> None:
    good = bytes.fromhex(REQUESTS[0]["hex"])
    for vector in INVALID:
        events = PacketDecoder().feed(bytes.fromhex(vector["hex"]) + good)
        packets = [e for e in events if isinstance(e, Packet)]
        assert packets == [parse_packet(good)], vector["name"]
