"""Loading of protocols/create2/golden_vectors.json."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

GOLDEN = Path(__file__).resolve().parents[2] / "protocols" / "create2" / "golden_vectors.json"


def golden(kind: str) -> list[dict[str, Any]]:
    """The golden vectors of one kind: command, reply, frame or wrap."""
    vectors: list[dict[str, Any]] = json.loads(GOLDEN.read_text())["vectors"]
    return [v for v in vectors if v["kind"] == kind]
