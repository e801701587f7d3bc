"""Run ``odohil report`` as a user does."""

from __future__ import annotations

import subprocess
from pathlib import Path

from tests import forked


def run_report(session: Path, out: Path, *more: str) -> subprocess.CompletedProcess[str]:
    """``odohil report SESSION --out OUT [more...]`` in a process of its own, forked
    from a server that imported odohil's run and resume once (tests/forked.py): the
    report's own imports (matplotlib) happen in that process, as in a fresh one."""
    return forked.completed(["odohil", "report", str(session), "--out", str(out), *more], 120)
