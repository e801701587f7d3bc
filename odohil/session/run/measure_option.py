"""The seam between a session and what measures its trials (``--measure``):
the pose-source registry (odohil/session/measure/registry.py), plus the wizard's
operator, who has no ``--measure`` form (the wizard builds its source itself).

A session's measurement is a registry :class:`MeasureOption`, or None for the
operator.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from odohil.errors import ParameterError, TrialFileError
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.events import OPERATOR
from odohil.session.measure.registry import (
    MeasureOption,
    Preflight,
    check_measure,
    journaled_measure,
    parse_measure,
)
from odohil.session.plans.plan import Plan

__all__ = ["OPERATOR", "MeasureOption", "check", "journal_name", "measure_option", "settings_of"]


def measure_option(
    given: str | None, journaled: str | None, old_settings: Mapping[str, Any]
) -> MeasureOption | None:
    """``--measure`` (``given``), else a resumed session's (its header's
    ``measure`` and settings); None for the operator.

    Raises:
        ParameterError: no pose source takes ``given`` (naming every form),
            or the journaled one is not installed.
    """
    if given is not None:
        return None if given == OPERATOR else parse_measure(given)
    if journaled == OPERATOR:
        return None
    return journaled_measure(journaled or "fake", old_settings)


def check(
    option: MeasureOption | None, description: RobotDescription, plan: Plan, truth: bool
) -> str:
    """The source's pre-flight check (nothing moves, nothing is written) and
    what it is, in words. ``truth``: the fake's true pose can be read."""
    if option is None:
        return "the operator's tape"
    try:
        check_measure(option, Preflight(description, plan, truth))
    except (ParameterError, TrialFileError) as exc:
        if "--measure" in str(exc) or not option.text:
            raise
        raise type(exc)(f"--measure {option.text}: {exc}") from None
    return f"{option.kind}" + (f" ({option.text})" if option.text else "")


def journal_name(option: MeasureOption | None) -> str:
    """The header's ``measure``."""
    return OPERATOR if option is None else option.kind


def settings_of(
    option: MeasureOption | None, old: Mapping[str, Any], given: bool
) -> dict[str, Any]:
    """The header settings the source keeps: a resumed session's, replaced by
    a new ``--measure``'s (``given``); ``trial_file`` is always there (null
    unless the source is a trial file)."""
    kept = {k: v for k, v in old.items() if not given or k not in ("trial_file", "mocap_url")}
    journaled = {} if option is None else option.journal_settings()
    return {"trial_file": None, **kept, **journaled}
