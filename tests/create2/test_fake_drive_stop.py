"""Issue 31: the fake Create 2 never dies on a Drive (radius 0 included, CHOICE
C30), and packets 19 and 20 each count since they were themselves last read
(C11). Driven through the in-process ``fakecreate2://`` port (the fake's URL
handler), raw OI bytes in."""

from __future__ import annotations

import time

import serial
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fakes
from odohil.protocol.create2.numbers import decode_s16, encode_s16

fakes.register_url_handlers()

URL = "fakecreate2://?seed=1&mode_change_ms=0&time_scale=20"
START_SAFE = bytes((0x80, 0x83))


def _open(url: str = URL) -> serial.Serial:
    port = serial.serial_for_url(url, baudrate=115200, timeout=0.5)
    port.write(START_SAFE)
    return port


def _ask(port: serial.Serial, packet: int) -> int:
    port.write(bytes((0x8E, packet)))
    reply = port.read(2)
    assert len(reply) == 2
    return decode_s16(reply)


def test_drive_radius_0_stops_and_drives_straight() -> None:
    with _open() as port:
        port.write(bytes.fromhex("89 00 00 00 00"))  # the common stop: velocity 0, radius 0
        assert port.truth().moving is False
        port.write(bytes.fromhex("89 00 C8 00 00"))  # 200 mm/s, radius 0: straight (C30)
        truth = port.truth()
        assert (truth.right_mm_s, truth.left_mm_s) == (200.0, 200.0)
        port.write(bytes.fromhex("89 00 00 00 00"))
        assert port.truth().moving is False
        port.write(bytes((0x8E, 35)))
        assert port.read(1) == b"\x02"  # still Safe, still answering


_SHARED: dict[str, serial.Serial] = {}


def _shared_port() -> serial.Serial:
    if "port" not in _SHARED:
        _SHARED["port"] = _open("fakecreate2://?seed=2&mode_change_ms=0&max_gap_ms=1")
    return _SHARED["port"]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(-32768, 32767), st.integers(-32768, 32767))
def test_no_drive_kills_the_fake(velocity: int, radius: int) -> None:
    port = _shared_port()
    port.write(b"\x89" + encode_s16(velocity) + encode_s16(radius))
    truth = port.truth()
    assert abs(truth.right_mm_s) <= 500.0
    assert abs(truth.left_mm_s) <= 500.0
    port.write(bytes((0x80, 0x83)))  # Passive (wheels stopped), Safe


NOT_BAUD_OR_POWER = st.integers(0, 255).filter(lambda b: b not in (0x81, 0x85))
"""Any byte but Baud (the host would have to follow the new rate) and Power
(asleep until a hook wakes it): both are obeyed, not deaths."""


@settings(max_examples=60, deadline=None)
@given(st.lists(NOT_BAUD_OR_POWER, max_size=48).map(bytes))
def test_no_byte_sequence_kills_the_fake(noise: bytes) -> None:
    port = _shared_port()
    port.write(noise)
    # zeros complete any pending command, lists included (a Song of 255 notes
    # has 512 data bytes); then Start, Safe
    port.write(bytes(520) + START_SAFE)
    truth = port.truth()
    assert not truth.disconnected
    assert truth.mode == 2
    port.reset_input_buffer()


def test_reading_angle_does_not_zero_distance() -> None:
    # after 1 s straight at 100 mm/s, angle then distance: the distance is the
    # motion since 19 was itself last read (C11), not 0
    with _open() as port:
        _ask(port, 19), _ask(port, 20)
        port.write(bytes.fromhex("91 00 64 00 64"))
        time.sleep(0.05)  # 1 s simulated at time scale 20
        port.write(bytes.fromhex("91 00 00 00 00"))
        travel_mm = port.truth().travel_m * 1000.0
        assert travel_mm > 50.0
        assert _ask(port, 20) == 0
        distance = _ask(port, 19)
        assert abs(distance - travel_mm) < 1.0
        assert _ask(port, 19) == 0  # read: counted from here on
        # and the other way round: reading 19 leaves 20's count alone
        port.write(bytes.fromhex("91 00 64 FF 9C"))  # spin CCW
        time.sleep(0.02)
        port.write(bytes.fromhex("91 00 00 00 00"))
        assert _ask(port, 19) == 0
        assert _ask(port, 20) > 5
