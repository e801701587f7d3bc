"""One place decides whether a fake robot carries a truth side channel and
which client reads it: the robot backend declares it (odohil/session/robots/registry.py
``fake_hooks``), so run, resume and validate agree on both robots (issue 18).

The fake Create 2 runs as a process on a pty where the pty is the point (the
truth socket); the commands run in process through typer's runner.
"""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner, Result

from fakes.create2.process import Create2Process
from odohil.cli.app import app
from odohil.session.robots.registry import fake_hooks

FAKE = "fakecreate2://?seed=3&time_scale=10&max_gap_ms=15&skip_waits=1"
"""The in-process fake Create 2. Its clock is the wall clock unless ``max_gap_ms``
bounds the step between two host calls (fakes/create2/clock.py): without it, a
test worker descheduled for a few milliseconds on a busy machine (``-n 4`` on 2
cores) let a validation leg drive on, 37 counts past its target against a
tolerance of 22, and validate exit 1 ("leg -0.5 m ended +37 ... counts from its
target"). With it, the fake's time advances in bounded steps between the
driver's calls, however late they come, as a real robot's host would see it.
``skip_waits=1``: a read waiting for the next stream frame moves the fake's
clock to it instead of sleeping (the same frames at the same simulated times)."""


def invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


def test_each_backend_declares_its_fake_and_truth_client() -> None:
    nomad, create2 = fake_hooks("nomad150"), fake_hooks("create2")
    assert nomad is not None
    assert create2 is not None
    assert (nomad.url_scheme, create2.url_scheme) == ("fakerobot:", "fakecreate2:")
    assert nomad.truth_client_class().__name__ == "TruthClient"
    assert create2.truth_client_class().__name__ == "Create2TruthClient"


def test_run_reads_the_create2_truth_socket_and_validate_accepts_its_fake_url(
    tmp_path: Path,
) -> None:
    session = tmp_path / "s"
    with Create2Process(["--seed", "3", "--time-scale", "10"]) as fake:
        ran = invoke(
            "run", "--robot", "create2", "--port", fake.device, "--measure", "fake",
            "--truth-socket", fake.truth_socket, "--plan", "k=0.5,l=1,n=2;k=1,l=1,n=2",
            "--allow-few-trials", "--session", session,
        )  # fmt: skip
    assert ran.exception is None or isinstance(ran.exception, SystemExit), repr(ran.exception)
    # finished; 2 trials a design: doubtful (below the planner's minimum), nothing else
    assert ran.exit_code == 3, ran.output
    assert "verdict: DOUBTFUL" in ran.output
    assert "fewer than 10 trials a design" in ran.output
    checked = invoke(
        "validate", session, "--path", "forth-back:2,0.5,reverse", "--trials", "2",
        "--measure", "fake", "--port", FAKE, "--json", "--force",
    )  # fmt: skip
    assert "truth side channel" not in checked.output
    verdict = json.loads(checked.output[checked.output.index("{") :])
    # both trials driven and measured; a trial whose floor marks fit two poses
    # is left out and named (seen once in CI under 4 workers, where the
    # real-time fake's draws differ: a 6 mm forth-and-back pose change)
    assert verdict["n_trials"] + len(verdict["left_out_ambiguous"]) == 2, checked.output
    # The claim is that validate drives the fake URL and reads its truth; its
    # statistical verdict on a four-trial calibration is not: that calibration's
    # K_rho interval spans a factor of 30 and the validation's prediction takes
    # the spread at the point estimate (odohil/science/validation.py: the delta
    # method leaves the spread's uncertainty out), so on a busy host, where the
    # real-time fake's draws differ, a low K_rho now and then fails two trials
    # whose x spread it underpredicts (seen once: x mean residual -12.5 mm, SE
    # 1.9 mm). The exit status must be the verdict's, exactly.
    status = verdict["verdict"]["status"]
    assert checked.exit_code == {"pass": 0, "fail": 3}[status], checked.output
