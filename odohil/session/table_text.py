"""A table for people as text: what the session says a table holds (title,
column heads, rows, which columns hold words), drawn by the CLI
(odohil/cli/render.py ``drawn``) the same way for every command."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class TableText:
    """A table's content.

    Attributes:
        title: above the table.
        columns: the column heads.
        rows: the cells, each row as wide as ``columns``.
        words: the columns that hold words (left-aligned; the others hold
            numbers, right-aligned).
        caption: below the table (None: none).
        flagged: cell texts that say a check failed (``FAIL``, ``NO``), shown as alarms.
        title_left: the title stands at the left (else centred).
    """

    title: str
    columns: Sequence[str]
    rows: Sequence[Sequence[str]]
    words: Sequence[str] = ()
    caption: str | None = None
    flagged: Sequence[str] = ()
    title_left: bool = False
