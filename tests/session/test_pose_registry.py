"""Pose sources through the ``odohil.pose_sources`` entry-point group (issue 18).

A toy pose source, installed from the test as a distribution of its own (a
``.dist-info`` folder with ``entry_points.txt`` and a module on ``sys.path``,
found by importlib.metadata as an installed package would be), runs a whole
session on the in-process fake robot through ``odohil run`` without a line of
the CLI or the engine knowing it; its session is read back by ``estimate`` and
continued by ``resume``. An unknown ``--measure`` form is refused before
anything moves, naming every accepted form, the registered ones included.
"""

from __future__ import annotations

import json
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.robots import __file__ as robots_init
from odohil.session.journal import events as ev
from odohil.session.journal.file import read_journal
from odohil.session.measure.registry import kind_names, parse_measure

NOMAD = Path(robots_init).with_name("nomad150.toml")
PORT = "fakerobot://?seed=3&time_scale=100"
PLAN = "k=1,l=1,n=10;k=0.5,l=1,n=10"
TOY_MODULE = "toy_odohil_source"

TOY_SOURCE = '''
"""A toy pose source: the fake robot's true pose change plus its own noise."""

import contextlib
from dataclasses import dataclass

from odohil.errors import ParameterError
from odohil.session.measure.kinds import SnapshotTruth
from odohil.session.measure.registry import OpenedSource
from odohil.session.measure.truth import TruthPoseSource

OPENED = []


@dataclass(frozen=True)
class ToySettings:
    sigma_m: float


class Toy:
    name = "toy"
    forms = "toy:SIGMA_M (the fake's true pose with Gaussian noise of SIGMA_M metres)"

    def parse(self, text):
        if not text.startswith("toy:"):
            return None
        try:
            sigma = float(text[4:])
        except ValueError:
            sigma = float("nan")
        if not 0 < sigma < 1:
            raise ParameterError(f"--measure {text!r}: toy:SIGMA_M needs 0 < SIGMA_M < 1")
        return ToySettings(sigma)

    def journal_settings(self, settings):
        return {"toy_sigma_m": settings.sigma_m}

    def from_journal(self, journaled):
        return ToySettings(float(journaled["toy_sigma_m"]))

    def check(self, settings, preflight):
        if not preflight.truth_available:
            raise ParameterError("--measure toy: needs the fake robot's truth")

    @contextlib.contextmanager
    def open(self, settings, ctx):
        OPENED.append("open")
        sigma = (settings.sigma_m, settings.sigma_m, settings.sigma_m)
        try:
            yield OpenedSource(
                lambda link: TruthPoseSource(SnapshotTruth(link.truth), sigma, ctx.seed),
                note="toy source ready",
            )
        finally:
            OPENED.append("closed")


TOY = Toy()
'''


def invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


