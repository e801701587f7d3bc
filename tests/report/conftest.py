"""Sessions shared by the report tests: run once by the engine against the
in-process fake robot."""

from __future__ import annotations

from pathlib import Path

import pytest

from odohil.session.journal.state import SessionState

from .session_factory import build_session

PLAN = "k=1,l=2,n=6;k=4,l=0.5,n=6"


@pytest.fixture(scope="session")
def session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, SessionState]:
    folder = tmp_path_factory.mktemp("report") / "session"
    return folder, build_session(folder, PLAN, seed=5)


@pytest.fixture(scope="session")
def bumped(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A session whose trial 3 was marked 5 cm across the path from the robot."""
    folder = tmp_path_factory.mktemp("bumped") / "session"
    build_session(folder, PLAN, seed=5, bump=(3, 0.05))
    return folder
