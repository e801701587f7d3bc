"""``odohil report`` on a real session (engine against the in-process fake robot)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from odohil.science.estimators import estimate
from odohil.session.journal.file import read_journal
from odohil.session.journal.state import SessionState, replay, session_observations
from odohil.session.results.exports import FILE_NAMES
from odohil.session.results.report import load_report

from .page import assert_self_contained, parse_page
from .run import run_report
from .session_factory import build_session

FEW_TRIALS = "fewer than 10 trials a design, the planner's minimum for honest intervals"
"""The report session's one doubt: its 6 trials a design."""


def test_report_is_self_contained_and_matches_the_estimate(
    session: tuple[Path, SessionState], tmp_path: Path
) -> None:
    folder, state = session
    assert state.finished
    out = tmp_path / "out"
    # 6 trials a design, below the planner's 10: refused without --force, saying why
    refused = run_report(folder, tmp_path / "refused")
    assert refused.returncode == 3, refused.stderr
    assert "fewer than 10 trials a design" in " ".join(refused.stderr.split())
    assert not (tmp_path / "refused").exists()
    run = run_report(folder, out, "--force")
    assert run.returncode == 0, run.stderr

    # The report writes the same filter files as odohil export (FILE_NAMES).
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["index.html", "parameters.json", *FILE_NAMES.values()]
    )
    page = parse_page(out / "index.html")
    assert_self_contained(page)
    # Every plot is there, inline.
    assert page.figures == [
        "end-points-1",
        "end-points-2",
        "phi1",
        "convergence",
        "model-check",
    ]

    expected = estimate(session_observations(state)).to_json_dict()
    # doubtful for its 6 trials a design alone (below the planner's 10)
    assert expected["verdict"]["status"] == "doubtful"
    assert [r.split(":")[0] for r in expected["verdict"]["reasons"]] == [FEW_TRIALS]
    written = json.loads((out / "parameters.json").read_text())
    # as estimate --json prints it: the estimate, then what the session's trials add
    assert written["flagged_trials"] == [
        t.trial for t in state.completed if not t.clear_cut or t.flag_reason
    ]
    assert written["ambiguous_trials"] == []
    assert any("fewer than 10" in r for r in written["export_refusals"])
    outcome_keys = ("flagged_trials", "ambiguous_trials", "export_refusals")
    estimate_part = {k: v for k, v in written.items() if k not in outcome_keys}
    assert estimate_part == json.loads(json.dumps(expected))

    model = json.loads((out / FILE_NAMES["json"]).read_text())
    params = written["parameters"]
    rates = model["variance_rates"]
    assert rates["heading_rad2_per_m"] == pytest.approx(params["K_theta"]["value"], 1e-12)
    assert rates["along_track_m2_per_m"] == pytest.approx(params["K_rho"]["value"], 1e-12)
    corrections = model["corrections"]
    assert corrections["heading_drift_rad_per_m"]["value"] == pytest.approx(
        params["E_R"]["value"], 1e-12
    )
    assert corrections["distance_scale"]["value"] == pytest.approx(1 + params["E_T"]["value"])
    # Every export is named on the page.
    html = (out / "index.html").read_text()
    assert all(name in html for name in FILE_NAMES.values())


def test_report_converges_over_trials(session: tuple[Path, SessionState], tmp_path: Path) -> None:
    folder, _ = session
    report = load_report(folder)
    assert report.result is not None
    # The estimate exists from the second trial of the first design on, one per trial.
    assert [p.n_trials for p in report.convergence] == list(range(2, 13))
    last = report.convergence[-1]
    final = report.result.params.as_tuple()
    for i in range(4):
        # The incremental and the batch optimum agree to well within a standard error.
        assert abs(last.values[i] - final[i]) < 0.05 * last.stderr[i]


def test_report_without_an_estimate_says_why(tmp_path: Path) -> None:
    folder = tmp_path / "short"
    build_session(folder, "k=1,l=1,n=1", seed=2)
    out = tmp_path / "out"
    refused = run_report(folder, out)
    assert refused.returncode == 3, refused.stderr  # no estimate: as estimate and export
    assert "NO ESTIMATE" in refused.stderr
    assert not out.exists()
    run = run_report(folder, out, "--force")
    assert run.returncode == 0, run.stderr
    assert "No estimate" in (out / "index.html").read_text()
    assert "error" in json.loads((out / "parameters.json").read_text())
    assert replay(read_journal(folder).records).finished


def test_report_of_a_missing_session_fails_cleanly(tmp_path: Path) -> None:
    run = run_report(tmp_path / "nothing", tmp_path / "out")
    assert run.returncode == 2
    assert "journal" in run.stderr


def test_an_untrusted_estimate_is_refused_without_force(bumped: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    run = run_report(bumped, out)
    assert run.returncode == 3, run.stderr
    assert "--force" in run.stderr
    assert "trial 3 (k=1 l=2 m turn)" in run.stderr
    assert not out.exists()


def test_a_forced_report_states_the_verdict_in_every_export(bumped: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    run = run_report(bumped, out, "--force")
    assert run.returncode == 0, run.stderr
    written = json.loads((out / "parameters.json").read_text())
    assert written["verdict"]["status"] == "doubtful"
    assert any("trial 3" in r for r in written["verdict"]["reasons"])
    for name in FILE_NAMES.values():
        text = (out / name).read_text()
        if name.endswith(".yaml"):
            assert text.startswith("# WARNING: this estimate is DOUBTFUL"), name
        else:
            assert json.loads(text)["verdict"]["status"] == "doubtful"
    html = (out / "index.html").read_text()
    assert "Verdict: <strong>doubtful</strong>" in html
    assert "written on request (--force)" in html
    # The flagged trials (the floor marks' solution in doubt) and the trial the
    # robust fit down-weights, listed by trial number.
    state = replay(read_journal(bumped).records)
    flagged = {t.trial for t in state.completed if not t.clear_cut or t.flag_reason}
    assert 3 in flagged
    rows = parse_page(out / "index.html").pointed_out
    assert {n for n, what in rows.items() if "flagged" in what} == flagged
    assert "outlier, down-weighted" in rows[3]


def test_report_exclude_leaves_the_trial_out(bumped: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    run = run_report(bumped, out, "--exclude", "3", "--force")  # 6 trials a design
    assert run.returncode == 0, run.stderr
    written = json.loads((out / "parameters.json").read_text())
    # the outlier left out: doubtful for the 6 trials a design alone
    assert written["verdict"]["status"] == "doubtful"
    assert [r.split(":")[0] for r in written["verdict"]["reasons"]] == [FEW_TRIALS]
    assert written["excluded"] == [3]
    assert written["n_trials"] == 11
    assert json.loads((out / FILE_NAMES["json"]).read_text())["excluded"] == [3]
    rows = parse_page(out / "index.html").pointed_out
    assert rows[3].startswith("excluded")
    assert not any("excluded" in what for n, what in rows.items() if n != 3)

    bad = run_report(bumped, tmp_path / "other", "--exclude", "13")
    assert bad.returncode == 2
    assert "--exclude" in bad.stderr
    assert "1..12" in bad.stderr
