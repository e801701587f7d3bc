"""Issue 30, part 5: ``simulate --as-driven`` writes a one-way design's trials
as a plan drives them (every other one backwards), so ``run --measure FILE``
serves a plan of k = 0.5; the file without it is refused, naming the rows."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_OK
from odohil.session.journal.file import read_journal
from odohil.session.trials.trial_file import read_trials

PLAN = "k=0.5,l=1,n=10"
PORT = "fakerobot://?seed=3&time_scale=2000"


def _simulate(out: Path, *extra: str) -> None:
    made = CliRunner().invoke(app, [
        "simulate", "--k", "0.5", "--l", "1", "--trials", "10", "--seed", "3",
        "--out", str(out), *extra,
    ])  # fmt: skip
    assert made.exit_code == 0, made.output


def _run(trials: Path, session: Path) -> tuple[int, str]:
    done = CliRunner().invoke(app, [
        "run", "--robot", "nomad150", "--port", PORT, "--plan", PLAN, "--measure", str(trials),
        "--session", str(session), "--allow-few-trials",
    ])  # fmt: skip
    return done.exit_code, " ".join(done.output.split())


def test_a_file_written_as_driven_serves_a_plan_of_half_integer_k(tmp_path: Path) -> None:
    trials = tmp_path / "driven.csv"
    _simulate(trials, "--as-driven")
    read = read_trials(trials)
    assert [t.design.backward for t in read.trials] == [False, True] * 5
    assert all((t.pose_change[0] < 0) == t.design.backward for t in read.trials)
    code, said = _run(trials, tmp_path / "s")
    # served whole and trusted (its E_R not told from none: not exportable, said)
    assert code == EXIT_OK, said
    assert "verdict: TRUSTED" in said
    records = read_journal(tmp_path / "s").records
    assert sum(r.kind == "solved" for r in records) == 10


def test_a_file_of_forward_trials_is_refused_before_anything_moves(tmp_path: Path) -> None:
    trials = tmp_path / "forward.csv"
    _simulate(trials)
    assert not any(t.design.backward for t in read_trials(trials).trials)
    code, said = _run(trials, tmp_path / "s")
    assert code == EXIT_BAD_INPUT, said
    assert "row 2 (line 3) is k=0.5 l=1 m turn, trial 2 runs k=0.5 l=1 m turn backward" in said
    assert "nothing moved" in said
