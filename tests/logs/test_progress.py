"""Progress of reading and fitting a recording (issue 30): the session tells a
callback each stage with counts rising to the total, and the command line's
rich bar draws only on a terminal, only once a stage has run its 2 s."""

from __future__ import annotations

import io
import time
from pathlib import Path

from odohil.session.progress import TerminalBar
from odohil.session.results.outcome import estimate_source
from odohil.session.trials.logs import ImportOptions
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.optiodom import joined_runs, run_files
from tests.logs.data import OPTIODOM, needs_optiodom, optiodom_robot


class Recorder:
    """Every call, in order."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, int, int]] = []

    def __call__(self, stage: str, done: int, total: int) -> None:
        self.calls.append((stage, done, total))


def _stages(calls: list[tuple[str, int, int]]) -> dict[str, list[tuple[int, int]]]:
    out: dict[str, list[tuple[int, int]]] = {}
    for stage, done, total in calls:
        out.setdefault(stage, []).append((done, total))
    return out


def _check_rising(counts: list[tuple[int, int]]) -> None:
    dones = [done for done, _ in counts]
    assert dones == sorted(dones)
    assert counts[-1][0] == counts[-1][1]  # the stage ends at its total
    assert all(done < total for done, total in counts[:-1])


@needs_optiodom
def test_reading_cutting_and_fitting_a_log_tell_their_progress(tmp_path: Path) -> None:
    runs = run_files([OPTIODOM / "ivanjko"])[:4]
    log = tmp_path / "four.csv"
    write_csv_log(log, joined_runs(runs))
    recorder = Recorder()
    estimate_source([log], optiodom_robot(), recording=ImportOptions(progress=recorder))
    stages = _stages(recorder.calls)
    assert list(stages) == ["reading four.csv", "cutting trials", "fitting"]
    for counts in stages.values():
        _check_rising(counts)
    assert stages["reading four.csv"][-1][1] == log.stat().st_size
    assert stages["cutting trials"][-1][1] == 4  # one count a trial
    assert stages["fitting"] == [(0, 1), (1, 1)]


@needs_optiodom
def test_an_optiodom_folder_counts_its_run_files() -> None:
    runs = run_files([OPTIODOM / "ivanjko"])[:3]
    recorder = Recorder()
    estimate_source(runs, optiodom_robot(), recording=ImportOptions(progress=recorder))
    stages = _stages(recorder.calls)
    assert list(stages) == ["reading runs", "fitting"]  # each run's cut is not a stage
    _check_rising(stages["reading runs"])
    assert stages["reading runs"][-1] == (3, 3)


class Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def test_no_bar_when_stderr_is_no_terminal() -> None:
    stream = io.StringIO()
    bar = TerminalBar(stream, after_s=0.0)
    assert not bar.enabled
    bar("reading", 0, 10)
    time.sleep(0.05)
    assert not bar.showing
    bar("reading", 10, 10)
    assert stream.getvalue() == ""


def test_a_bar_on_a_terminal_once_a_stage_runs_long_enough_and_gone_when_it_ends() -> None:
    stream = Terminal()
    bar = TerminalBar(stream, after_s=0.05)
    assert bar.enabled
    bar("reading big.csv", 0, 10)
    assert not bar.showing  # not yet: a short stage shows nothing
    deadline = time.monotonic() + 2.0
    while not bar.showing and time.monotonic() < deadline:
        time.sleep(0.01)
    assert bar.showing
    bar("reading big.csv", 5, 10)
    bar("reading big.csv", 10, 10)
    assert not bar.showing
    assert "reading big.csv" in stream.getvalue()


def test_a_short_stage_on_a_terminal_draws_nothing() -> None:
    stream = Terminal()
    bar = TerminalBar(stream, after_s=5.0)
    bar("fitting", 0, 1)
    bar("fitting", 1, 1)
    assert not bar.showing
    assert stream.getvalue() == ""
