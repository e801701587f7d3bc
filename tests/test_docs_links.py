"""The docs cite files of this repository by relative path: every relative
link in README.md and docs/*.md names a file that exists (and a heading of it,
when it names one), and no doc or docstring names a machine path or a notes
file outside the repository."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\[[^\]]*\]\(\s*([^)\s]+)\s*\)", re.MULTILINE)


def _slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    return {
        _slug(line.lstrip("#"))
        for line in path.read_text(encoding="utf-8").splitlines()
        if line.startswith("#")
    }


def _relative_links(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    return [
        target
        for target in LINK.findall(text)
        if not re.match(r"^[a-z][a-z0-9+.-]*:", target)  # http:, https:, mailto:
    ]


def test_every_relative_link_names_an_existing_file_and_heading() -> None:
    broken = []
    checked = 0
    for doc in DOCS:
        for target in _relative_links(doc):
            checked += 1
            file_part, _, anchor = target.partition("#")
            linked = (doc.parent / file_part).resolve() if file_part else doc
            if not linked.exists():
                broken.append(f"{doc.relative_to(ROOT)}: {target} (no such file)")
            elif anchor and linked.suffix == ".md" and anchor not in _anchors(linked):
                broken.append(f"{doc.relative_to(ROOT)}: {target} (no such heading)")
            elif ROOT not in linked.parents and linked != ROOT:
                broken.append(f"{doc.relative_to(ROOT)}: {target} (outside the repository)")
    assert broken == []
    assert checked > 0


def test_the_link_check_catches_a_broken_link(tmp_path: Path) -> None:
    doc = tmp_path / "a.md"
    doc.write_text("# Title\nsee [b](b.md) and [t](#title) and [x](https://example.org)\n")
    assert _relative_links(doc) == ["b.md", "#title"]
    assert "title" in _anchors(doc)
    assert not (doc.parent / "b.md").exists()


def test_docs_cite_no_machine_path_and_no_outside_notes() -> None:
    sources = [*DOCS, *sorted((ROOT / "odohil").rglob("*.py"))]
    offenders = []
    for path in sources:
        if path.name == "paper-notes.md":
            continue  # says where it was copied from
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if re.search(r"/(?:work|home|Users)/|\bNOTES(\.md)?\b", line):
                offenders.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert offenders == []
