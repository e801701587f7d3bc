"""Builds protocols/nomad/golden_vectors.json by plain byte arithmetic.

Deliberately imports nothing from odohil, so the vectors check the codec
instead of echoing it. Run: python tests/protocol/make_golden_vectors.py
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def sm16(v: int) -> list[int]:
    m = abs(v)
    return [m & 0xFF, (m >> 8) | (0x80 if v < 0 else 0)]


def u16(v: int) -> list[int]:
    return [v & 0xFF, v >> 8]


def u32(v: int) -> list[int]:
    return [(v >> (8 * i)) & 0xFF for i in range(4)]


def pkt(t: int, payload: list[int]) -> list[int]:
    length = len(payload) + 2
    body = [1, length & 255, length >> 8, t, *payload]
    return [*body, sum(body) % 256, 92]


def hx(b: list[int]) -> str:
    return " ".join(f"{x:02X}" for x in b)


V: list[dict[str, Any]] = []


def facts(
    name: str, direction: str, h: str, message: str, fields: dict[str, Any], code: int, **extra: Any
) -> None:
    V.append(
        dict(
            name=name,
            source="facts §3/§5",
            direction=direction,
            hex=h,
            code=code,
            message=message,
            fields=fields,
            **extra,
        )
    )


def ours(
    name: str,
    direction: str,
    b: list[int],
    message: str,
    fields: dict[str, Any],
    code: int,
    **extra: Any,
) -> None:
    V.append(
        dict(
            name=name,
            source="odohil",
            direction=direction,
            hex=hx(b),
            code=code,
            message=message,
            fields=fields,
            **extra,
        )
    )


# --- facts document worked examples, copied verbatim
facts("gs()", "request", "01 02 00 07 0A 5C", "Gs", {}, 7)
facts(
    "pr(100,0,0) forward 10.0 in",
    "request",
    "01 08 00 03 64 00 00 00 00 00 70 5C",
    "Pr",
    {"trans": 100, "steer": 0, "turret": 0},
    3,
)
facts(
    "pr(-100,0,0)",
    "request",
    "01 08 00 03 64 80 00 00 00 00 F0 5C",
    "Pr",
    {"trans": -100, "steer": 0, "turret": 0},
    3,
)
facts(
    "pr(0,900,0) steer +90.0 deg",
    "request",
    "01 08 00 03 00 00 84 03 00 00 93 5C",
    "Pr",
    {"trans": 0, "steer": 900, "turret": 0},
    3,
)
facts(
    "sp(200,450,450)",
    "request",
    "01 08 00 02 C8 00 C2 01 C2 01 59 5C",
    "Sp",
    {"trans": 200, "steer": 450, "turret": 450},
    2,
)
facts(
    "ac(300,300,300)",
    "request",
    "01 08 00 01 2C 01 2C 01 2C 01 91 5C",
    "Ac",
    {"trans": 300, "steer": 300, "turret": 300},
    1,
)
facts(
    "vm(50,0,0)",
    "request",
    "01 08 00 05 32 00 00 00 00 00 40 5C",
    "Vm",
    {"trans": 50, "steer": 0, "turret": 0},
    5,
)
facts(
    "ws(1,1,1,30)",
    "request",
    "01 06 00 1F 01 01 01 1E 47 5C",
    "Ws",
    {"trans": True, "steer": True, "turret": True, "timeout_s": 30},
    31,
)
facts("conf_tm(5)", "request", "01 03 00 12 05 1B 5C", "ConfTm", {"seconds": 5}, 18)
facts("dp(0,0)", "request", "01 06 00 0C 00 00 00 00 13 5C", "Dp", {"x": 0, "y": 0}, 12)
facts("da(0,0)", "request", "01 06 00 1E 00 00 00 00 25 5C", "Da", {"steer": 0, "turret": 0}, 30)
facts("zr()", "request", "01 02 00 0D 10 5C", "Zr", {}, 13)
facts("st()", "request", "01 02 00 09 0C 5C", "St", {}, 9)
facts("lp()", "request", "01 02 00 0A 0D 5C", "Lp", {}, 10)
facts(
    "get_rc reply x=100 y=-20 steer=turret=900",
    "reply",
    "01 0A 00 15 64 00 14 80 84 03 84 03 26 5C",
    "RcReply",
    {"x": 100, "y": -20, "steer": 900, "turret": 900},
    21,
    request="GetRc",
)
facts("NAK", "reply", "01 02 00 08 0B 5C", "NAK", {}, 8, request="Gs")
facts(
    "N150 state reply to gs x=100 y=-20 steer=turret=900",
    "reply",
    hx(
        [1, 0x2C, 0, 7]
        + [0] * 19
        + [0x64, 0, 0x14, 0x80, 0x84, 3, 0x84, 3]
        + [0] * 15
        + [0x3A, 0x5C]
    ),
    "RobotState",
    {"x": 100, "y": -20, "steer": 900, "turret": 900},
    7,
    request="Gs",
    mask="N150",
)
# --- more, built here from the encoding rules
ours(
    "pr(3937,0,0) one metre, rounded",
    "request",
    pkt(3, sm16(3937) + sm16(0) + sm16(0)),
    "Pr",
    {"trans": 3937, "steer": 0, "turret": 0},
    3,
)
ours(
    "pr(0,1800,0) turn 180 deg",
    "request",
    pkt(3, sm16(0) + sm16(1800) + sm16(0)),
    "Pr",
    {"trans": 0, "steer": 1800, "turret": 0},
    3,
)
ours(
    "pr(-32767,32767,-1) extremes",
    "request",
    pkt(3, sm16(-32767) + sm16(32767) + sm16(-1)),
    "Pr",
    {"trans": -32767, "steer": 32767, "turret": -1},
    3,
)
ours(
    "pa(10,-10,3599)",
    "request",
    pkt(4, sm16(10) + sm16(-10) + sm16(3599)),
    "Pa",
    {"trans": 10, "steer": -10, "turret": 3599},
    4,
)
ours(
    "vm(-50,-450,0)",
    "request",
    pkt(5, sm16(-50) + sm16(-450) + sm16(0)),
    "Vm",
    {"trans": -50, "steer": -450, "turret": 0},
    5,
)
ours(
    "sp(65535,0,1)",
    "request",
    pkt(2, u16(65535) + u16(0) + u16(1)),
    "Sp",
    {"trans": 65535, "steer": 0, "turret": 1},
    2,
)
ours(
    "ct N150 default mask",
    "request",
    pkt(6, [0, 0, 0xFF, 0xFF, 0xFF, 0, 1]),
    "Ct",
    {"mask_hex": "00 00 FF FF FF 00 01"},
    6,
)
ours(
    "conf_sn(10, 0..15)",
    "request",
    pkt(15, [10, *list(range(16))]),
    "ConfSn",
    {"rate": 10, "order": list(range(16))},
    15,
)
ours(
    "conf_sn(25, [0,1,15])",
    "request",
    pkt(15, [25, 0, 1, 15] + [255] * 13),
    "ConfSn",
    {"rate": 25, "order": [0, 1, 15]},
    15,
)
ours("conf_tm(0) watchdog off", "request", pkt(18, [0]), "ConfTm", {"seconds": 0}, 18)
ours("conf_tm(255)", "request", pkt(18, [255]), "ConfTm", {"seconds": 255}, 18)
ours(
    "ws(1,1,0,0)",
    "request",
    pkt(31, [1, 1, 0, 0]),
    "Ws",
    {"trans": True, "steer": True, "turret": False, "timeout_s": 0},
    31,
)
ours(
    "dp(-32767,32767)",
    "request",
    pkt(12, sm16(-32767) + sm16(32767)),
    "Dp",
    {"x": -32767, "y": 32767},
    12,
)
ours(
    "da(-900,1800)",
    "request",
    pkt(30, sm16(-900) + sm16(1800)),
    "Da",
    {"steer": -900, "turret": 1800},
    30,
)
ours(
    "conf_ser(0, 38400)",
    "request",
    pkt(35, [0, *u16(38400)]),
    "ConfSer",
    {"port": 0, "baud": 38400},
    35,
)
ours(
    "mv(2,100, 1,-450, 0,0)",
    "request",
    pkt(43, u16(2) + sm16(100) + u16(1) + sm16(-450) + u16(0) + sm16(0)),
    "Mv",
    {"trans_mode": 2, "trans": 100, "steer_mode": 1, "steer": -450, "turret_mode": 0, "turret": 0},
    43,
)
ours("tk('hi')", "request", pkt(11, [ord("h"), ord("i"), 0]), "Tk", {"text": "hi"}, 11)
for name, code, msg in [
    ("get_sn()", 20, "GetSn"),
    ("get_rc()", 21, "GetRc"),
    ("get_rv()", 22, "GetRv"),
    ("get_ra()", 23, "GetRa"),
    ("get_bp()", 27, "GetBp"),
]:
    ours(name, "request", pkt(code, []), msg, {}, code)
sonar = [(17 * i + 3) % 256 for i in range(16)]
pay = [
    *sonar,
    0,
    1,
    128,
    *sm16(-1234),
    *sm16(5678),
    *sm16(3599),
    *sm16(0),
    *sm16(-200),
    *sm16(450),
    *sm16(0),
    *sm16(-7),
    3,
    *u32(16909060),
    230,
    229,
]
ours(
    "N150 state reply to pr, moving",
    "reply",
    pkt(3, pay),
    "RobotState",
    {
        "sonar": sonar,
        "bumper": 0x000180,
        "x": -1234,
        "y": 5678,
        "steer": 3599,
        "turret": 0,
        "trans_vel": -200,
        "steer_vel": 450,
        "turret_vel": 0,
        "compass": -7,
        "motor_status": 3,
        "timestamp_ms": 0x01020304,
        "voltage_cpu_raw": 230,
        "voltage_motor_raw": 229,
    },
    3,
    request="Pr",
    mask="N150",
)
ours(
    "N150 state reply to ws, stopped",
    "reply",
    pkt(
        31, [0] * 16 + [0, 0, 0] + sm16(10) + sm16(-10) + [0] * 12 + [0] + u32(123456) + [230, 230]
    ),
    "RobotState",
    {"x": 10, "y": -10, "timestamp_ms": 123456, "voltage_cpu_raw": 230, "voltage_motor_raw": 230},
    31,
    request="Ws",
    mask="N150",
)
ours(
    "get_rv reply",
    "reply",
    pkt(22, sm16(200) + sm16(-450) + sm16(0)),
    "RvReply",
    {"trans": 200, "steer": -450, "turret": 0},
    22,
    request="GetRv",
)
ours(
    "get_ra reply (CHOICE C15)",
    "reply",
    pkt(23, u16(300) + u16(300) + u16(300)),
    "RaReply",
    {"trans": 300, "steer": 300, "turret": 300},
    23,
    request="GetRa",
)
ours(
    "get_sn reply",
    "reply",
    pkt(20, sonar + u32(1000)),
    "SnReply",
    {"sonar": sonar, "timestamp_ms": 1000},
    20,
    request="GetSn",
)
ours(
    "get_bp reply",
    "reply",
    pkt(27, [1, 2, 3, *u32(7)]),
    "BpReply",
    {"bumper": 0x010203, "timestamp_ms": 7},
    27,
    request="GetBp",
)
# --- invalid frames: what the stream decoder must report
good = pkt(7, [])
bad_chk = good[:]
bad_chk[4] ^= 0xFF
V.append(
    dict(
        name="gs with bad checksum",
        source="odohil",
        direction="invalid",
        hex=hx(bad_chk),
        fault="bad_checksum",
    )
)
bad_end = good[:]
bad_end[5] = 0x5D
V.append(
    dict(
        name="gs with bad end byte",
        source="odohil",
        direction="invalid",
        hex=hx(bad_end),
        fault="bad_end",
    )
)
V.append(
    dict(
        name="LEN 1", source="odohil", direction="invalid", hex="01 01 00 07 5C", fault="bad_length"
    )
)
V.append(
    dict(
        name="LEN 0x0300 (too long)",
        source="odohil",
        direction="invalid",
        hex="01 00 03 07 0B 5C",
        fault="bad_length",
    )
)
V.append(
    dict(
        name="garbage without start byte",
        source="odohil",
        direction="invalid",
        hex="5C 00 FF 7E",
        fault="garbage",
    )
)
doc = {
    "schema": "odohil nomad golden vectors v1; see protocols/nomad/README.md#golden-vectors",
    "vectors": V,
}
OUT = Path(__file__).resolve().parents[2] / "protocols" / "nomad" / "golden_vectors.json"
if __name__ == "__main__":
    OUT.write_text(json.dumps(doc, indent=1) + "\n")
