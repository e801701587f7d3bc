"""The commands that read a source or design an experiment, through typer's
runner in process (issue 18, deliverable 5): they parse, call the session layer
and render; every exit status is the one odohil/cli/exit_codes.py gives, on
inputs whose verdict is known (a trusted simulated file, degenerate rows that
fail, one trial that gives no estimate)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_OK, EXIT_UNTRUSTED
from odohil.cli.render import verdict_text
from odohil.science.estimators.verdict import Status, Verdict
from odohil.session.text.outcome import verdict_line

HEADER = "k,l_m,variant,dx_m,dy_m,dtheta_rad"


def odohil(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "200"})


@pytest.fixture(scope="module")
def trusted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """60 simulated trials of two designs whose estimate is trusted (seeds fixed)."""
    folder = tmp_path_factory.mktemp("sources")
    rows: list[str] = []
    for k, l_m, seed in (("1", "6", "1"), ("20", "0.5", "2")):
        out = folder / f"k{k}.csv"
        done = odohil("simulate", "--k", k, "--l", l_m, "--trials", "30", "--out", out,
                      "--seed", seed, "--segment-m", "0.01")  # fmt: skip
        assert done.exit_code == EXIT_OK, done.output
        rows += out.read_text().splitlines()[1:]
    combined = folder / "trusted.csv"
    combined.write_text("\n".join([HEADER, *rows]) + "\n")
    return combined


@pytest.fixture
def degenerate(tmp_path: Path) -> Path:
    """Identical rows: a degenerate fit, verdict failed."""
    rows = ["1,6,turn,0.01,0.1,-0.04"] * 30 + ["20,0.5,turn,0.002,0.01,-0.07"] * 30
    same = tmp_path / "same.csv"
    same.write_text("\n".join([HEADER, *rows]) + "\n")
    return same


@pytest.fixture
def single(tmp_path: Path) -> Path:
    """One trial: no estimate."""
    one = tmp_path / "one.csv"
    one.write_text(f"{HEADER}\n1,6,turn,0.01,0.1,-0.04\n")
    return one


def test_estimate_trusted_prints_the_verdict_line_and_the_table(trusted: Path) -> None:
    done = odohil("estimate", trusted)
    assert done.exit_code == EXIT_OK, done.output
    assert done.stdout.splitlines()[0] == "verdict: TRUSTED"
    assert "odometry error parameters (robust, 60 trials)" in done.stdout
    as_json = json.loads(odohil("estimate", trusted, "--json").stdout)
    assert as_json["verdict"] == {"status": "trusted", "reasons": []}


def test_estimate_failed_and_no_estimate_exit_3(degenerate: Path, single: Path) -> None:
    failed = odohil("estimate", degenerate)
    assert failed.exit_code == EXIT_UNTRUSTED
    assert failed.stdout.startswith("verdict: FAILED (")
    none = odohil("estimate", single)
    assert none.exit_code == EXIT_UNTRUSTED
    assert none.stdout.startswith("verdict: NO ESTIMATE (")


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (("--exclude", "3,x"), "--exclude"),
        (("--min-rest", "-1"), "--min-rest"),
        (("--max-truth-gap", "0"), "--max-truth-gap"),
    ],
)
@pytest.mark.parametrize("command", ["estimate", "report", "validate"])
def test_source_options_resolved_in_one_place_refuse_bad_values_with_exit_2(
    trusted: Path, tmp_path: Path, command: str, args: tuple[str, ...], named: str
) -> None:
    extra = {"report": ["--out", str(tmp_path / "r")], "validate": ["--path", "square:1"]}
    done = odohil(command, trusted, *extra.get(command, []), *args)
    assert done.exit_code == EXIT_BAD_INPUT, done.output
    assert named in done.stderr
    assert "Traceback" not in done.output


def test_export_refuses_an_imprecise_or_untrusted_estimate_unless_forced(
    trusted: Path, degenerate: Path, single: Path, tmp_path: Path
) -> None:
    out = tmp_path / "p.json"
    imprecise = odohil("export", trusted, "--format", "json", "--out", out)
    assert imprecise.exit_code == EXIT_UNTRUSTED, imprecise.output  # E_T's interval > E_T
    assert "not precise enough to export: the distance scale" in imprecise.stderr
    assert not out.exists()
    forced = odohil("export", trusted, "--format", "json", "--out", out, "--force")
    assert forced.exit_code == EXIT_OK, forced.output
    assert json.loads(out.read_text())["verdict"]["status"] == "trusted"
    for source in (degenerate, single):
        refused = odohil("export", source, "--format", "json", "--out", tmp_path / "no.json")
        assert refused.exit_code == EXIT_UNTRUSTED, refused.output
        assert "refused:" in refused.stderr
        assert not (tmp_path / "no.json").exists()
    nothing = odohil("export", single, "--format", "json", "--force")
    assert nothing.exit_code == EXIT_UNTRUSTED  # no estimate: nothing to export even forced
    assert "there is no estimate" in nothing.stderr


def test_report_refuses_no_estimate_and_writes_when_forced(
    trusted: Path, single: Path, tmp_path: Path
) -> None:
    refused = odohil("report", single, "--out", tmp_path / "none")
    assert refused.exit_code == EXIT_UNTRUSTED
    assert "verdict: NO ESTIMATE" in refused.stderr
    assert not (tmp_path / "none").exists()
    imprecise = odohil("report", trusted, "--out", tmp_path / "ok")
    assert imprecise.exit_code == EXIT_UNTRUSTED
    assert "refused: the estimate is not precise enough" in imprecise.stderr
    done = odohil("report", trusted, "--out", tmp_path / "ok", "--force")
    assert done.exit_code == EXIT_OK, done.output
    assert (tmp_path / "ok" / "index.html").is_file()


def test_validate_refuses_a_failed_calibration_and_bad_alpha(
    degenerate: Path, trusted: Path
) -> None:
    refused = odohil("validate", degenerate, "--path", "square:1", "--robot", "nomad150")
    assert refused.exit_code == EXIT_UNTRUSTED, refused.output
    assert "nothing tested" in refused.stderr
    alpha = odohil("validate", trusted, "--path", "square:1", "--alpha", "0.9")
    assert alpha.exit_code == EXIT_BAD_INPUT
    assert "--alpha must be within (0, 0.5]" in alpha.stderr


def test_validate_prints_the_calibrations_verdict_line_then_its_own(trusted: Path) -> None:
    """Every command that estimates prints the verdict line: validate's is the
    calibration's (stderr), then the validation's (in sample: a pass)."""
    done = odohil("validate", trusted, "--path", f"file:{trusted}", "--robot", "nomad150")
    assert done.exit_code == EXIT_OK, done.output
    assert done.stderr.splitlines()[0] == "verdict: TRUSTED"
    assert done.stdout.startswith("validation: PASS (60 trials of file:")
    # and what that pass rules out, in the paper's units
    assert "what a pass rules out: with probability 90 % the bias tests catch E_R off by" in (
        done.stdout.replace("\n", " ")
    )


def test_import_refuses_a_log_that_is_not_there(tmp_path: Path) -> None:
    done = odohil("import", tmp_path / "nope.csv", "--robot", "nomad150", "--out", tmp_path / "t")
    assert done.exit_code == EXIT_BAD_INPUT
    assert "error:" in done.stderr


@pytest.mark.parametrize(
    "args",
    [
        ("predict", "--k", "1", "--l", "2", "--json"),
        ("covariance", "--k", "1", "--l", "2", "--json"),
        ("covariance", "--side", "1", "--simulate", "20", "--seed", "3", "--json"),
        ("plan", "--budget-m", "100", "--json"),
        ("plan", "--evaluate", "k=1,l=6,n=30;k=20,l=0.5,n=30", "--json"),
    ],
)
def test_design_tools_print_json_and_exit_0(args: tuple[str, ...]) -> None:
    done = odohil(*args)
    assert done.exit_code == EXIT_OK, done.output
    assert isinstance(json.loads(done.stdout), dict)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("predict", "--k", "1", "--l", "2", "--K-theta", "-1"), "--K-theta"),
        (("covariance", "--k", "1", "--side", "2"), "not both"),
        (("plan", "--budget-m", "100", "--evaluate", "k=1,l=6,n=30"), "--evaluate"),
        (("plan",), "--budget-m"),
        (("simulate", "--k", "1", "--l", "2", "--trials", "2", "--out", "/no/such/x.csv"),
         "does not exist"),
    ],
)  # fmt: skip
def test_design_tools_refuse_bad_input_with_exit_2(args: tuple[str, ...], message: str) -> None:
    done = odohil(*args)
    assert done.exit_code == EXIT_BAD_INPUT, done.output
    assert message in " ".join(done.output.replace("│", " ").split())


def test_bash_completion_script_and_completions() -> None:
    # The script for a named shell: `--show-completion` guesses the shell from
    # the process's ancestors (shellingham), which a test must not depend on.
    source = {"_ODOHIL_COMPLETE": "source_bash"}
    script = CliRunner().invoke(app, [], prog_name="odohil", env=source)
    assert script.exit_code == EXIT_OK, script.output
    assert "complete -o default -F _odohil_completion odohil" in script.output
    env = {"_ODOHIL_COMPLETE": "complete_bash", "COMP_WORDS": "odohil est", "COMP_CWORD": "1"}
    words = CliRunner().invoke(app, [], prog_name="odohil", env=env)
    assert words.output.split() == ["estimate"]
    env["COMP_WORDS"], env["COMP_CWORD"] = "odohil estimate --log-f", "2"
    flags = CliRunner().invoke(app, [], prog_name="odohil", env=env)
    assert flags.output.split() == ["--log-format"]


def test_the_top_level_help_offers_completion() -> None:
    shown = odohil("--help").output
    assert "--install-completion" in shown
    assert "--show-completion" in shown


def test_a_usage_error_exits_with_the_tables_bad_input_status() -> None:
    """typer.BadParameter (a usage error) exits with click's status: it must be
    the table's 2, so every bad input says the same."""
    assert typer.BadParameter("x").exit_code == EXIT_BAD_INPUT


@pytest.mark.parametrize(("status", "reasons"), [("trusted", ()), ("doubtful", ("few trials",))])
def test_the_live_panel_shows_the_same_verdict_line_as_estimate(
    status: Status, reasons: tuple[str, ...]
) -> None:
    """The wizard's live panel said "Verdict: doubtful: ..." where every command
    prints "verdict: DOUBTFUL (...)": one renderer now."""
    verdict = Verdict(status, reasons)
    assert verdict_text(verdict).plain == verdict_line(verdict)
    assert verdict_line(verdict).startswith(f"verdict: {status.upper()}")
