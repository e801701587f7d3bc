"""The serial line between the host and the fake Create 2, bit by bit (8N1).

A byte is a start bit (0), eight data bits (least significant first) and a
stop bit (1); the line idles at 1. A UART that reads at another rate than the
sender's samples those levels at its own bit times: it finds a start bit on the
first low level, samples the eight data bits and the stop bit in the middle of
its own bit periods, and flags a framing error when the stop bit is low. That
is what a real Create 2 and its host see when their rates differ (the OI
specification, p.4: both ends must agree on the rate; a Baud command, p.9,
changes the robot's). Pure functions, no I/O.
"""

from __future__ import annotations

BITS_PER_BYTE = 10
"""Start bit, eight data bits, stop bit (8N1)."""


def _level(data: bytes, bit_index: int) -> int:
    """The line's level during sent bit ``bit_index`` (1 outside the data)."""
    if bit_index < 0 or bit_index >= len(data) * BITS_PER_BYTE:
        return 1
    byte, bit = divmod(bit_index, BITS_PER_BYTE)
    if bit == 0:
        return 0
    if bit == BITS_PER_BYTE - 1:
        return 1
    return (data[byte] >> (bit - 1)) & 1


def reframe(data: bytes, sent_baud: int, read_baud: int) -> list[tuple[int, bool]]:
    """What a UART at ``read_baud`` frames from ``data`` sent back to back at
    ``sent_baud``: ``(byte, stop bit seen)`` in order; at equal rates, ``data``
    itself with every stop bit seen."""
    if sent_baud == read_baud:
        return [(b, True) for b in data]
    sent_bit = 1.0 / sent_baud
    read_bit = 1.0 / read_baud
    total_bits = len(data) * BITS_PER_BYTE

    def level_at(t: float) -> int:
        return _level(data, int(t / sent_bit))

    out: list[tuple[int, bool]] = []
    t = 0.0
    while True:
        # the first low level at or after t (levels change only at sent bit edges)
        k = int(t / sent_bit)
        while k < total_bits and _level(data, k) == 1:
            k += 1
        if k >= total_bits:
            return out
        start = max(t, k * sent_bit)
        if level_at(start + 0.5 * read_bit) != 0:  # a glitch, not a start bit
            t = start + 0.5 * read_bit
            continue
        value = 0
        for i in range(8):
            value |= level_at(start + (1.5 + i) * read_bit) << i
        stop_ok = level_at(start + 9.5 * read_bit) == 1
        out.append((value, stop_ok))
        t = start + 9.5 * read_bit


def carried(data: bytes, sent_baud: int, read_baud: int) -> bytes:
    """Every byte the reader frames, framing errors included (a host's raw tty)."""
    return bytes(b for b, _ in reframe(data, sent_baud, read_baud))


def accepted(data: bytes, sent_baud: int, read_baud: int) -> tuple[bytes, int]:
    """The bytes the reader frames without a framing error (the OI drops the
    others), and how many it dropped."""
    framed = reframe(data, sent_baud, read_baud)
    good = bytes(b for b, ok in framed if ok)
    return good, len(framed) - len(good)
