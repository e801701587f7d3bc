"""A folder made once a test run and shared by every xdist worker.

A module-scoped fixture runs once per worker that takes one of its tests:
with ``-n 4`` a calibration the module's tests share can run four times (the
same seeded commands: the same journal). :func:`made_once` runs it once a test
run, in a folder beside the workers' own (under a file lock, so a second
worker waits for the first), and copies it into the caller's folder, which
the caller may then write into.
"""

from __future__ import annotations

import fcntl
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest


def made_once(
    factory: pytest.TempPathFactory, name: str, make: Callable[[Path], object], folder: Path
) -> Path:
    """``make(shared)`` run once a test run, ``shared`` copied into ``folder``.

    Args:
        factory: pytest's ``tmp_path_factory``.
        name: the shared folder's name, unique in the test run.
        make: fills the (new, empty) folder it is given (what it returns is
            not used); its assertions are the first caller's (a later caller
            after a failed ``make`` runs it again).
        folder: where the caller's copy goes (created if missing).

    Returns:
        ``folder``.
    """
    root = factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # the controller's folder, above every worker's
    shared = root / name
    with open(root / f"{name}.lock", "w", encoding="utf-8") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        done = root / f"{name}.done"
        if not done.exists():
            shutil.rmtree(shared, ignore_errors=True)
            shared.mkdir()
            make(shared)
            done.touch()
    shutil.copytree(shared, folder, dirs_exist_ok=True)
    return folder
