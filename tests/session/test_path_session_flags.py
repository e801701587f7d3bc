"""A session with general paths names its flagged trials (issue 19).

The finding: ``odohil estimate SESSION --json`` (and ``odohil report``'s
parameters.json, ``export --format json`` and the estimate's text) listed no
flagged trial for a session whose plan names a square, although the report's
table pointed out the squares whose pose from the marks was in doubt: the
flags came from the session's forth-and-back trial set
(odohil/session/journal/state.py ``session_trials``), which a session with general
paths estimates without (its trials are ``session_path_trials``).
"""

from __future__ import annotations

import json
from pathlib import Path

from odohil.session.results.report.data import load_report
from tests.cli.test_validate_paths import odohil
from tests.session.helpers import FINE_TAPE_ROBOT_TOML as ROBOT_TOML
from tests.session.helpers import doubtful_only_for_few_trials

PLAN = "k=10,l=0.5,n=5;path=square:0.5,cw,n=5"
SEED = 6
"""A seed whose fake tape leaves squares not clear-cut (measured: trials 7 and
9 flagged, 8 ambiguous)."""


def test_the_flagged_squares_of_a_session_are_named(tmp_path: Path) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML, encoding="utf-8")
    session = tmp_path / "session"
    code, _, err = odohil(
        "run", "--allow-few-trials", "--port", f"fakerobot://?seed={SEED}&time_scale=20000",
        "--robot", str(robot), "--plan", PLAN, "--measure", "fake", "--seed", str(SEED),
        "--session", str(session),
    )  # fmt: skip
    assert code == 3, err  # doubtful only for its 5 trials a path (issue 31)
    assert doubtful_only_for_few_trials(err), err
    # the report's table points out the trials whose pose is in doubt
    points = load_report(session).trials
    doubted = [p.trial for p in points if p.flagged and not p.ambiguous]
    squares = [p.trial for p in points if p.design.startswith("square")]
    assert set(doubted) & set(squares), (doubted, squares)  # the finding needs a doubted square
    code, out, err = odohil("estimate", str(session), "--json")
    assert code == 3, err
    data = json.loads(out)
    assert data["flagged_trials"] == doubted
    assert data["ambiguous_trials"] == [p.trial for p in points if p.ambiguous]
    code, out, err = odohil("estimate", str(session))
    assert code == 3, err
    named = " ".join(out.split())
    assert "flagged trials (pose from the marks in doubt): " + f"{doubted[0]} (" in named, out
