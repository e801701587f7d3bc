"""OI opcodes, the OI modes and the data bytes each command takes (facts §3, §4)."""

from __future__ import annotations

from enum import IntEnum


class Opcode(IntEnum):
    """Command opcodes of the Create 2 OI (p.8-22 of the OI specification)."""

    RESET = 7
    START = 128
    BAUD = 129
    CONTROL = 130
    SAFE = 131
    FULL = 132
    POWER = 133
    SPOT = 134
    CLEAN = 135
    MAX_CLEAN = 136
    DRIVE = 137
    MOTORS = 138
    LEDS = 139
    SONG = 140
    PLAY = 141
    SENSORS = 142
    SEEK_DOCK = 143
    MOTORS_PWM = 144
    DRIVE_DIRECT = 145
    DRIVE_PWM = 146
    STREAM = 148
    QUERY_LIST = 149
    PAUSE_RESUME = 150
    SCHEDULING_LEDS = 162
    DIGIT_LEDS_RAW = 163
    BUTTONS = 165
    DIGIT_LEDS_ASCII = 164
    SCHEDULE = 167
    SET_DAY_TIME = 168
    STOP = 173


class Mode(IntEnum):
    """OI modes as packet 35 reports them (p.29)."""

    OFF = 0
    PASSIVE = 1
    SAFE = 2
    FULL = 3


FIXED_DATA_BYTES: dict[int, int] = {
    Opcode.RESET: 0,
    Opcode.START: 0,
    Opcode.BAUD: 1,
    Opcode.CONTROL: 0,
    Opcode.SAFE: 0,
    Opcode.FULL: 0,
    Opcode.POWER: 0,
    Opcode.SPOT: 0,
    Opcode.CLEAN: 0,
    Opcode.MAX_CLEAN: 0,
    Opcode.DRIVE: 4,
    Opcode.MOTORS: 1,
    Opcode.LEDS: 3,
    Opcode.PLAY: 1,
    Opcode.SENSORS: 1,
    Opcode.SEEK_DOCK: 0,
    Opcode.MOTORS_PWM: 3,
    Opcode.DRIVE_DIRECT: 4,
    Opcode.DRIVE_PWM: 4,
    Opcode.PAUSE_RESUME: 1,
    Opcode.SCHEDULING_LEDS: 2,
    Opcode.DIGIT_LEDS_RAW: 4,
    Opcode.DIGIT_LEDS_ASCII: 4,
    Opcode.BUTTONS: 1,
    Opcode.SCHEDULE: 15,
    Opcode.SET_DAY_TIME: 3,
    Opcode.STOP: 0,
}
"""Data bytes after the opcode of every command of fixed length."""

BAUD_RATES: tuple[int, ...] = (
    300,
    600,
    1200,
    2400,
    4800,
    9600,
    14400,
    19200,
    28800,
    38400,
    57600,
    115200,
)
"""Line rate of each Baud code 0..11 (p.9)."""

DEFAULT_BAUD = 115200
"""The Create 2's power-on line rate (p.4; CHOICE C1)."""


def data_bytes(opcode: int, head: bytes) -> int | None:
    """How many data bytes follow ``opcode``, given the data bytes ``head``
    received so far (the list commands need their first byte(s)).

    Returns None while ``head`` is too short to tell, and -1 for an opcode the
    OI does not have (the fake skips it: CHOICE C10).
    """
    if opcode in FIXED_DATA_BYTES:
        return FIXED_DATA_BYTES[opcode]
    if opcode in (Opcode.STREAM, Opcode.QUERY_LIST):
        return None if not head else 1 + head[0]
    if opcode == Opcode.SONG:
        return None if len(head) < 2 else 2 + 2 * head[1]
    return -1
