"""Builds protocols/create2/golden_vectors.json by plain byte arithmetic.

Deliberately imports nothing from odohil, so the vectors check the codec
instead of echoing it. Every number comes from the facts document's §4-§6
and §11 (the worked examples, reproduced here byte for byte).
Run: python tests/create2/make_golden_vectors.py
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

OUT = Path(__file__).resolve().parents[2] / "protocols" / "create2" / "golden_vectors.json"


def s16(v: int) -> list[int]:
    """Two's complement, high byte first."""
    u = v + 65536 if v < 0 else v
    return [u // 256, u % 256]


def hx(b: list[int]) -> str:
    return " ".join(f"{x:02X}" for x in b)


def frame(body: list[int]) -> list[int]:
    head = [19, len(body), *body]
    return [*head, (256 - sum(head) % 256) % 256]


V: list[dict[str, Any]] = []


def command(name: str, b: list[int], builder: str, args: list[int], source: str) -> None:
    V.append(dict(name=name, kind="command", hex=hx(b), builder=builder, args=args, source=source))


def reply(name: str, ids: list[int], b: list[int], values: dict[int, int], source: str) -> None:
    V.append(
        dict(
            name=name,
            kind="reply",
            ids=ids,
            hex=hx(b),
            values={str(k): v for k, v in values.items()},
            source=source,
        )
    )


def stream_frame(name: str, ids: list[int], b: list[int], values: dict[int, int], src: str) -> None:
    V.append(
        dict(
            name=name,
            kind="frame",
            ids=ids,
            hex=hx(b),
            values={str(k): v for k, v in values.items()},
            source=src,
        )
    )


def sequence(name: str, b: list[int], constant: str, opcodes: list[int], source: str) -> None:
    V.append(
        dict(
            name=name, kind="sequence", hex=hx(b), constant=constant, opcodes=opcodes, source=source
        )
    )


def wrap(name: str, prev: int, cur: int, delta: int) -> None:
    V.append(dict(name=name, kind="wrap", previous=prev, current=cur, delta=delta, source="§11"))


# ---- commands (§11 worked examples and §4) ----
command("Start", [128], "start", [], "§11")
command("Safe", [131], "safe", [], "§11")
command("Full", [132], "full", [], "§11")
command("Stop", [173], "stop_oi", [], "§11")
command("Reset", [7], "reset", [], "§11")
command("Baud 19200", [129, 7], "baud", [19200], "§2, §11")
command("Baud 115200", [129, 11], "baud", [115200], "§2")
command("Drive -200 mm/s r 500", [137, *s16(-200), *s16(500)], "drive", [-200, 500], "§11 p.13")
command("Drive straight 200", [137, *s16(200), 0x7F, 0xFF], "drive", [200, 0x7FFF], "§4")
command("Drive stop, radius 0", [137, 0, 0, 0, 0], "drive", [0, 0], "C30")
command("Drive 200 radius 0 (straight, C30)", [137, 0, 200, 0, 0], "drive", [200, 0], "C30")
command("Spin CW 100", [137, *s16(100), 0xFF, 0xFF], "drive", [100, -1], "§11")
command("Spin CCW 100", [137, *s16(100), 0x00, 0x01], "drive", [100, 1], "§11")
command("Direct 200,200", [145, 0, 200, 0, 200], "drive_direct", [200, 200], "§11")
command("Direct -150,-150", [145, 0xFF, 0x6A, 0xFF, 0x6A], "drive_direct", [-150, -150], "§11")
command("Direct R 500 L -500", [145, *s16(500), *s16(-500)], "drive_direct", [500, -500], "§4")
command("Direct stop", [145, 0, 0, 0, 0], "drive_direct", [0, 0], "§11")
command("PWM R +128 L -128", [146, 0x00, 0x80, 0xFF, 0x80], "drive_pwm", [128, -128], "§11")
command("Sensors 35", [142, 35], "sensors", [35], "§11")
command("Sensors 100", [142, 100], "sensors", [100], "§4")
command("Query 43,44", [149, 2, 43, 44], "query_list", [43, 44], "§11")
command("Stream 43,44", [148, 2, 43, 44], "stream", [43, 44], "§11")
command("Stream 7,35,43,44", [148, 4, 7, 35, 43, 44], "stream", [7, 35, 43, 44], "§11")
command("Stream none (undocumented; the host never sends it)", [148, 0], "stream", [], "C8")
command("Pause", [150, 0], "pause_resume", [0], "§11")
command("Resume", [150, 1], "pause_resume", [1], "§11")

# ---- command sequences ----
# 130 Starts: a Stream or Query List cut after its opcode takes 1 + 128 of them
sequence("Resync: Start x 130", [128] * 130, "RESYNC", [128] * 130, "§9 (S6), C10")

# ---- raw replies ----
reply("Mode Safe", [35], [2], {35: 2}, "§11")
reply("Query 43,44: L 1000 R -3", [43, 44], [0x03, 0xE8, 0xFF, 0xFD], {43: 1000, 44: -3}, "§11")
reply("Distance -1 mm", [19], s16(-1), {19: -1}, "§5")
reply("Angle +90 deg", [20], s16(90), {20: 90}, "§5")
reply("Bumps: drop L + bump R", [7], [0x08 | 0x01], {7: 9}, "§5")
reply("Requested R 200 L -150", [41, 42], [*s16(200), *s16(-150)], {41: 200, 42: -150}, "§5")
g100 = [0] * 80
g100[12:14] = s16(-25)  # 19 distance @12
g100[14:16] = s16(7)  # 20 angle @14
g100[40] = 3  # 35 mode @40
g100[44:46] = s16(-300)  # 39 velocity @44
g100[52:54] = s16(-32768)  # 43 @52
g100[54:56] = s16(32767)  # 44 @54
g100[79] = 1  # 58 stasis @79
reply(
    "Group 100 at the offsets of §5",
    [100],
    g100,
    {19: -25, 20: 7, 35: 3, 39: -300, 43: -32768, 44: 32767, 58: 1, 7: 0, 22: 0},
    "§5",
)
g101 = [0] * 28
g101[0:2] = s16(4499)
g101[2:4] = s16(-4499)
reply("Group 101: encoders first", [101], g101, {43: 4499, 44: -4499, 58: 0}, "§5")

# ---- stream frames ----
stream_frame(
    "Frame 43,44",
    [43, 44],
    [0x13, 0x06, 0x2B, 0x03, 0xE8, 0x2C, 0xFF, 0xFD, 0xA9],
    {43: 1000, 44: -3},
    "§11",
)
stream_frame(
    "Frame 7,35,43,44",
    [7, 35, 43, 44],
    [0x13, 0x0A, 0x07, 0x00, 0x23, 0x02, 0x2B, 0x03, 0xE8, 0x2C, 0xFF, 0xFD, 0x79],
    {7: 0, 35: 2, 43: 1000, 44: -3},
    "§11",
)
stream_frame(
    "Frame with 19 inside the data",
    [19, 43],
    frame([19, *s16(19), 43, *s16(0x1313)]),
    {19: 19, 43: 0x1313},
    "§10.5",
)
stream_frame(
    "Frame 7,9,10,11,12,35,41,42,43,44",
    [7, 9, 10, 11, 12, 35, 41, 42, 43, 44],
    frame(
        [
            *[7, 2, 9, 1, 10, 0, 11, 0, 12, 0, 35, 1, 41, *s16(-500), 42, *s16(500)],
            *[43, *s16(-15), 44, *s16(65530 - 65536)],
        ]
    ),
    {7: 2, 9: 1, 10: 0, 11: 0, 12: 0, 35: 1, 41: -500, 42: 500, 43: -15, 44: -6},
    "§5/§6",
)

# ---- encoder wrap (§11, §10.1) ----
wrap("0x7FF0 -> 0x8010 forwards through s16 max", 0x7FF0, 0x8010, 32)
wrap("0x0005 -> 0xFFF6 backwards through 0", 0x0005, 0xFFF6, 65521 - 65536)
wrap("65530 -> 5 forwards through 65535", 65530, 5, 11)
wrap("5 -> 65526 backwards (libcreate gives +65522)", 5, 65526, -15)
wrap("no motion", 1234, 1234, 0)
wrap("a 2 m leg forwards", 65000, (65000 + 4499) % 65536, 4499)


def main() -> None:
    doc = {
        "schema": (
            "odohil create2 golden vectors v1; see protocols/create2/README.md#golden-vectors"
        ),
        "vectors": V,
    }
    OUT.write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