@pytest.fixture
def toy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The toy pose source installed as the distribution ``toy-odohil-source``
    (only for this test: sys.path and sys.modules are restored)."""
    site = tmp_path / "site"
    info = site / "toy_odohil_source-0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: toy-odohil-source\nVersion: 0\n", encoding="utf-8"
    )
    (info / "entry_points.txt").write_text(
        f"[odohil.pose_sources]\ntoy = {TOY_MODULE}:TOY\n", encoding="utf-8"
    )
    (site / f"{TOY_MODULE}.py").write_text(textwrap.dedent(TOY_SOURCE), encoding="utf-8")
    monkeypatch.syspath_prepend(str(site))
    yield site
    sys.modules.pop(TOY_MODULE, None)


def test_a_toy_pose_source_registered_as_an_entry_point_runs_a_session(toy: Path) -> None:
    assert "toy" in kind_names()
    session = toy.parent / "session"
    ran = invoke(
        "run", "--robot", NOMAD, "--port", PORT, "--measure", "toy:0.001", "--plan", PLAN,
        "--session", session, "--seed", "7",
    )  # fmt: skip
    assert ran.exit_code == 0, ran.output
    assert "verdict: TRUSTED" in ran.output
    assert "toy source ready" in ran.output
    assert sys.modules[TOY_MODULE].OPENED == ["open", "closed"]  # type: ignore[attr-defined]
    records = read_journal(session).records
    header = records[0].data
    assert header["measure"] == "toy"
    assert header["settings"]["toy_sigma_m"] == 0.001
    assert header["settings"]["trial_file"] is None  # the journal's format as for every source
    solved = [r.data for r in records if r.kind == ev.SOLVED]
    assert len(solved) == 20
    assert {s["source"] for s in solved} == {
        "the fake robot's true pose with simulated noise"  # TruthPoseSource, by the toy
    }
    estimated = invoke("estimate", session, "--json")
    assert estimated.exit_code == 0, estimated.output
    assert json.loads(estimated.stdout)["verdict"]["status"] == "trusted"


def test_a_toy_session_resumes_through_its_journaled_settings(toy: Path) -> None:
    session = toy.parent / "session"
    ran = invoke(
        "run", "--robot", NOMAD, "--port", PORT, "--measure", "toy:0.001", "--plan", PLAN,
        "--session", session,
    )  # fmt: skip
    assert ran.exit_code == 0, ran.output
    journal = session / "journal.jsonl"
    lines = journal.read_text(encoding="utf-8").splitlines(keepends=True)
    solved_at = [i for i, line in enumerate(lines) if json.loads(line)["kind"] == ev.SOLVED]
    journal.write_text("".join(lines[: solved_at[9] + 1]), encoding="utf-8")  # after trial 10
    resumed = invoke("resume", session, "--from-here")
    assert resumed.exit_code == 0, resumed.output
    assert "verdict: TRUSTED" in resumed.output
    assert "toy source ready" in resumed.output
    solved = [r for r in read_journal(session).records if r.kind == ev.SOLVED]
    assert [r.data["trial"] for r in solved] == list(range(1, 21))


def test_a_toy_forms_error_is_refused_before_anything_is_written(toy: Path) -> None:
    session = toy.parent / "session"
    ran = invoke(
        "run", "--robot", NOMAD, "--port", PORT, "--measure", "toy:-1", "--plan", PLAN,
        "--session", session,
    )  # fmt: skip
    assert ran.exit_code == 2, ran.output
    assert "toy:SIGMA_M needs 0 < SIGMA_M < 1" in ran.output
    assert not session.exists()


@pytest.mark.parametrize("registered", [False, True])
def test_an_unknown_measure_form_is_refused_naming_every_accepted_form(
    tmp_path: Path, request: pytest.FixtureRequest, registered: bool
) -> None:
    if registered:
        request.getfixturevalue("toy")
    session = tmp_path / "session"
    ran = invoke(
        "run", "--robot", NOMAD, "--port", PORT, "--measure", "udp://10.0.0.5:5555",
        "--plan", PLAN, "--session", session,
    )  # fmt: skip
    assert ran.exit_code == 2, ran.output
    words = " ".join(ran.output.split())
    assert "--measure 'udp://10.0.0.5:5555': no pose source takes this form" in words
    for form in ("`fake`", "tcp://HOST:PORT", "a trial file's path"):
        assert form in words
    assert ("toy:SIGMA_M" in words) == registered
    assert not session.exists()


def test_the_built_in_kinds_parse_as_before() -> None:
    assert (parse_measure("fake").kind, parse_measure("tcp://h:1").kind) == ("fake", "tcp")
    assert parse_measure("trials.csv").kind == "file"
    assert parse_measure("C:/trials.csv").kind == "file"  # a drive letter is no scheme


def test_validate_refuses_fake_without_truth_before_anything_moves(tmp_path: Path) -> None:
    """The fake's pre-flight check is the registry's, the same for run and
    validate: no truth channel is bad input (exit 2) before the port opens
    (validate said exit 1 from inside the connection before)."""
    session = tmp_path / "calibration"
    ran = invoke(
        "run", "--robot", NOMAD, "--port", PORT, "--measure", "fake", "--plan", PLAN,
        "--session", session,
    )  # fmt: skip
    assert ran.exit_code == 0, ran.output
    out = tmp_path / "validation"
    checked = invoke(
        "validate", session, "--path", "forth-back:2,0.5,reverse", "--trials", "2",
        "--measure", "fake", "--port", str(tmp_path / "no-such-port"), "--out", out,
    )  # fmt: skip
    assert checked.exit_code == 2, checked.output
    assert "--measure fake needs the fake robot's truth side channel" in " ".join(
        checked.output.split()
    )
    assert not out.exists()
