"""The console script running one command imports that command's module only:
``odohil emulate`` and ``odohil simulate`` start without the estimators (and
no command imports scipy.stats or scipy.optimize at its start), and every command is still there
for ``--help``, a typo and an in-process import (odohil/cli/app.py)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

_PROBE = """
import runpy, sys
sys.argv = ["odohil", *sys.argv[1:]]
try:
    runpy.run_module("odohil", run_name="__main__")
except SystemExit:
    pass
from odohil.cli.app import COMMAND_MODULES
print("STATS:", "scipy.stats" in sys.modules, "RUN:", "odohil.cli.run" in sys.modules,
      "OPTIMIZE:", "scipy.optimize" in sys.modules, "SPECIAL:", "scipy.special" in sys.modules,
      "COMMANDS:", sum(f"odohil.cli.{name}" in sys.modules for name in COMMAND_MODULES))
"""


def _probe(*args: str, usage: bool = True) -> list[str]:
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, *args], capture_output=True, text=True, timeout=60
    )
    assert ("Usage" in done.stdout) is usage, done.stderr
    return done.stdout.strip().splitlines()[-1].split()


@pytest.mark.parametrize("command", ["emulate", "simulate"])
def test_a_light_command_loads_neither_the_estimators_nor_scipy_stats(command: str) -> None:
    assert _probe(command, "--help")[:4] == ["STATS:", "False", "RUN:", "False"]


def test_the_top_level_help_and_an_import_still_have_every_command() -> None:
    assert _probe("--help")[2:4] == ["RUN:", "True"]
    from odohil.cli.app import COMMAND_MODULES, app

    names = {command.name for command in app.registered_commands}
    assert len(names) == len(COMMAND_MODULES)
    assert {"emulate", "run", "import", "wizard"} <= names


def test_no_command_imports_scipy_stats_or_scipy_optimize_at_its_start() -> None:
    """Every command's module loaded (``--help``), and neither scipy.stats (about
    1 s of CPU; odohil/science/distributions.py has what the package needs)
    nor scipy.optimize (0.7 s; imported where the joint fit falls back to it)
    nor scipy.special (0.3 s; imported at the first probability computed)."""
    assert _probe("--help")[:8] == [
        "STATS:", "False", "RUN:", "True", "OPTIMIZE:", "False", "SPECIAL:", "False"
    ]  # fmt: skip


def test_a_refused_option_computes_no_probability(tmp_path: Path) -> None:
    """A run refused for a bad ``--plan`` (exit 2) loads no scipy.special."""
    args = ["run", "--robot", "nomad150", "--measure", "fake", "--plan", "k=1,l=zz,n=3"]
    more = ["--port", "fakerobot://", "--session", str(tmp_path / "s")]
    assert _probe(*args, *more, usage=False)[6:8] == ["SPECIAL:", "False"]
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("flag", ["--version", "-V"])
def test_the_version_loads_no_command(flag: str) -> None:
    """``odohil --version`` prints and exits before any command is looked at:
    it imports no command's module (odohil/cli/app.py)."""
    assert _probe(flag, usage=False)[-2:] == ["COMMANDS:", "0"]
