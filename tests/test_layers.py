"""The architecture's layering holds: each layer imports only the layers below it."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ORDER = ["science", "protocol", "driver", "session", "cli"]
BASE = {"odohil", "odohil.errors", "odohil.units"}


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
    return found


@pytest.mark.parametrize("layer", ORDER)
def test_layer_imports_only_layers_below(layer: str) -> None:
    allowed = {f"odohil.{name}" for name in ORDER[: ORDER.index(layer) + 1]}
    offenders = []
    for path in sorted((ROOT / "odohil" / layer).rglob("*.py")):
        for module in _imports(path):
            if layer != "cli" and (module == "fakes" or module.startswith("fakes.")):
                offenders.append(f"{path.name} imports the fake robot ({module})")
            if not module.startswith("odohil") or module in BASE:
                continue
            if not any(module == a or module.startswith(a + ".") for a in allowed):
                offenders.append(f"{path.relative_to(ROOT)} imports {module}")
    assert offenders == []


def test_science_does_no_io() -> None:
    banned = {"serial", "socket", "os", "subprocess", "pathlib", "io", "sys", "typer", "rich"}
    offenders = []
    for path in sorted((ROOT / "odohil" / "science").rglob("*.py")):
        for module in _imports(path):
            if module.split(".")[0] in banned:
                offenders.append(f"{path.name} imports {module}")
        if "print(" in path.read_text() or "open(" in path.read_text():
            offenders.append(f"{path.name} prints or opens files")
    assert offenders == []
