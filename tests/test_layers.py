"""The architecture's layering holds: each layer imports only the layers below it;
the session names no robot; protocol and driver have one subpackage per robot
protocol, which do not import each other."""

from __future__ import annotations

import ast
import tomllib
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


def test_session_names_no_robot_protocol() -> None:
    """The session owns Robot and PoseSource and names no robot (issue 10)."""
    offenders = [
        str(path.relative_to(ROOT))
        for path in sorted((ROOT / "odohil" / "session").rglob("*.py"))
        if "nomad" in path.read_text().lower()
    ]
    assert offenders == []


def _subpackages(layer: str) -> set[str]:
    return {p.parent.name for p in (ROOT / "odohil" / layer).glob("*/__init__.py")}


SHARED_DRIVER_MODULES = {"__init__", "odometry", "port", "guardian", "step_limit", "stopping"}
"""What the driver layer shares between its backends (guardian: the stop if odohil dies;
step_limit: the time limit of a leg or a turn; stopping: stop-and-confirm, settle and
the stop on any failure)."""

SHARED_PROTOCOL_MODULES = {"__init__", "numbers"}
"""What the protocol layer shares between its robot protocols (wire integers)."""


def test_protocol_and_driver_have_one_subpackage_per_robot_protocol() -> None:
    protocols = _subpackages("protocol")
    assert protocols, "odohil/protocol has no robot protocol subpackage"
    top_protocol = {p.stem for p in (ROOT / "odohil" / "protocol").glob("*.py")}
    assert top_protocol <= SHARED_PROTOCOL_MODULES, "protocol code lives in its robot's subpackage"
    assert _subpackages("driver") == protocols
    top_driver = {p.stem for p in (ROOT / "odohil" / "driver").glob("*.py")}
    assert top_driver <= SHARED_DRIVER_MODULES, "backend code lives in its robot's subpackage"


@pytest.mark.parametrize("layer", ["protocol", "driver"])
def test_robot_subpackages_do_not_import_each_other(layer: str) -> None:
    names = _subpackages("protocol") | _subpackages("driver")
    offenders = []
    for path in sorted((ROOT / "odohil" / layer).rglob("*.py")):
        rel = path.relative_to(ROOT / "odohil" / layer)
        own = rel.parts[0] if len(rel.parts) > 1 else None  # None: shared module
        for module in _imports(path):
            parts = module.split(".")
            robot_module = len(parts) >= 3 and parts[:2] in (
                ["odohil", "protocol"],
                ["odohil", "driver"],
            )
            if robot_module and parts[2] in names and parts[2] != own:
                offenders.append(f"{path.relative_to(ROOT)} imports {module}")
    assert offenders == []


def test_every_driver_backend_is_registered_by_name() -> None:
    """Backends are found by name through the odohil.robots entry points."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    entries = project["project"]["entry-points"]["odohil.robots"]
    registered = {value.split(":")[0].split(".")[2] for value in entries.values()}
    assert registered == _subpackages("driver")
