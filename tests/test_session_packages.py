"""odohil/session's house plan holds (docs/architecture.md): its subpackages
form a stack, each importing only those below it; the ground modules import
nothing of the session; no module of odohil is in an import circle (counting
imports under ``TYPE_CHECKING`` and inside functions); and a name one
subpackage takes from another is in that subpackage's face (its
``__init__``'s ``__all__``, or its module's own ``__all__``)."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "odohil" / "session"

FLOORS = [
    {"robots"},
    {"plans"},
    {"trials"},
    {"journal"},
    {"measure", "results"},
    {"run"},
    {"text"},
    {"commands"},
    {"wizard"},
]
"""The subpackages from the bottom up; two on one floor do not import each other."""

GROUND = {"bounded_io", "signals", "table_text", "plugins", "addresses", "progress"}
"""The modules directly in odohil/session/: they import nothing of the session."""

FLOOR = {package: level for level, floor in enumerate(FLOORS) for package in floor}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {
    _module_name(path): path
    for top in ("odohil", "fakes")
    for path in sorted((ROOT / top).rglob("*.py"))
}


@functools.cache
def _imports(path: Path) -> tuple[tuple[str, str | None], ...]:
    """Every (module, name) ``path`` imports, anywhere in it (name None for
    ``import module``; a submodule imported by name is the module)."""
    found: list[tuple[str, str | None]] = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, None) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                found.append((sub, None) if sub in MODULES else (node.module, alias.name))
    return tuple(found)


def _package(module: str) -> str | None:
    """The session subpackage (or ground module) ``module`` is in."""
    parts = module.split(".")
    if parts[:2] != ["odohil", "session"] or len(parts) < 3:
        return None
    return parts[2]


def test_the_session_has_its_subpackages_and_ground_modules() -> None:
    found = {p.stem for p in SESSION.glob("*.py")} - {"__init__"}
    assert found == GROUND
    assert {p.parent.name for p in SESSION.glob("*/__init__.py")} == set(FLOOR)


def test_no_session_module_imports_one_above_it() -> None:
    offenders = []
    for module, path in MODULES.items():
        own = _package(module)
        if own is None:
            continue
        for imported, _ in _imports(path):
            other = _package(imported)
            if other is None or other == own:
                continue
            if own in GROUND:
                offenders.append(f"ground {module} imports {imported}")
            elif other not in GROUND and FLOOR[other] >= FLOOR[own]:
                offenders.append(f"{module} ({own}) imports {imported} ({other})")
    assert offenders == []


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                on_stack.discard(top)
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_module_of_odohil_is_in_an_import_circle() -> None:
    graph = {
        module: {m for m, _ in _imports(path) if m in MODULES and m != module}
        for module, path in MODULES.items()
    }
    assert _cycles(graph) == []


@functools.cache
def _face(module: str) -> frozenset[str]:
    """The ``__all__`` of ``module`` (empty without one)."""
    for node in ast.parse(MODULES[module].read_text()).body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
        ):
            return frozenset(ast.literal_eval(node.value))
    return frozenset()


@pytest.mark.parametrize("package", sorted(FLOOR))
def test_a_name_taken_from_a_subpackage_is_in_its_face(package: str) -> None:
    face = _face(f"odohil.session.{package}")
    offenders = []
    for module, path in MODULES.items():
        if _package(module) == package:
            continue
        for imported, name in _imports(path):
            if name is None or _package(imported) != package:
                continue
            if name not in face and name not in _face(imported):
                offenders.append(
                    f"{module} imports {name} from {imported}: not in the __all__ of "
                    f"odohil.session.{package} nor of its module"
                )
    assert offenders == []
