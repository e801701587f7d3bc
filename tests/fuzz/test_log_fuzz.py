"""Property-based fuzz of the log readers and the general-path trial file:
whatever the text, a reader returns trials or raises its own error
(RecordingError, TrialFileError) naming the file; never another exception."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from odohil.errors import RecordingError, TrialFileError
from odohil.session.trials.logs import ImportOptions, read_recording
from odohil.session.trials.path_trial_file import read_path_trials
from tests.logs.data import optiodom_robot

CELLS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-(10**6), 10**6).map(str),
    st.sampled_from(["", " ", "x", "1e400", "-0", "nan", "run-1", '"a,b"']),
)
CSV_HEADERS = st.sampled_from(
    [
        "t_s,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad",
        "t_s,ticks_left,ticks_right,true_x_m,true_y_m,true_theta_rad,trial",
        "t_s,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad,trial",
        "t_s,true_x_m",
        "",
    ]
)


def _refusal(call: Callable[[], object], error: type[Exception]) -> str | None:
    """The message of the ``error`` the call raised, or None when it returned."""
    try:
        call()
    except error as exc:
        return str(exc)
    return None


FUZZ = settings(
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@FUZZ
@given(header=CSV_HEADERS, rows=st.lists(st.lists(CELLS, min_size=0, max_size=9), max_size=30))
def test_csv_logs_only_raise_recording_errors(
    tmp_path: Path, header: str, rows: list[list[str]]
) -> None:
    path = tmp_path / "fuzz.csv"
    path.write_text("\n".join([header, *(",".join(row) for row in rows)]) + "\n")
    message = _refusal(
        lambda: read_recording([path], optiodom_robot(), ImportOptions(format="csv")),
        RecordingError,
    )
    assert message is None or "fuzz.csv" in message


@FUZZ
@given(rows=st.lists(st.lists(CELLS, min_size=0, max_size=9), max_size=30))
def test_tum_pairs_only_raise_recording_errors(tmp_path: Path, rows: list[list[str]]) -> None:
    odom = tmp_path / "odom.txt"
    truth = tmp_path / "truth.txt"
    text = "\n".join(" ".join(row) for row in rows) + "\n"
    odom.write_text(text)
    truth.write_text(text)
    with pytest.raises(RecordingError):
        read_recording([odom, truth], optiodom_robot(), ImportOptions(format="tum"))


@FUZZ
@given(
    lines=st.lists(
        st.one_of(
            st.just('{"format": "odohil-path-trials", "version": 1}'),
            st.just(
                '{"steps": [{"leg_m": 1.0}], "pose_change": [0, 0, 0], '
                '"measurement_cov": [[0, 0, 0], [0, 0, 0], [0, 0, 0]]}'
            ),
            st.text(max_size=40),
            st.recursive(
                st.one_of(
                    st.none(), st.booleans(), st.floats(), st.integers(), st.text(max_size=5)
                ),
                lambda inner: st.one_of(
                    st.lists(inner, max_size=4),
                    st.dictionaries(st.text(max_size=8), inner, max_size=4),
                ),
                max_leaves=10,
            ).map(repr),
        ),
        max_size=6,
    )
)
def test_trial_files_only_raise_trial_file_errors(tmp_path: Path, lines: list[str]) -> None:
    path = tmp_path / "fuzz.jsonl"
    path.write_text("\n".join(lines) + "\n")
    message = _refusal(lambda: read_path_trials(path), TrialFileError)
    assert message is None or "fuzz.jsonl" in message
