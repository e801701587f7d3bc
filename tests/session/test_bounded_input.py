"""Bounded input (issue 17, item 3): every file odohil reads is a regular file
read in bounded pieces (odohil/session/bounded_io.py).

Before: ``odohil estimate /dev/zero`` grew to 23.7 GB in 8 s and was killed by
the kernel; a FIFO without a writer (as a trial file, a ``--path file:`` pose
file or a session's journal) hung for ever; a 50 MB
single-line trial file was read whole before its 4096-character line limit was
checked. Now each is refused at once, exit 2, naming the file and the limit.

The hangs and the memory limit are properties of a process: those cases run
``odohil`` as one, under a deadline (and an address-space limit); the rest run
in process.
"""

from __future__ import annotations

import contextlib
import os
import resource
import subprocess
import sys
import tracemalloc
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.errors import JournalError, TrialFileError
from odohil.session.bounded_io import LineSplitter, read_file_bytes
from odohil.session.journal.file import JOURNAL_NAME
from odohil.session.trials.trial_file import MAX_LINE_BYTES, read_trials
from tests import forked
from tests.report.session_factory import build_session

ADDRESS_SPACE = 4 << 30
"""The address-space limit of the /dev/zero case, bytes (4 GiB)."""


def odohil(*args: str | Path, timeout_s: float, limit_memory: bool = False) -> tuple[int, str]:
    """``odohil ARGS`` as a process; (exit status, stderr in one line). Fails the
    test when it runs longer than ``timeout_s`` (the process is killed). Forked
    from the server that imported odohil once (tests/forked.py), but for the
    address-space limit's case: a console process, whose limit is set before
    its start."""

    def address_space() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))

    if not limit_memory:
        try:
            code, _, err = forked.run([str(a) for a in args], timeout_s=timeout_s)
        except TimeoutError:
            pytest.fail(f"odohil {' '.join(map(str, args))} still ran after {timeout_s} s")
        return code, " ".join(err.split())
    try:
        done = subprocess.run(
            [sys.executable, "-m", "odohil", *map(str, args)],
            capture_output=True,
            text=True,
            timeout=timeout_s,
            preexec_fn=address_space,
            check=False,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"odohil {' '.join(map(str, args))} still ran after {timeout_s} s")
    return done.returncode, " ".join(done.stderr.split())


def in_process(*args: str | Path) -> tuple[int, str]:
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return result.exit_code, " ".join(result.stderr.split())


@pytest.fixture
def fifo(tmp_path: Path) -> Iterator[Path]:
    """A FIFO nobody writes to (a reader that opens it blocks until a writer comes)."""
    path = tmp_path / "f.csv"
    os.mkfifo(path)
    yield path
    # free a reader the code under test may have left blocked
    with contextlib.suppress(OSError):
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small finished calibration session (the in-process fake Nomad)."""
    folder = tmp_path_factory.mktemp("bounded") / "calibration"
    build_session(folder, "k=1,l=1,n=3;k=0.5,l=1,n=3", seed=2)
    return folder


def test_estimate_dev_zero_under_a_4_gib_address_space_ends_at_once_with_exit_2() -> None:
    code, err = odohil("estimate", "/dev/zero", timeout_s=20, limit_memory=True)
    assert code == 2, err
    assert "trial file /dev/zero is a character device" in err, err


def test_a_fifo_trial_file_is_refused_without_waiting_for_a_writer(fifo: Path) -> None:
    code, err = odohil("estimate", fifo, timeout_s=10)
    assert code == 2, err
    assert f"trial file {fifo} is a FIFO" in err, err


def test_a_fifo_pose_file_of_validate_is_refused(session: Path, fifo: Path) -> None:
    code, err = odohil("validate", session, "--path", f"file:{fifo}", "--force", timeout_s=10)
    assert code == 2, err
    assert f"{fifo} is a FIFO" in err, err


@pytest.mark.parametrize("command", ["resume", "report", "estimate", "run"])
def test_a_session_whose_journal_is_a_fifo_is_refused(tmp_path: Path, command: str) -> None:
    folder = tmp_path / "session"
    folder.mkdir()
    os.mkfifo(folder / JOURNAL_NAME)
    extra = {
        "report": ["--out", str(tmp_path / "report.html")],
        "run": ["--session", str(folder), "--port", "fakerobot://?seed=1", "--robot",
                "nomad150", "--allow-few-trials", "--plan", "k=1,l=1,n=2", "--measure", "fake"],
    }.get(command, [])  # fmt: skip
    try:
        code, err = odohil(command, *([] if command == "run" else [folder]), *extra, timeout_s=10)
    finally:
        with contextlib.suppress(OSError):
            os.close(os.open(folder / JOURNAL_NAME, os.O_WRONLY | os.O_NONBLOCK))
    assert code == 2, err
    assert "journal" in err, err
    if command != "run":  # run: "already holds a session journal", at once
        assert "is a FIFO" in err, err


def test_a_50_mb_single_line_file_is_refused_by_its_size_unread(tmp_path: Path) -> None:
    big = tmp_path / "big.csv"
    with big.open("wb") as handle:
        handle.truncate(50_000_000)  # sparse: one 50 MB line of NUL bytes
    code, err = in_process("estimate", big)
    assert code == 2, err
    assert f"trial file {big} is 50000000 bytes: larger than the limit of 32 MiB" in err, err


def test_a_long_line_is_refused_after_its_limit_without_reading_the_file_whole(
    tmp_path: Path,
) -> None:
    """20 MB (under the size limit) in one line: refused once the line passes
    MAX_LINE_BYTES, with well under 1 MiB allocated."""
    long = tmp_path / "long.csv"
    with long.open("wb") as handle:
        handle.write(b"k,l_m,variant,dx_m,dy_m,dtheta_rad\n")
        handle.truncate(20_000_000)
    tracemalloc.start()
    try:
        with pytest.raises(TrialFileError) as raised:
            read_trials(long)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert f"line 2 is longer than the limit of {MAX_LINE_BYTES} bytes" in str(raised.value)
    assert peak < 1 << 20, peak


def test_a_file_that_grows_past_its_limit_while_read_is_refused(tmp_path: Path) -> None:
    """The size is checked on what is read, not only on what stat said."""
    path = tmp_path / "journal.jsonl"
    path.write_bytes(b"x\n" * 10)
    with pytest.raises(JournalError, match=r"more than the limit of 8 bytes|larger than"):
        read_file_bytes(path, what="the session journal", max_bytes=8, error=JournalError)


def test_the_line_splitter_holds_at_most_its_limit_and_counts_long_lines() -> None:
    splitter = LineSplitter(8)
    assert splitter.feed(b"short\nand a") == [b"short"]
    assert splitter.feed(b" very long line") == []  # dropped as it passes 8 bytes
    assert splitter.feed(b" still\nok\n") == [b"ok"]
    assert splitter.n_too_long == 1
    assert splitter.feed(b"12345678\n123456789\n") == [b"12345678"]
    assert splitter.n_too_long == 2
