"""Grouping trials by design, in one place."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any, TypeVar

from odohil.science.paths import Design

T = TypeVar("T")


def _design_of(item: Any) -> Design:
    design: Design = item.design
    return design


def by_design(
    items: Iterable[T], design_of: Callable[[T], Design] = _design_of
) -> dict[Design, list[T]]:
    """The items grouped by their design (``item.design`` unless ``design_of``
    says otherwise): designs in order of first appearance, each design's items
    in the order given."""
    groups: dict[Design, list[T]] = {}
    for item in items:
        groups.setdefault(design_of(item), []).append(item)
    return groups
