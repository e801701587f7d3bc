"""Property tests: round trips of every message, state packets, and a stream
decoder that never raises, never hangs and recovers packets after garbage."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odohil.errors import ParameterError, UnexpectedReplyError
from odohil.protocol.nomad import numbers
from odohil.protocol.nomad.framing import (
    MAX_LEN,
    DecodeFault,
    Packet,
    PacketDecoder,
    encode_packet,
    parse_packet,
)
from odohil.protocol.nomad.messages import Request, decode_request, encode_request
from odohil.protocol.nomad.state import (
    N150_MASK,
    StateMask,
    decode_state_payload,
    encode_state_payload,
    state_timestamp_ms,
)

from .strategies import (
    garbage_without_start,
    masks,
    packets,
    requests,
    state_for_mask,
)

settings.register_profile("protocol", max_examples=150, deadline=None)
settings.load_profile("protocol")


@given(st.integers(-0x7FFF, 0x7FFF))
def test_s16_round_trip_and_sign_bit(value: int) -> None:
    data = numbers.encode_s16(value)
    assert numbers.decode_s16(data) == value
    assert bool(data[1] & 0x80) == (value < 0)
    assert (data[0] | (data[1] & 0x7F) << 8) == abs(value)


@given(st.integers(-0x7FFF_FFFF, 0x7FFF_FFFF))
def test_s32_round_trip(value: int) -> None:
    data = numbers.encode_s32(value)
    assert numbers.decode_s32(data) == value
    assert bool(data[3] & 0x80) == (value < 0)


@given(st.integers(0, 0xFFFF), st.integers(0, 0xFFFF_FFFF))
def test_unsigned_round_trips(u16: int, u32: int) -> None:
    assert numbers.decode_u16(numbers.encode_u16(u16)) == u16
    assert numbers.decode_u32(numbers.encode_u32(u32)) == u32


@pytest.mark.parametrize(
    ("encode", "value"),
    [
        (numbers.encode_s16, 0x8000),
        (numbers.encode_s16, -0x8000),
        (numbers.encode_u16, -1),
        (numbers.encode_u16, 0x10000),
        (numbers.encode_s32, 0x8000_0000),
        (numbers.encode_u32, -1),
        (numbers.encode_u8, 256),
    ],
)
def test_out_of_range_raises(encode: object, value: int) -> None:
    with pytest.raises(ParameterError):
        encode(value)  # type: ignore[operator]


def test_minus_zero_decodes_to_zero() -> None:
    assert numbers.decode_s16(b"\x00\x80") == 0


@given(requests)
def test_every_request_round_trips(request: Request) -> None:
    wire = encode_request(request)
    assert len(wire) == wire[1] + 4
    assert decode_request(parse_packet(wire)) == request


@given(packets)
def test_packet_round_trip(packet: Packet) -> None:
    assert parse_packet(encode_packet(packet.type, packet.payload)) == packet


@given(st.data(), masks)
def test_state_payload_round_trips_for_any_mask(data: st.DataObject, mask: StateMask) -> None:
    state = data.draw(state_for_mask(mask))
    payload = encode_state_payload(state, mask)
    assert len(payload) == mask.payload_size
    assert decode_state_payload(payload, mask) == state
    assert state_timestamp_ms(payload, mask) == state.timestamp_ms
    assert StateMask.from_ct(mask.to_ct()) == mask


@given(st.binary(min_size=38, max_size=46))
def test_a_payloads_timestamp_alone_is_the_decoded_ones_or_the_same_refusal(
    payload: bytes,
) -> None:
    if len(payload) != N150_MASK.payload_size:
        with pytest.raises(UnexpectedReplyError) as decoding:
            decode_state_payload(payload, N150_MASK)
        with pytest.raises(UnexpectedReplyError) as reading:
            state_timestamp_ms(payload, N150_MASK)
        assert str(reading.value) == str(decoding.value)
    else:
        decoded = decode_state_payload(payload, N150_MASK)
        assert state_timestamp_ms(payload, N150_MASK) == decoded.timestamp_ms


@given(st.data())
def test_n150_state_round_trip(data: st.DataObject) -> None:
    state = data.draw(state_for_mask(N150_MASK))
    assert decode_state_payload(encode_state_payload(state, N150_MASK), N150_MASK) == state


def _chunks(data: bytes, cuts: list[int]) -> list[bytes]:
    points = sorted({c % (len(data) + 1) for c in cuts} | {0, len(data)})
    return [data[a:b] for a, b in itertools.pairwise(points)]


def _feed_all(stream: bytes, cuts: list[int]) -> tuple[list[Packet | DecodeFault], PacketDecoder]:
    decoder = PacketDecoder()
    events: list[Packet | DecodeFault] = []
    for chunk in _chunks(stream, cuts):
        events += decoder.feed(chunk)
        assert decoder.pending < MAX_LEN + 4
    return events, decoder


def _accounted(events: list[Packet | DecodeFault]) -> int:
    return sum(len(e.payload) + 6 if isinstance(e, Packet) else len(e.data) for e in events)


cuts = st.lists(st.integers(0, 10_000), max_size=12)


@given(st.binary(max_size=600), cuts)
def test_arbitrary_bytes_never_raise_and_every_byte_is_accounted(
    stream: bytes, cut: list[int]
) -> None:
    events, decoder = _feed_all(stream, cut)
    assert _accounted(events) + decoder.pending == len(stream)
    pending = decoder.pending
    assert decoder.reset() == stream[len(stream) - pending :]


@given(st.lists(st.tuples(garbage_without_start, packets), max_size=8), garbage_without_start, cuts)
def test_packets_after_garbage_are_all_recovered(
    pairs: list[tuple[bytes, Packet]], tail: bytes, cut: list[int]
) -> None:
    stream = b"".join(g + encode_packet(p.type, p.payload) for g, p in pairs) + tail
    events, decoder = _feed_all(stream, cut)
    assert [e for e in events if isinstance(e, Packet)] == [p for _, p in pairs]
    faults = [e for e in events if isinstance(e, DecodeFault)]
    assert all(f.kind == "garbage" for f in faults)
    assert b"".join(f.data for f in faults) == b"".join(g for g, _ in pairs) + tail
    assert decoder.pending == 0


@given(
    st.lists(packets, min_size=1, max_size=6),
    st.integers(0, 10_000),
    st.integers(1, 255),
    cuts,
)
def test_corrupted_stream_gives_typed_events_only(
    items: list[Packet], where: int, flip: int, cut: list[int]
) -> None:
    stream = bytearray(b"".join(encode_packet(p.type, p.payload) for p in items))
    stream[where % len(stream)] ^= flip
    events, decoder = _feed_all(bytes(stream), cut)
    assert all(isinstance(e, Packet | DecodeFault) for e in events)
    assert _accounted(events) + decoder.pending == len(stream)


@given(st.binary(min_size=1, max_size=60), packets)
def test_reset_drops_a_partial_packet(partial: bytes, packet: Packet) -> None:
    decoder = PacketDecoder()
    decoder.feed(b"\x01" + bytes([MAX_LEN, 0]) + partial[: MAX_LEN - 1])
    decoder.reset()
    assert decoder.pending == 0
    assert decoder.feed(encode_packet(packet.type, packet.payload)) == [packet]


@given(packets, st.integers(0, 10_000))
def test_missing_counts_the_bytes_still_needed(packet: Packet, cut: int) -> None:
    wire = encode_packet(packet.type, packet.payload)
    prefix = wire[: cut % len(wire)]
    decoder = PacketDecoder()
    assert decoder.feed(prefix) == []
    assert decoder.missing == (len(wire) - len(prefix) if len(prefix) >= 3 else 1)
