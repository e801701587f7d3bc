"""``--exclude N,...``: trial numbers to leave out of an estimate (a view; the
journal or file keeps every trial)."""

from __future__ import annotations

from odohil.errors import MeasurementError
from odohil.session.outcome import check_exclude

__all__ = ["EXCLUDE_HELP", "check_exclude", "parse_exclude"]

EXCLUDE_HELP = (
    "Trial numbers to leave out of the estimate, comma-separated (e.g. 3,17); "
    "the journal and files keep every trial."
)


def parse_exclude(text: str | None) -> frozenset[int]:
    """The trial numbers of ``--exclude`` (empty for None or "").

    Raises:
        MeasurementError: not a comma-separated list of positive integers
            (the message names ``--exclude``).
    """
    if text is None or not text.strip():
        return frozenset()
    numbers: set[int] = set()
    for part in text.split(","):
        item = part.strip()
        if not item.isdigit() or int(item) < 1:
            raise MeasurementError(
                f"--exclude: {item!r} is not a trial number; give positive integers "
                "separated by commas, e.g. --exclude 3,17"
            )
        numbers.add(int(item))
    return frozenset(numbers)
