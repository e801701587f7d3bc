"""General-path trial files (odohil/session/trials/path_trial_file.py): written and
read back to the same trials; bad files refused with the line and the key."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from odohil.errors import TrialFileError
from odohil.science.path_trials import PathTrial
from odohil.science.paths import EncoderPath, Leg, Turn, square
from odohil.session.trials.logs import ImportOptions, read_recording
from odohil.session.trials.path_trial_file import (
    is_path_trial_file,
    read_path_trials,
    write_path_trials,
)
from tests.logs.data import OPTIODOM, needs_optiodom, optiodom_robot


def _assert_same(a: list[PathTrial], b: list[PathTrial]) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert x.path.steps == y.path.steps
        assert x.path.name == y.path.name
        assert np.array_equal(x.pose_change, y.pose_change)
        assert np.array_equal(x.measurement_cov, y.measurement_cov)
        assert (x.source, x.span_s, x.trial, x.family, x.direction) == (
            y.source,
            y.span_s,
            y.trial,
            y.family,
            y.direction,
        )


def _trials() -> list[PathTrial]:
    cov = np.diag([1e-8, 2e-8, 3e-6]) + 1e-9
    return [
        PathTrial(
            square(0.75, counter_clockwise=False),
            [0.0123456789012345, -1 / 3, 1e-7],
            cov,
            "a.csv",
            (1.25, 7.5),
            1,
            "mixed",
            "cw",
        ),
        PathTrial(
            EncoderPath((Turn(np.pi / 3, "spin"), Leg(-0.2), Turn(-0.1, "arc")), name="x"),
            [0.1, 0.2, 0.3],
        ),
    ]


def test_trials_round_trip_to_the_same_numbers(tmp_path: Path) -> None:
    path = tmp_path / "trials.jsonl"
    trials = _trials()
    assert write_path_trials(path, trials, robot="create2") == 2
    assert is_path_trial_file(path)
    header = json.loads(path.read_text().splitlines()[0])
    assert header == {"format": "odohil-path-trials", "version": 1, "trials": 2, "robot": "create2"}
    _assert_same(read_path_trials(path), trials)


@needs_optiodom
def test_real_trials_round_trip(tmp_path: Path) -> None:
    trials = read_recording(
        [OPTIODOM / "circular/250620202104"], optiodom_robot(), ImportOptions(format="optiodom")
    )
    path = tmp_path / "circles.jsonl"
    write_path_trials(path, trials)
    _assert_same(read_path_trials(path), trials)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda r: r.update(steps=[{"leg_m": 0.0}]), r"line 2: a leg needs a finite non-zero"),
        (lambda r: r.update(steps=[{"turn_rad": 1.0, "kind": "arc"}]), r"line 2: a path needs"),
        (lambda r: r.update(steps=[{"turn_rad": 1.0, "kind": "x"}]), r"steps\[0\].kind: one of"),
        (lambda r: r.update(pose_change=[1, 2]), r"line 2: pose_change: \[x_m"),
        (lambda r: r.update(measurement_cov=[[1, 0, 0], [0, 1, 0], [0, 0, -1]]), "semi-definite"),
        (lambda r: r.update(direction="up"), r"line 2: direction: one of"),
        (lambda r: r.update(colour="red"), r"line 2: unknown key\(s\) colour"),
        (lambda r: r.pop("steps"), r"line 2: missing steps"),
        (lambda r: r.update(span_s=[1, "2"]), r"span_s\[1\]: a finite number"),
    ],
)
def test_a_bad_trial_line_names_the_line_and_the_key(tmp_path: Path, edit, message: str) -> None:
    path = tmp_path / "trials.jsonl"
    write_path_trials(path, _trials())
    lines = path.read_text().splitlines()
    record = json.loads(lines[1])
    edit(record)
    lines[1] = json.dumps(record)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(TrialFileError, match=message):
        read_path_trials(path)


def test_a_newer_version_a_short_file_and_another_format_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "trials.jsonl"
    write_path_trials(path, _trials())
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:2]) + "\n")
    with pytest.raises(
        TrialFileError, match=r"line 1: trials: the header says 2, the file holds 1"
    ):
        read_path_trials(path)
    path.write_text(lines[0].replace('"version": 1', '"version": 2') + "\n")
    with pytest.raises(TrialFileError, match=r"line 1: version: 2; this odohil reads versions 1-1"):
        read_path_trials(path)
    path.write_text("k,l_m,variant,dx_m,dy_m,dtheta_rad\n")
    assert not is_path_trial_file(path)
    with pytest.raises(TrialFileError, match=r"line 1: not a general-path trial file"):
        read_path_trials(path)
