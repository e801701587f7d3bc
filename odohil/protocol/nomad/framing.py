"""Packet framing: ``01 LEN(u16) TYPE payload CHK 5C``, and a stream decoder.

LEN counts TYPE through CHK (2 + payload bytes); CHK is the sum of every byte
from the start byte through the last payload byte, mod 256. There is no
escaping, so 0x01 and 0x5C may occur inside a packet.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from odohil.errors import ChecksumError, FramingError, ParameterError

START = 0x01
END = 0x5C
MIN_LEN = 2
MAX_LEN = 255
"""Largest LEN accepted (CHOICE C13): host packets are always shorter than 256
bytes and the biggest state packet odohil decodes (every group but laser,
no position attachments) has LEN 52; anything longer is treated as a
corrupted length, not waited for."""


@dataclass(frozen=True)
class Packet:
    """One well-formed packet: its TYPE byte and payload (LEN - 2 bytes)."""

    type: int
    payload: bytes

    def __post_init__(self) -> None:
        if not 0 <= self.type <= 0xFF:
            raise ParameterError(f"packet type must be a byte, got {self.type}")
        if len(self.payload) + MIN_LEN > MAX_LEN:
            raise ParameterError(f"payload too long: {len(self.payload)} bytes")


FaultKind = Literal["garbage", "bad_checksum", "bad_end", "bad_length"]


@dataclass(frozen=True)
class DecodeFault:
    """Bytes the decoder dropped, and why (an event, not an exception).

    ``garbage``: bytes before a start byte; ``bad_length``: LEN < 2 or above
    :data:`MAX_LEN`; ``bad_end`` / ``bad_checksum``: a complete frame whose
    end byte or checksum is wrong. For the last three, ``data`` holds the
    bytes dropped: the failed start byte up to (not including) the next 0x01.
    """

    kind: FaultKind
    data: bytes


def checksum(data: bytes | bytearray) -> int:
    """Sum of the bytes mod 256."""
    return sum(data) & 0xFF


def encode_packet(type_: int, payload: bytes) -> bytes:
    """The whole packet on the wire for a TYPE byte and payload."""
    packet = Packet(type_, bytes(payload))
    length = len(packet.payload) + MIN_LEN
    body = bytes((START, length & 0xFF, length >> 8, packet.type)) + packet.payload
    return body + bytes((checksum(body), END))


def parse_packet(data: bytes) -> Packet:
    """Exactly one whole packet; raises FramingError or ChecksumError."""
    if len(data) < 3 or data[0] != START:
        raise FramingError(f"not a packet start: {data[:4].hex(' ')}")
    length = data[1] | (data[2] << 8)
    if not MIN_LEN <= length <= MAX_LEN:
        raise FramingError(f"bad length {length}")
    if len(data) != length + 4:
        raise FramingError(f"LEN {length} needs {length + 4} bytes, got {len(data)}")
    if data[-1] != END:
        raise FramingError(f"bad end byte 0x{data[-1]:02X}")
    if checksum(data[: length + 2]) != data[length + 2]:
        raise ChecksumError(
            f"checksum 0x{data[length + 2]:02X}, expected 0x{checksum(data[: length + 2]):02X}"
        )
    return Packet(data[3], bytes(data[4 : length + 2]))


class PacketDecoder:
    """Turns a byte stream, in any chunking, into packets and fault events.

    After a bad frame it resynchronises at the next 0x01 after the failed
    start byte, so a packet hidden behind a corrupted length is still found.
    It never raises on input and never loops without consuming bytes.
    """

    def __init__(self) -> None:
        self._buf = bytearray()

    @property
    def pending(self) -> int:
        """Bytes buffered of a partial packet."""
        return len(self._buf)

    @property
    def missing(self) -> int:
        """Bytes still needed to complete the packet being received (at least 1;
        1 while the length is not known yet). Lets a reader ask for them at once."""
        buf = self._buf
        if len(buf) < 3 or buf[0] != START:
            return 1
        length = buf[1] | (buf[2] << 8)
        if not MIN_LEN <= length <= MAX_LEN:
            return 1
        return max(1, length + 4 - len(buf))

    def reset(self) -> bytes:
        """Drop a partial packet (e.g. after 1 s of silence); returns what was dropped."""
        dropped = bytes(self._buf)
        self._buf.clear()
        return dropped

    def feed(self, data: bytes) -> list[Packet | DecodeFault]:
        """Add bytes; return the packets and faults completed by them, in order."""
        self._buf += data
        out: list[Packet | DecodeFault] = []
        buf = self._buf
        while buf:
            if buf[0] != START:
                nxt = buf.find(START)
                cut = len(buf) if nxt < 0 else nxt
                out.append(DecodeFault("garbage", bytes(buf[:cut])))
                del buf[:cut]
                continue
            if len(buf) < 3:
                break
            length = buf[1] | (buf[2] << 8)
            if not MIN_LEN <= length <= MAX_LEN:
                out.append(self._drop_frame("bad_length"))
                continue
            total = length + 4
            if len(buf) < total:
                break
            if buf[total - 1] != END:
                out.append(self._drop_frame("bad_end"))
                continue
            if checksum(buf[: length + 2]) != buf[length + 2]:
                out.append(self._drop_frame("bad_checksum"))
                continue
            out.append(Packet(buf[3], bytes(buf[4 : length + 2])))
            del buf[:total]
        return out

    def _drop_frame(self, kind: FaultKind) -> DecodeFault:
        nxt = self._buf.find(START, 1)
        cut = len(self._buf) if nxt < 0 else nxt
        fault = DecodeFault(kind, bytes(self._buf[:cut]))
        del self._buf[:cut]
        return fault
