"""Issue 11's friction: one unit convention (``--units paper|si``, the same
default everywhere, labels from odohil/units.py), right plurals, the same
option names across commands, and the README's ``covariance`` call."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path
from typing import Any

import pytest
import typer

from odohil import units
from odohil.cli.app import app
from tests import forked

ROOT = Path(__file__).resolve().parents[2]
PRINTS_PARAMETERS = ("estimate", "run", "resume", "demo", "wizard", "predict", "covariance")


def _commands() -> dict[str, Any]:
    group: Any = typer.main.get_command(app)
    return dict(group.commands)


def _options(command: Any) -> dict[str, Any]:
    return {
        name: param
        for param in command.params
        if param.param_type_name == "option"
        for name in param.opts
    }


@pytest.mark.parametrize("name", PRINTS_PARAMETERS)
def test_every_command_that_prints_parameters_takes_units_with_the_same_default(
    name: str,
) -> None:
    option = _options(_commands()[name]).get("--units")
    assert option is not None, f"odohil {name} has no --units"
    assert str(option.default) == units.DEFAULT_UNIT_SYSTEM == "paper"


def test_no_option_differs_from_another_only_by_its_unit_suffix() -> None:
    """Before: wizard --max-leg against plan --max-leg-m."""
    seen = {opt: cmd for cmd, c in _commands().items() for opt in _options(c)}
    clashes = [(opt, seen[opt], opt + "-m", seen[opt + "-m"]) for opt in seen if opt + "-m" in seen]
    assert clashes == []
    assert "--max-leg-m" in _options(_commands()["wizard"])


def test_unit_labels_never_show_1_as_a_unit() -> None:
    for system in units.UNIT_SYSTEMS:
        for name in ("E_R", "E_T", "K_theta", "K_rho"):
            assert units.parameter_unit(name, system) != "1"
        assert units.unit_column("E_T", system) == "(no unit)"
        assert units.with_unit("-0.02", units.parameter_unit("E_T", system)) == "-0.02"
    assert units.product_unit("m", "m") == "m^2"
    assert units.product_unit("m", "rad") == "m rad"


def test_plural() -> None:
    assert units.plural(1, "trial") == "1 trial"
    assert units.plural(0, "trial") == "0 trials"
    assert units.plural(2, "more trial") == "2 more trials"
    assert units.plural(1, "more trial") == "1 more trial"
    assert units.plural_noun(1, "distance") == "distance"


def test_no_message_counts_trials_by_hand() -> None:
    """Before: "1 more trials", "(1 trials remain", "Session complete: 1 trials",
    "about 1 more trials of": every count of trials goes through units.plural."""
    hand_made = re.compile(r"\{[^{}]*\}\s+(more )?trials\b")
    found = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
        for path in sorted((ROOT / "odohil").rglob("*.py"))
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if hand_made.search(line)
    ]
    assert found == []


def _odohil(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "COLUMNS": "200"}
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    return forked.completed(["odohil", *args], 60, env)


def test_the_readme_covariance_call_works() -> None:
    """Before: ``odohil covariance --k 1 --l 6`` failed with "Missing option '--path'"."""
    readme = (ROOT / "README.md").read_text()
    assert "`odohil covariance (--k K --l L \\| --side S)" in readme
    assert "odohil covariance --k 1 --l 6" in readme
    for args in (["--k", "1", "--l", "6"], ["--side", "3"]):
        done = _odohil("covariance", *args)
        assert done.returncode == 0, done.stderr
        assert "(m m)" not in done.stdout
        assert "(m^2)" in done.stdout
        assert "deg/m" in done.stdout
    both = _odohil("covariance", "--k", "1", "--l", "6", "--side", "3")
    assert both.returncode == 2
    assert "not both" in both.stderr


def test_predict_and_covariance_print_parameters_in_the_chosen_units() -> None:
    for command in (["predict", "--k", "1", "--l", "6"], ["covariance", "--k", "1", "--l", "6"]):
        paper = _odohil(*command)
        si = _odohil(*command, "--units", "si")
        assert "E_R = -0.202 deg/m" in paper.stdout
        assert "E_R = -0.003526 rad/m" in si.stdout
        assert "E_T = -0.02," in si.stdout  # a plain number: no "1" after it
