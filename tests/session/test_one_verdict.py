"""One session, every command, one verdict (issue 18).

Each session is made by ``odohil run`` on the in-process fake robot
(``fakerobot://``), then read by estimate, report, export, validate and the
wizard's final screen, all in process through typer's runner. They must call
it the same (trusted, doubtful, failed, no estimate) and exit with the status
the table of odohil/cli/exit_codes.py gives: 0 trusted, 3 not trusted or no
estimate; report and export also 3 when the estimate is too imprecise to
export (a design below the planner's minimum, a correction not told from none).
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest
from rich.console import Console
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.cli.wizard import final_screen
from odohil.robots import __file__ as robots_init
from odohil.session.journal.state import load_session
from odohil.session.results.outcome import estimate_path

NOMAD = Path(robots_init).with_name("nomad150.toml")
PORT = "fakerobot://?seed=3&time_scale=100"

SESSIONS = {
    # turn trials on a robot whose turns carry error: doubtful everywhere
    "turns-with-error": (
        "k=1,l=1,n=10,variant=turn;k=0.5,l=1,n=10",
        "doubtful",
        (3, 3, 3, 3, 3),
    ),
    # two trials: below the planner's minimum trials a design, whose intervals
    # cover less than they say (bench/few_trials_coverage.py): doubtful everywhere
    "two-trials": ("k=1,l=1,n=2", "doubtful", (3, 3, 3, 3, 3)),
    # one trial (a two-trial session interrupted after its first trial: run
    # refuses a one-trial plan before motion): no estimate anywhere
    "one-trial": ("k=1,l=1,n=2", "no estimate", (3, 3, 3, 3, 3)),
}


def keep_first_trial(session: Path) -> None:
    """Cut a session's journal after its first solved trial, as a session
    interrupted there leaves it."""
    journal = session / "journal.jsonl"
    lines = journal.read_text(encoding="utf-8").splitlines(keepends=True)
    first = next(i for i, line in enumerate(lines) if json.loads(line)["kind"] == "solved")
    journal.write_text("".join(lines[: first + 1]), encoding="utf-8")


def invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


def robot_file(tmp_path: Path, turns_exact: bool) -> Path:
    text = NOMAD.read_text(encoding="utf-8")
    if not turns_exact:
        text = text.replace("turns_exact = true", "turns_exact = false")
    path = tmp_path / "robot.toml"
    path.write_text(text, encoding="utf-8")
    return path


def status_of(document: dict[str, object] | None) -> str:
    if document is None:
        return "no estimate"
    verdict = document["verdict"]
    assert isinstance(verdict, dict)
    return str(verdict["status"])


@pytest.mark.parametrize("name", list(SESSIONS))
def test_every_command_gives_the_session_one_verdict(tmp_path: Path, name: str) -> None:
    plan, expected, exits = SESSIONS[name]
    run_exit, estimate_exit, report_exit, export_exit, validate_exit = exits
    robot = robot_file(tmp_path, turns_exact=name != "turns-with-error")
    session = tmp_path / name
    ran = invoke(
        "run", "--robot", robot, "--port", PORT, "--measure", "fake", "--plan", plan,
        "--session", session, "--allow-turns", "--allow-few-trials", "--json",
    )  # fmt: skip
    assert ran.exit_code == run_exit, ran.output
    last = json.loads(ran.stdout.strip().splitlines()[-1])
    statuses: dict[str, str] = {}
    if name == "one-trial":
        keep_first_trial(session)
    else:
        assert f"verdict: {expected.upper()}" in ran.stderr  # printed when trusted too
        statuses["run"] = status_of(last if "verdict" in last else None)

    est = invoke("estimate", session, "--json")
    assert est.exit_code == estimate_exit, est.output
    statuses["estimate"] = status_of(json.loads(est.stdout) if est.stdout.strip() else None)

    refused = invoke("report", session, "--out", tmp_path / "refused")
    assert refused.exit_code == report_exit, refused.output
    assert (tmp_path / "refused").exists() == (report_exit == 0)
    forced = invoke("report", session, "--out", tmp_path / "report", "--force")
    assert forced.exit_code == 0, forced.output
    parameters = tmp_path / "report" / "parameters.json"
    statuses["report"] = status_of(
        json.loads(parameters.read_text()) if parameters.exists() else None
    )

    refused = invoke("export", session, "--format", "json")
    assert refused.exit_code == export_exit, refused.output
    forced = invoke("export", session, "--format", "json", "--force")
    statuses["export"] = status_of(json.loads(forced.stdout) if forced.exit_code == 0 else None)

    trials = tmp_path / "validation.csv"
    # turns with error: validated without turns (turn trials are refused, exit 2,
    # when the calibration fitted no turn errors: tests/create2/test_validate_turn_free.py)
    variant = "reverse" if name == "turns-with-error" else "turn"
    made = invoke("simulate", "--k", "2", "--l", "1.5", "--trials", "5", "--seed", "1",
                  "--variant", variant, "--out", trials)  # fmt: skip
    assert made.exit_code == 0, made.output
    checked = invoke("validate", session, "--path", f"file:{trials}", "--json")
    assert checked.exit_code == validate_exit, checked.output
    forced = invoke("validate", session, "--path", f"file:{trials}", "--json", "--force")
    document = json.loads(forced.stdout) if forced.stdout.strip().startswith("{") else None
    statuses["validate"] = status_of(document["calibration"] if document else None)

    screen = io.StringIO()
    code = final_screen(Console(file=screen, width=200), load_session(session).state)
    assert code == (0 if expected == "trusted" else 3)
    words = screen.getvalue()
    statuses["wizard"] = (
        "no estimate" if "NO ESTIMATE" in words else words.split("verdict: ")[1].split()[0].lower()
    )

    statuses["recipe"] = estimate_path(session).status
    assert statuses == dict.fromkeys(statuses, expected)


def test_report_without_estimate_writes_nothing_and_exits_3(tmp_path: Path) -> None:
    """Every trial left out: no estimate, so nothing to report (exit 3), as estimate and export."""
    session = tmp_path / "s"
    ran = invoke(
        "run", "--robot", NOMAD, "--port", PORT, "--measure", "fake", "--plan", "k=1,l=1,n=2",
        "--session", session, "--allow-few-trials",
    )  # fmt: skip
    assert ran.exit_code == 3, ran.output  # two trials: doubtful, below the minimum
    for args in (
        ("report", session, "--out", tmp_path / "r", "--exclude", "1,2"),
        ("estimate", session, "--exclude", "1,2"),
        ("export", session, "--format", "json", "--exclude", "1,2"),
    ):
        result = invoke(*args)
        assert result.exit_code == 3, (args, result.output)
        assert "NO ESTIMATE" in result.output, result.output
    assert not (tmp_path / "r").exists()


def test_run_refuses_fewer_trials_a_design_than_the_planner_before_motion(
    tmp_path: Path,
) -> None:
    session = tmp_path / "s"
    args = ("run", "--robot", NOMAD, "--port", PORT, "--measure", "fake", "--session", session)
    refused = invoke(*args, "--plan", "k=1,l=1,n=2;k=4,l=0.5,n=12")
    assert refused.exit_code == 2, refused.output
    words = " ".join(refused.output.split())
    assert "fewer than 10 trials a design (k=1 l=1 m turn (n=2))" in words
    assert "--allow-few-trials" in words
    assert not session.exists()  # nothing written, nothing moved
