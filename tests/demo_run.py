"""One ``odohil demo --session S`` per test process, shared by the tests that
read its table (tests/cli/test_demo_table.py) and its journal
(tests/session/test_backward_prediction.py): the same command, the same
default seed, so the same session; it ran twice before.

A process of its own, forked from a server that imported odohil once
(tests/forked.py), with ``COLUMNS=160`` so that the table is not wrapped.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from tests import forked

_DONE: dict[str, tuple[subprocess.CompletedProcess[str], Path]] = {}


def demo_run(factory: pytest.TempPathFactory) -> tuple[subprocess.CompletedProcess[str], Path]:
    """The demo's finished process and its session folder (run on first use)."""
    if "demo" not in _DONE:
        session = factory.mktemp("demo") / "s"
        done = forked.completed(
            ["odohil", "demo", "--session", str(session)], 300, {**os.environ, "COLUMNS": "160"}
        )
        _DONE["demo"] = (done, session)
    return _DONE["demo"]
