"""A raw byte link to the fake robot: requests built by the protocol layer, no driver."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import serial

from odohil.protocol.nomad.framing import DecodeFault, Packet, PacketDecoder
from odohil.protocol.nomad.messages import Request, encode_request


class RawLink:
    """Writes request bytes to a pyserial port and reads whole packets back."""

    def __init__(self, port: serial.Serial) -> None:
        self.port = port

    def send(self, data: bytes) -> None:
        """Drain pending input (as Ndirect does), then write ``data``."""
        self.port.reset_input_buffer()
        self.port.write(data)

    def read_for(self, seconds: float) -> bytes:
        """Every byte that arrives within ``seconds``."""
        out = bytearray()
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            self.port.timeout = min(left, 0.05)
            out += self.port.read(4096)
        return bytes(out)

    def read_packet(self, timeout: float = 2.0) -> Packet | None:
        """The first whole packet within ``timeout`` s (None if none); faults are ignored."""
        decoder = PacketDecoder()
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            self.port.timeout = min(left, 0.05)
            for item in decoder.feed(self.port.read(1)):
                if not isinstance(item, DecodeFault):
                    return item
        return None

    def read_until_packet(self, timeout: float = 2.0) -> tuple[bytes, float]:
        """Raw bytes up to and including the first whole packet, and the wall time it ended."""
        decoder = PacketDecoder()
        raw = bytearray()
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            self.port.timeout = min(left, 0.05)
            byte = self.port.read(1)
            raw += byte
            if any(isinstance(i, Packet) for i in decoder.feed(byte)):
                return bytes(raw), time.monotonic()
        return bytes(raw), time.monotonic()

    def request(self, req: Request, timeout: float = 2.0) -> Packet:
        """Send ``req`` and return its reply packet (AssertionError if none)."""
        self.send(encode_request(req))
        packet = self.read_packet(timeout)
        assert packet is not None, f"no reply to {req}"
        return packet


GOLDEN = Path(__file__).resolve().parents[2] / "protocols" / "nomad" / "golden_vectors.json"


def golden(direction: str) -> list[dict[str, Any]]:
    """The golden vectors of one direction: request, reply or invalid."""
    vectors: list[dict[str, Any]] = json.loads(GOLDEN.read_text())["vectors"]
    return [v for v in vectors if v["direction"] == direction]
