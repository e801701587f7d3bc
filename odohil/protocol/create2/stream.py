"""The stream frame ``[19][N][id][data]...[checksum]`` (facts §6; p.21-22).

N counts the bytes between N and the checksum, ids included; every byte of
the frame, header and checksum included, sums to 0 modulo 256. The byte 19
also occurs inside data, so :class:`StreamDecoder` aligns on 19, checks that
N bytes parse as ids and their data, and confirms with the checksum before it
believes a frame; on any failure it drops that one byte and searches again.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from odohil.protocol.create2.packets import PACKETS, encode_reply, is_valid_id, members

STREAM_HEADER = 19
"""First byte of every stream frame."""
STREAM_PERIOD_S = 0.015
"""The OI sends a frame every 15 ms."""


def checksum(frame_without_checksum: bytes) -> int:
    """The byte that makes the whole frame sum to 0 modulo 256."""
    return -sum(frame_without_checksum) & 0xFF


def body_size(packet_ids: Iterable[int]) -> int:
    """N of a frame streaming ``packet_ids``: one byte per id plus its data."""
    return sum(1 + sum(PACKETS[m].size for m in members(pid)) for pid in packet_ids)


def frame_size(packet_ids: Iterable[int]) -> int:
    """Bytes of a whole frame (header, N, body, checksum)."""
    return body_size(packet_ids) + 3


def encode_frame(packet_ids: Iterable[int], values: Mapping[int, int]) -> bytes:
    """A frame of ``packet_ids`` (groups allowed) with ``values`` of the single
    packets (missing ones read 0)."""
    body = bytearray()
    for pid in packet_ids:
        body.append(pid)
        body += encode_reply((pid,), values)
    head = bytes((STREAM_HEADER, len(body))) + bytes(body)
    return head + bytes((checksum(head),))


@dataclass(frozen=True)
class StreamFrame:
    """One frame that passed every check.

    Attributes:
        ids: the ids in the frame, in order (groups as sent).
        values: value of every single packet in it (groups expanded).
        raw: the frame's bytes.
    """

    ids: tuple[int, ...]
    values: dict[int, int]
    raw: bytes


def parse_body(body: bytes) -> StreamFrame | None:
    """The ids and values of a frame body, or None if it does not parse exactly."""
    ids: list[int] = []
    values: dict[int, int] = {}
    offset = 0
    while offset < len(body):
        pid = body[offset]
        if not is_valid_id(pid):
            return None
        offset += 1
        for member in members(pid):
            spec = PACKETS[member]
            if offset + spec.size > len(body):
                return None
            values[member] = spec.decode(body[offset : offset + spec.size])
            offset += spec.size
        ids.append(pid)
    return StreamFrame(tuple(ids), values, b"")


class StreamDecoder:
    """Splits a byte stream into :class:`StreamFrame` values, resynchronising.

    Args:
        expected_ids: when given, only frames of exactly these ids count
            (a stricter alignment, as libcreate's ``N == expected``).
    """

    def __init__(self, expected_ids: tuple[int, ...] | None = None) -> None:
        self.expected_ids = expected_ids
        self._expected_n = None if expected_ids is None else body_size(expected_ids)
        self._buf = bytearray()
        self.skipped = 0
        """Bytes dropped while searching for a frame (noise, lost alignment)."""

    def feed(self, data: bytes) -> list[StreamFrame]:
        """Add received bytes; return every complete valid frame, in order."""
        self._buf += data
        frames: list[StreamFrame] = []
        while True:
            start = self._buf.find(STREAM_HEADER)
            if start < 0:
                self.skipped += len(self._buf)
                self._buf.clear()
                return frames
            if start:
                self.skipped += start
                del self._buf[:start]
            if len(self._buf) < 2:
                return frames
            n = self._buf[1]
            if self._expected_n is not None and n != self._expected_n:
                # a 19 inside data: do not wait for N bytes that cannot be a frame
                self.skipped += 1
                del self._buf[:1]
                continue
            if len(self._buf) < n + 3:
                return frames
            raw = bytes(self._buf[: n + 3])
            frame = parse_body(raw[2:-1]) if sum(raw) & 0xFF == 0 else None
            if frame is None or (self.expected_ids is not None and frame.ids != self.expected_ids):
                self.skipped += 1
                del self._buf[:1]
                continue
            del self._buf[: n + 3]
            frames.append(StreamFrame(frame.ids, frame.values, raw))

    def clear(self) -> None:
        """Forget any partial frame."""
        self._buf.clear()
