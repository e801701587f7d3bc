"""The Create 2 codec reproduces every golden vector (built by plain byte
arithmetic in make_golden_vectors.py), both ways."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from fakes.create2.config import build_config
from fakes.create2.engine import Create2Engine
from odohil.driver.create2.link import SAMPLE_IDS
from odohil.protocol.create2 import commands
from odohil.protocol.create2.commands import Command, CommandSplitter
from odohil.protocol.create2.numbers import encoder_delta, to_signed16
from odohil.protocol.create2.packets import decode_reply, encode_reply
from odohil.protocol.create2.stream import StreamDecoder, encode_frame

from .golden import GOLDEN, golden

COMMANDS = golden("command")
REPLIES = golden("reply")
FRAMES = golden("frame")
WRAPS = golden("wrap")
SEQUENCES = golden("sequence")


def _ids(v: dict[str, Any]) -> str:
    return str(v["name"])


def _values(v: dict[str, Any]) -> dict[int, int]:
    return {int(k): int(x) for k, x in v["values"].items()}


def test_the_vectors_file_is_what_the_generator_makes(tmp_path: Path) -> None:
    before = GOLDEN.read_text()
    script = Path(__file__).with_name("make_golden_vectors.py")
    subprocess.run([sys.executable, str(script)], check=True)
    assert GOLDEN.read_text() == before


@pytest.mark.parametrize("vector", COMMANDS, ids=_ids)
def test_command_encodes_to_its_bytes(vector: dict[str, Any]) -> None:
    builder = getattr(commands, vector["builder"])
    args = vector["args"]
    if vector["builder"] in ("query_list", "stream"):
        data = builder(args)
    elif vector["builder"] == "pause_resume":
        data = builder(bool(args[0]))
    else:
        data = builder(*args)
    assert data.hex(" ").upper() == vector["hex"]


@pytest.mark.parametrize("vector", COMMANDS, ids=_ids)
def test_command_splits_back_whole(vector: dict[str, Any]) -> None:
    data = bytes.fromhex(vector["hex"])
    splitter = CommandSplitter()
    # byte by byte: nothing comes out before the last data byte
    for byte in data[:-1]:
        assert splitter.feed(bytes((byte,))) == []
    (command,) = splitter.feed(data[-1:])
    assert command.known
    assert bytes((command.opcode,)) + command.data == data
    assert splitter.pending == b""


@pytest.mark.parametrize("vector", SEQUENCES, ids=_ids)
def test_sequence_is_its_bytes_and_splits_into_its_commands(vector: dict[str, Any]) -> None:
    data = bytes.fromhex(vector["hex"])
    assert getattr(commands, vector["constant"]) == data
    out = CommandSplitter().feed(data)
    assert [c.opcode for c in out] == vector["opcodes"]
    assert all(c.known for c in out)


@pytest.mark.parametrize("vector", REPLIES, ids=_ids)
def test_reply_decodes_and_encodes(vector: dict[str, Any]) -> None:
    data = bytes.fromhex(vector["hex"])
    decoded = decode_reply(vector["ids"], data)
    for pid, value in _values(vector).items():
        assert decoded[pid] == value, pid
    assert encode_reply(vector["ids"], decoded) == data


@pytest.mark.parametrize("vector", FRAMES, ids=_ids)
def test_frame_decodes_and_encodes(vector: dict[str, Any]) -> None:
    data = bytes.fromhex(vector["hex"])
    assert sum(data) % 256 == 0
    (frame,) = StreamDecoder().feed(data)
    assert frame.ids == tuple(vector["ids"])
    assert frame.values == _values(vector)
    assert frame.raw == data
    assert encode_frame(vector["ids"], _values(vector)) == data


@pytest.mark.parametrize("vector", FRAMES, ids=_ids)
def test_frame_found_after_noise_and_split_anywhere(vector: dict[str, Any]) -> None:
    data = bytes.fromhex(vector["hex"])
    noise = bytes((19, 200, 19, 3, 7, 1, 0))  # false headers, bad checksums
    stream = noise + data + data[:-1] + bytes(((data[-1] + 1) % 256,)) + data
    for cut in range(len(stream) + 1):
        decoder = StreamDecoder(tuple(vector["ids"]))
        frames = decoder.feed(stream[:cut]) + decoder.feed(stream[cut:])
        assert [f.raw for f in frames] == [data, data], cut


@pytest.mark.parametrize("vector", WRAPS, ids=_ids)
def test_encoder_delta_wraps_both_ways(vector: dict[str, Any]) -> None:
    prev, cur = vector["previous"], vector["current"]
    assert encoder_delta(prev, cur) == vector["delta"]
    # the same wire bytes read as s16 (the spec) give the same delta
    assert encoder_delta(to_signed16(prev), to_signed16(cur)) == vector["delta"]


def test_unknown_opcode_is_skipped_and_partial_command_waits() -> None:
    splitter = CommandSplitter()
    out = splitter.feed(bytes((0x00, 0x91, 0x00)))
    assert [(c.opcode, c.known) for c in out] == [(0, False)]
    assert splitter.pending == bytes((0x91, 0x00))
    out = splitter.feed(commands.RESYNC)
    # the pending Drive Direct completes on Start bytes, then Starts only
    assert out[0] == Command(0x91, bytes((0x00, 0x80, 0x80, 0x80)))
    assert out[1:] == [Command(0x80, b"")] * (commands.RESYNC_STARTS - 3)
    assert splitter.pending == b""


def _cut_short() -> list[tuple[str, bytes]]:
    """Every command vector, and the driver's own list commands, cut after each
    of its bytes but the last: what a host that died mid-command leaves."""
    whole = [(str(v["name"]), bytes.fromhex(v["hex"])) for v in COMMANDS]
    whole += [
        ("driver's Query List", commands.query_list(SAMPLE_IDS)),
        ("driver's Stream", commands.stream(SAMPLE_IDS)),
    ]
    return [(f"{name}[:{cut}]", data[:cut]) for name, data in whole for cut in range(1, len(data))]


def test_resync_completes_any_command_cut_short_with_defined_opcodes() -> None:
    # C10 (protocols/create2/README.md): whatever command the host left
    # pending, lists included, the Starts complete it and at least one Start
    # then acts; nothing stays pending and no undefined opcode is sent
    assert set(commands.RESYNC) == {0x80}
    for name, partial in _cut_short():
        splitter = CommandSplitter()
        assert splitter.feed(partial) == [], name
        out = splitter.feed(commands.RESYNC)
        assert splitter.pending == b"", name
        assert all(c.known for c in out), name
        assert (bytes((out[0].opcode,)) + out[0].data).startswith(partial), name
        assert out[-1] == Command(0x80, b""), name


def test_resync_leaves_the_fake_passive_and_stopped_at_its_rate() -> None:
    # the same cut commands, each sent while the fake drives, then the resync
    wall = [0.0]
    for name, partial in _cut_short():
        engine = Create2Engine(build_config(seed=1, mode_change_s=0.0), clock=lambda: wall[0])
        engine.receive(bytes((0x80, 0x83)) + commands.drive_direct(200, 200))
        assert engine.truth().moving
        engine.receive(partial + commands.RESYNC)
        truth = engine.truth()
        assert (truth.mode, truth.moving, truth.baud) == (1, False, 115200), name
        assert truth.unknown_opcodes == 0, name
