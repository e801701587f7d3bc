"""Property tests of the Create 2 codec: round trips and the encoder wrap."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from odohil.protocol.create2.commands import CommandSplitter, drive, drive_direct, query_list
from odohil.protocol.create2.numbers import (
    decode_s16,
    decode_u16,
    encode_s16,
    encode_u16,
    encoder_delta,
)
from odohil.protocol.create2.packets import GROUPS, PACKETS, decode_reply, encode_reply, members
from odohil.protocol.create2.stream import StreamDecoder, encode_frame

S16 = st.integers(-32768, 32767)
SPEED = st.integers(-500, 500)
IDS = st.sampled_from(sorted(PACKETS) + sorted(GROUPS))


def _value(spec_id: int, draw: st.DrawFn) -> int:
    spec = PACKETS[spec_id]
    if spec.size == 1:
        return draw(st.integers(-128, 127) if spec.signed else st.integers(0, 255))
    return draw(S16 if spec.signed else st.integers(0, 65535))


@st.composite
def id_lists(draw: st.DrawFn) -> tuple[list[int], dict[int, int]]:
    ids = draw(st.lists(IDS, min_size=1, max_size=6))
    values = {m: _value(m, draw) for pid in ids for m in members(pid)}
    return ids, values


@given(S16)
def test_s16_round_trip(value: int) -> None:
    data = encode_s16(value)
    assert decode_s16(data) == value
    assert decode_u16(data) == value % 65536
    assert encode_u16(value % 65536) == data


@given(st.integers(0, 65535), st.integers(-32768, 32767))
def test_encoder_delta_recovers_any_motion_through_the_wrap(start: int, moved: int) -> None:
    end = (start + moved) % 65536
    assert encoder_delta(start, end) == moved
    assert encoder_delta(end, start) == (-moved if moved != -32768 else -32768)


@given(st.lists(st.integers(-32767, 32767), min_size=1, max_size=40), st.integers(0, 65535))
def test_summed_deltas_track_total_motion(steps: list[int], origin: int) -> None:
    counts, total, wire = origin, 0, origin
    for step in steps:
        counts += step
        total += step
        previous, wire = wire, counts % 65536
        total_seen = encoder_delta(previous, wire)
        assert total_seen == step
    assert (origin + total) % 65536 == wire


@given(id_lists())
def test_reply_round_trip(case: tuple[list[int], dict[int, int]]) -> None:
    ids, values = case
    data = encode_reply(ids, values)
    assert decode_reply(ids, data) == values


@given(id_lists(), st.binary(max_size=20))
def test_frame_round_trip_after_noise(case: tuple[list[int], dict[int, int]], noise: bytes) -> None:
    ids, values = case
    frame = encode_frame(ids, values)
    if len(frame) - 3 > 255:
        return
    frames = StreamDecoder(tuple(ids)).feed(noise + frame)
    assert frames[-1].values == values
    assert frames[-1].ids == tuple(ids)


@given(st.lists(st.tuples(SPEED, SPEED), min_size=1, max_size=10))
def test_command_stream_splits_back(pairs: list[tuple[int, int]]) -> None:
    sent = [drive_direct(r, left) for r, left in pairs] + [drive(pairs[0][0], 0x7FFF)]
    sent.append(query_list([43, 44, 100]))
    split = CommandSplitter().feed(b"".join(sent))
    assert [bytes((c.opcode,)) + c.data for c in split] == sent
