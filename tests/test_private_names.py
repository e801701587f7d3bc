"""Issue 32's leftover "pre-flight calls the private Journal._check_not_in_use":
no module of odohil/ or fakes/ reaches into another module's private names
(``_name``), neither by importing one nor through a name it imported
(``Journal._lock``, ``events._table``). A name another module needs is public
(``Journal.check_not_in_use``), or the two are one module's job."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CANDIDATE = re.compile(r"\b(?!self\b|cls\b)\w+\._[a-z]|import[^\n]*\b_[a-z]|^\s+_[a-z]\w*,", re.M)
"""Text that may reach a private name: only modules with some are parsed (cheap)."""


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _findings(text: str, where: str) -> list[str]:
    """Where the module ``text`` (named ``where``) reaches into another module's privates."""
    tree = ast.parse(text, filename=where)
    imported: set[str] = set()
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] not in ("odohil", "fakes"):
                continue
            for alias in node.names:
                if _private(alias.name):
                    found.append(f"{where}:{node.lineno}: imports {node.module}.{alias.name}")
                imported.add(alias.asname or alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] in ("odohil", "fakes"):
                    imported.add(alias.asname or alias.name.split(".")[0])
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and _private(node.attr)
            and isinstance(node.value, ast.Name)
            and node.value.id in imported
        ):
            found.append(f"{where}:{node.lineno}: uses {node.value.id}.{node.attr}")
    return found


def _modules() -> list[Path]:
    return [
        path for package in ("odohil", "fakes") for path in sorted((ROOT / package).rglob("*.py"))
    ]


def test_the_scan_sees_a_private_name_reached_from_outside() -> None:
    probe = ROOT / "odohil" / "session" / "run" / "checks.py"
    text = probe.read_text()
    assert "Journal.check_not_in_use(" in text
    text = text.replace("Journal.check_not_in_use(", "Journal._check_not_in_use(")
    text += "\nfrom odohil.session.journal.file import _fsync_dir\n"
    assert CANDIDATE.search(text)
    found = _findings(text, "checks.py")
    assert any("uses Journal._check_not_in_use" in f for f in found), found
    assert any("imports odohil.session.journal.file._fsync_dir" in f for f in found), found


def test_no_module_reaches_into_another_modules_private_names() -> None:
    found = [
        finding
        for path in _modules()
        if CANDIDATE.search(text := path.read_text())
        for finding in _findings(text, str(path.relative_to(ROOT)))
    ]
    assert not found, "\n".join(found)
