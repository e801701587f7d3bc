"""``--measure tape`` (or operator, wizard) names no file: the operator's tape
is the wizard's, and the refusal says so instead of "cannot read trial file
tape" (found while building `odohil wizard --validate`, issue 19)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT
from odohil.errors import ParameterError
from odohil.session.measure.registry import parse_measure


@pytest.mark.parametrize("word", ["tape", "operator", "wizard", "Tape"])
def test_an_operator_word_points_to_the_wizard(word: str) -> None:
    with pytest.raises(ParameterError) as refused:
        parse_measure(word)
    said = str(refused.value)
    assert f"--measure {word!r}" in said
    assert "odohil wizard --validate" in said
    assert "trial file" in said  # the accepted forms are still listed


def test_a_file_named_like_the_word_is_still_a_trial_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tape").write_text("dx_m,dy_m,dtheta_rad\n1,0,0\n")
    assert parse_measure("tape").kind == "file"


def test_run_refuses_measure_tape_before_anything_is_written(tmp_path: Path) -> None:
    session = tmp_path / "s"
    done = CliRunner().invoke(
        app,
        ["run", "--robot", "nomad150", "--port", "fakerobot://?seed=1&time_scale=2000",
         "--plan", "k=1,l=2,n=10;k=0.5,l=2,n=10", "--measure", "tape", "--session", str(session)],
    )  # fmt: skip
    assert done.exit_code == EXIT_BAD_INPUT, done.output
    assert "odohil wizard" in " ".join(done.output.replace("│", " ").split())
    assert not session.exists()
