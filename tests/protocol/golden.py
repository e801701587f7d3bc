"""Shared loading of the golden vectors (protocols/nomad/golden_vectors.json)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

GOLDEN = Path(__file__).resolve().parents[2] / "protocols" / "nomad" / "golden_vectors.json"


def golden(direction: str) -> list[dict[str, Any]]:
    """The golden vectors of one direction: request, reply or invalid."""
    vectors: list[dict[str, Any]] = json.loads(GOLDEN.read_text())["vectors"]
    return [v for v in vectors if v["direction"] == direction]
