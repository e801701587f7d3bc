"""The journal: append, fsync, replay; torn last records; corruption."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import threading
import time
import zlib
from collections.abc import Callable
from contextlib import AbstractContextManager
from pathlib import Path

import pytest

from odohil.errors import JournalError
from odohil.session.journal.file import (
    JOURNAL_NAME,
    Journal,
    encode_record,
    parse_journal,
    read_journal,
)
from odohil.session.signals import SignalReceived, ctrl_c_in_words, signals_raise


def _write_three(folder: Path) -> None:
    with Journal.create(folder) as journal:
        journal.append("session", {"format": 1, "note": "é ü"})
        journal.append("plan", {"designs": [{"k": 1, "l_m": 0.5}]})
        journal.append("measurement", {"value_m": 0.1 + 0.2})


def test_appended_records_replay_exactly(tmp_path: Path) -> None:
    _write_three(tmp_path)
    contents = read_journal(tmp_path)
    assert contents.torn is None
    assert [r.seq for r in contents.records] == [1, 2, 3]
    assert [r.kind for r in contents.records] == ["session", "plan", "measurement"]
    assert contents.records[0].data["note"] == "é ü"
    # floats survive bit for bit
    assert contents.records[2].data["value_m"] == 0.1 + 0.2


def test_each_line_is_json_with_a_crc_of_the_rest(tmp_path: Path) -> None:
    _write_three(tmp_path)
    for line in (tmp_path / JOURNAL_NAME).read_bytes().splitlines():
        obj = json.loads(line)
        crc = obj.pop("crc")
        body = json.dumps(obj, separators=(",", ":"), ensure_ascii=True).encode()
        assert f"{zlib.crc32(body):08x}" == crc


def test_append_is_on_disk_before_it_returns(tmp_path: Path) -> None:
    with Journal.create(tmp_path) as journal:
        journal.append("session", {"format": 1})
        # another reader sees it at once, while the journal is still open
        assert len(read_journal(tmp_path).records) == 1


def test_reopening_continues_the_sequence(tmp_path: Path) -> None:
    _write_three(tmp_path)
    journal, contents = Journal.open(tmp_path)
    with journal:
        assert contents.torn is None
        assert journal.append("finished", {}).seq == 4
    assert [r.seq for r in read_journal(tmp_path).records] == [1, 2, 3, 4]


def test_create_refuses_an_existing_session(tmp_path: Path) -> None:
    _write_three(tmp_path)
    with pytest.raises(JournalError, match="resume"):
        Journal.create(tmp_path)


def test_second_writer_is_refused(tmp_path: Path) -> None:
    with Journal.create(tmp_path) as journal:
        journal.append("session", {"format": 1})
        with pytest.raises(JournalError, match="in use"):
            Journal.open(tmp_path)


def test_nan_cannot_be_journaled(tmp_path: Path) -> None:
    with (
        Journal.create(tmp_path) as journal,
        pytest.raises(ValueError, match=r"[Oo]ut of range|NaN|nan"),
    ):
        journal.append("measurement", {"value_m": float("nan")})


@pytest.mark.parametrize("cut", [1, 10, 30, -2, -1])
def test_torn_last_record_is_reported_and_set_aside(tmp_path: Path, cut: int) -> None:
    _write_three(tmp_path)
    path = tmp_path / JOURNAL_NAME
    content = path.read_bytes()
    last_start = content.rstrip(b"\n").rfind(b"\n") + 1
    torn_bytes = (
        content[last_start : last_start + cut]
        if cut > 0
        else content[: len(content) + cut][last_start:]
    )
    path.write_bytes(content[:last_start] + torn_bytes)

    contents = read_journal(tmp_path)
    assert [r.seq for r in contents.records] == [1, 2]
    assert contents.torn is not None
    assert contents.torn.line_number == 3
    assert contents.torn.set_aside is None
    assert path.read_bytes() == content[:last_start] + torn_bytes  # reading changes nothing

    journal, reopened = Journal.open(tmp_path)
    with journal:
        assert reopened.torn is not None
        kept = reopened.torn.set_aside
        assert kept is not None
        assert kept.read_bytes() == torn_bytes
        assert "torn" in reopened.torn.describe()
        assert journal.append("torn_record", {"file": kept.name}).seq == 3
    final = read_journal(tmp_path)
    assert final.torn is None
    assert [r.kind for r in final.records] == ["session", "plan", "torn_record"]


def test_bit_flip_in_last_record_is_torn(tmp_path: Path) -> None:
    _write_three(tmp_path)
    path = tmp_path / JOURNAL_NAME
    content = bytearray(path.read_bytes())
    content[-20] ^= 0x01
    path.write_bytes(bytes(content))
    contents = read_journal(tmp_path)
    assert contents.torn is not None
    assert "CRC" in contents.torn.reason or "JSON" in contents.torn.reason
    assert len(contents.records) == 2


def test_trailing_zero_bytes_after_a_crash_are_torn(tmp_path: Path) -> None:
    _write_three(tmp_path)
    path = tmp_path / JOURNAL_NAME
    path.write_bytes(path.read_bytes() + b"\0" * 4096)
    contents = read_journal(tmp_path)
    assert len(contents.records) == 3
    assert contents.torn is not None


@pytest.mark.parametrize("line_index", [0, 1])
def test_corruption_before_the_last_record_is_an_error(tmp_path: Path, line_index: int) -> None:
    _write_three(tmp_path)
    path = tmp_path / JOURNAL_NAME
    lines = path.read_bytes().splitlines(keepends=True)
    lines[line_index] = lines[line_index].replace(b'"seq"', b'"Seq"')
    path.write_bytes(b"".join(lines))
    with pytest.raises(JournalError, match=f"record {line_index + 1} is corrupt"):
        read_journal(tmp_path)
    with pytest.raises(JournalError):
        Journal.open(tmp_path)
    # nothing was changed or set aside
    assert path.read_bytes() == b"".join(lines)
    assert sorted(p.name for p in tmp_path.iterdir()) == [JOURNAL_NAME]


def test_sequence_gap_is_an_error() -> None:
    lines = [
        encode_record(1, "a", {}, 0.0),
        encode_record(3, "b", {}, 0.0),
        encode_record(4, "c", {}, 0.0),
    ]
    with pytest.raises(JournalError, match="sequence number 3 where 2"):
        parse_journal(b"".join(lines))


def test_empty_journal_has_no_records() -> None:
    contents = parse_journal(b"")
    assert contents.records == ()
    assert contents.torn is None


def test_ctrl_c_during_an_append_waits_for_the_record(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    real_fsync = os.fsync

    def fsync_with_ctrl_c(fd: int) -> None:
        # Ctrl-C while the record goes to disk; raise_signal delivers it to this thread
        # at once (os.kill may hand it to another thread of the worker, later)
        signal.raise_signal(signal.SIGINT)
        real_fsync(fd)

    with Journal.create(tmp_path) as journal:
        journal.append("session", {"format": 1})
        monkeypatch.setattr(os, "fsync", fsync_with_ctrl_c)
        with pytest.raises(KeyboardInterrupt):
            journal.append("measurement", {"value_m": 1.0})
        monkeypatch.undo()
        # the interrupted record is whole and counted; the journal goes on
        journal.append("stopped", {})
    contents = read_journal(tmp_path)
    assert contents.torn is None
    assert [r.kind for r in contents.records] == ["session", "measurement", "stopped"]


class _Sender:
    """Sends a signal when told: from a thread started before the record (one
    started within would inherit the block), to itself, so that Python's C
    handler runs there before ``pthread_kill`` returns, as when the kernel hands
    a signal sent to the process to a BLAS or reader thread while the main
    thread blocks it (Python then runs the handler in the main thread); or as
    ``kill -N`` of this process from a child, which the kernel gives to a thread
    that does not block it, or keeps until the main thread takes it."""

    def __init__(self, how: str, signum: int) -> None:
        self.how, self.signum = how, signum
        self._go, self._sent = threading.Event(), threading.Event()
        self._thread = threading.Thread(target=self._in_thread, daemon=True)
        if how == "thread":
            self._thread.start()

    def _in_thread(self) -> None:
        self._go.wait(10)
        signal.pthread_kill(threading.get_ident(), self.signum)
        self._sent.set()

    def send(self) -> None:
        if self.how == "thread":
            self._go.set()
            assert self._sent.wait(10)
        else:
            subprocess.run(["kill", f"-{self.signum}", str(os.getpid())], check=True, timeout=10)


HANDLERS: dict[str, Callable[[], AbstractContextManager[object]]] = {
    "session": lambda: signals_raise(),  # run, resume, wizard: every signal but Ctrl-C raises
    "ctrl-c in words": lambda: ctrl_c_in_words(),  # run, resume: Ctrl-C
    "python's": lambda: contextlib.nullcontext(),  # the wizard's Ctrl-C
}


@pytest.mark.parametrize("sender", ["thread", "process"])
@pytest.mark.parametrize(("signum", "handlers", "raised"), [
    (signal.SIGTERM, "session", SignalReceived),
    (signal.SIGINT, "ctrl-c in words", KeyboardInterrupt),
    (signal.SIGINT, "python's", KeyboardInterrupt),
])  # fmt: skip
def test_a_signal_sent_during_a_record_is_delivered_right_after_it(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    sender: str,
    signum: int,
    handlers: str,
    raised: type[BaseException],
) -> None:
    """The signal is sent while the record goes to disk, by another thread or
    process; the record is whole and counted, and the signal raises in the
    main thread as append returns (the engine then stops the robot)."""
    real_fsync = os.fsync
    synced: list[int] = []

    sending = _Sender(sender, signum)

    def fsync_under_a_signal(fd: int) -> None:
        sending.send()
        deadline = time.monotonic() + 0.05
        while time.monotonic() < deadline:  # Python code: a handler would run here
            time.sleep(0.005)
        real_fsync(fd)
        synced.append(fd)

    with HANDLERS[handlers](), Journal.create(tmp_path) as journal:
        journal.append("session", {"format": 1})
        monkeypatch.setattr(os, "fsync", fsync_under_a_signal)
        handler = signal.getsignal(signum)
        with pytest.raises(raised) as ended:
            journal.append("measurement", {"value_m": 1.0})
        monkeypatch.undo()
        assert synced  # raised after the record was on disk, not during it
        assert signal.pthread_sigmask(signal.SIG_BLOCK, ()) == set()  # nothing left blocked
        assert signal.getsignal(signum) is handler  # nor swapped
        assert journal.next_seq == 3
        journal.append("stopped", {})  # not broken: the record and the count agree
    if isinstance(ended.value, SignalReceived):
        assert ended.value.signum == signum
    contents = read_journal(tmp_path)
    assert contents.torn is None
    assert [r.kind for r in contents.records] == ["session", "measurement", "stopped"]


def test_whether_a_session_is_in_use_is_a_public_question(tmp_path: Path) -> None:
    """The pre-flight asked ``Journal._check_not_in_use`` from outside the
    journal module; the question is public and documented now."""
    folder = tmp_path / "s"
    Journal.check_not_in_use(folder)  # no journal: nobody uses it
    with Journal.create(folder), pytest.raises(JournalError, match="session in use"):
        Journal.check_not_in_use(folder)
    Journal.check_not_in_use(folder)  # closed: free again


def test_no_private_journal_member_is_used_outside_the_journal_module() -> None:
    package = Path(__file__).resolve().parents[2] / "odohil"
    users = [
        str(path.relative_to(package))
        for path in package.rglob("*.py")
        if path != package / "session" / "journal" / "file.py"
        and "Journal._" in path.read_text(encoding="utf-8")
    ]
    assert users == []
