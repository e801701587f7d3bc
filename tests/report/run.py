"""Run ``odohil report`` as a user does."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def run_report(session: Path, out: Path, *more: str) -> subprocess.CompletedProcess[str]:
    """``odohil report SESSION --out OUT [more...]`` in a fresh interpreter."""
    return subprocess.run(
        [sys.executable, "-m", "odohil", "report", str(session), "--out", str(out), *more],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
