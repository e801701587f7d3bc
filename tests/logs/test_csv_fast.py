"""The CSV log's fast reader (numpy, column by column) gives what the line by
line reader gives, and leaves every bad row to it (issue 30, big logs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from odohil.errors import RecordingError
from odohil.session.robots.description import load_robot_description
from odohil.session.trials.logs.csv_log import _checked_rows, _fast_rows, _piece_rows, read_csv_log

HEADER = "t_s,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad,trial"


def _text(rows: int = 40, seed: int = 1) -> str:
    rng = np.random.default_rng(seed)
    lines = ["# a comment before the header", "", HEADER]
    for i in range(rows):
        values = [repr(float(v)) for v in rng.normal(size=7)]
        values[0] = repr(0.05 * i + 1e-3 * float(rng.random()))
        if i % 7 == 3:
            values[4:7] = ["", " ", ""]  # the capture lost the robot
        label = "" if i % 11 == 0 else f" run-{i // 11} "
        lines.append(",".join([*values, label]))
    return "\n".join(lines) + "\n"


def _same(text: str, chunk_chars: int) -> None:
    fast = _fast_rows(Path("log.csv"), text, chunk_chars)
    slow = _checked_rows(Path("log.csv"), text)
    assert fast is not None
    assert fast.names == slow.names
    assert fast.labels == slow.labels
    for name in ("t_s", "odometry", "truth", "where"):
        a, b = getattr(fast, name), getattr(slow, name)
        assert a.shape == b.shape
        assert np.array_equal(a, b, equal_nan=True)  # bit for bit: the same float()


@pytest.mark.parametrize("chunk_chars", [1, 100, 10**6])
def test_the_fast_reader_gives_the_line_by_line_readers_numbers(chunk_chars: int) -> None:
    _same(_text(), chunk_chars)
    _same(_text().replace("\n", "\r\n"), chunk_chars)


@pytest.mark.parametrize(
    "change",
    [
        lambda t: t.replace("run-1 ", '"run-1"', 1),  # quotes
        lambda t: t + "\n",  # a blank line among the rows
        lambda t: t + "# a comment\n",
        lambda t: t + "1,2\n",  # a short row
        lambda t: t.replace(", ,", ",nan,", 1),  # a written nan where a gap was
    ],
)
def test_anything_the_fast_reader_does_not_check_goes_line_by_line(change: object) -> None:
    assert callable(change)
    assert _fast_rows(Path("log.csv"), change(_text())) is None


def test_a_bad_value_in_a_big_log_names_its_line_and_field(tmp_path: Path) -> None:
    lines = _text(rows=300).splitlines()
    fields = lines[250].split(",")
    fields[5] = "north"
    lines[250] = ",".join(fields)
    path = tmp_path / "log.csv"
    path.write_text("\n".join(lines) + "\n")
    robot = load_robot_description(Path("docs/examples/optiodom.toml"))
    with pytest.raises(RecordingError, match=r"log.csv line 251: true_y_m: not a finite number"):
        read_csv_log(path, robot)


def _plain(rows: int, order: list[str], seed: int = 2) -> str:
    """A log without gaps (the piecewise reader's usual case), columns in ``order``."""
    rng = np.random.default_rng(seed)
    lines = ["# before", "", ",".join(order)]
    for i in range(rows):
        row = {
            name: repr(float(v))
            for name, v in zip(HEADER.split(",")[1:7], rng.normal(size=6), strict=True)
        }
        row["t_s"] = repr(0.05 * i + 1e-3 * float(rng.random()))
        row["odo_x_m"] = repr(float(rng.normal()) * 10.0 ** int(rng.integers(-30, 30)))
        row["trial"] = "" if i % 11 == 0 else f" run-{i // 11} é"
        lines.append(",".join(row[name] for name in order))
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("piece_bytes", [1, 300, 10**6])
@pytest.mark.parametrize(
    "order",
    [HEADER.split(","), HEADER.split(",")[:-1], ["trial", *HEADER.split(",")[:-1]]],
)
def test_the_piecewise_reader_gives_the_line_by_line_readers_numbers(
    tmp_path: Path, piece_bytes: int, order: list[str]
) -> None:
    text = _plain(60, order)
    log = tmp_path / "log.csv"
    log.write_text(text, encoding="utf-8")
    fast = _piece_rows(log, piece_bytes)
    slow = _checked_rows(log, text)
    assert fast is not None
    assert fast.names == slow.names
    assert fast.labels == (slow.labels if "trial" in order else [])
    for name in ("t_s", "odometry", "truth", "where"):
        a, b = getattr(fast, name), getattr(slow, name)
        assert a.shape == b.shape
        assert np.array_equal(a, b)  # bit for bit: numpy's parse rounds as float() does


@pytest.mark.parametrize(
    "change",
    [
        lambda t: t.replace("run-1 ", '"run-1"', 1),  # quotes
        lambda t: t + "\n",  # a blank line among the rows
        lambda t: t + "# a comment\n",
        lambda t: t + "1,2\n",  # a short row
        lambda t: t + "0.0, 1,2,3,4,5,6,x\n",  # a space among the numbers
        lambda t: t.replace("é", "\x0cé", 1),  # a line break for splitlines
        lambda t: t.replace("e-", "1_0e-", 1),  # float's underscores
        lambda t: "\n".join(t.splitlines()[:5]) + "\n0.0,1,,,,,,\n",  # a gap
    ],
)
def test_anything_the_piecewise_reader_does_not_check_goes_on(
    tmp_path: Path, change: object
) -> None:
    assert callable(change)
    text = change(_plain(30, HEADER.split(",")))
    log = tmp_path / "log.csv"
    log.write_text(text, encoding="utf-8", newline="")
    assert _piece_rows(log, 200) is None


def test_a_comment_line_is_no_label_of_a_first_trial_column(tmp_path: Path) -> None:
    order = ["trial", *HEADER.split(",")[:-1]]
    log = tmp_path / "log.csv"
    log.write_text(_plain(5, order).replace(" run-0", "#run-0"), encoding="utf-8")
    assert _piece_rows(log) is None
