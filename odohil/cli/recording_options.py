"""The options of every command that reads a source in place of a session (``import``,
``estimate``, ``export``, ``report``, ``validate``), declared and resolved in one place:
:func:`source_options` adds them to a command, which receives them typed: ``recording``
(:class:`~odohil.session.trials.logs.ImportOptions`: format, bag topics, time association,
rest thresholds, ``--window-m``), ``selection`` (``--family``/``--direction``: a
:class:`~odohil.session.results.outcome.Selection`), ``exclude`` (numbers of ``--exclude``).
A value the session layer refuses is reported as every bad input is (exit 2, nothing done)."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from enum import StrEnum
from typing import TYPE_CHECKING, Any

from odohil.cli.options import EXCLUDE_HELP, Command, add_options, choices, keyword
from odohil.cli.render import bad_inputs
from odohil.session.progress import TerminalBar
from odohil.session.results.outcome import Selection, parse_exclude
from odohil.session.trials.logs import FORMATS, WINDOW_M_HELP, ImportOptions

if TYPE_CHECKING:
    FormatChoice = StrEnum
else:
    FormatChoice = choices("FormatChoice", FORMATS)
"""The log formats odohil reads (docs/recording.md), from the registry READERS."""


_DEFAULTS = ImportOptions()
_SECONDS = (  # (parameter, flag, field of ImportOptions, help)
    ("max_time_diff", "--max-time-diff", "max_time_diff_s", "TUM, bags: largest stamp "
     "difference of an odometry and ground-truth pair, s."),
    ("time_offset", "--time-offset", "time_offset_s", "TUM, bags: added to the ground "
     "truth's stamps, s."),
    ("min_rest", "--min-rest", "min_rest_s", "Shortest rest between two trials, s."),
    ("min_edge_rest", "--min-edge-rest", "min_edge_rest_s", "Shortest rest averaged at an end "
     "of a trial cut by a trial column or file, s (0: any); without one, its first/last sample."),
    ("max_truth_gap", "--max-truth-gap", "max_truth_gap_s", "Longest time without ground "
     "truth in a trial, s."),
)  # fmt: skip
_SELECTION = (
    ("family", "--family", "Use only the general-path trials of this path family (straight, "
     "spin, arc, square, ...: what `odohil import` lists), e.g. the straight runs of a "
     "recording that also holds spins."),
    ("direction", "--direction", "Use only the general-path trials of this direction "
     "(forward, backward, cw, ccw, mixed)."),
)  # fmt: skip


def _parameters(format_flags: tuple[str, ...], selection: bool) -> list[inspect.Parameter]:
    params = [
        keyword(
            "log_format",
            FormatChoice | None,
            None,
            *format_flags,
            help="The log format of a recording (default: guessed from the paths).",
        ),
        keyword("odom_topic", str, _DEFAULTS.odom_topic, "--odom-topic",
                help="Bags: the odometry topic (nav_msgs/msg/Odometry)."),
        keyword("truth_topic", str, _DEFAULTS.truth_topic, "--truth-topic",
                help="Bags: the ground-truth topic (geometry_msgs/msg/PoseStamped or "
                "nav_msgs/msg/Odometry)."),
    ]  # fmt: skip
    params += [
        keyword(name, float, getattr(_DEFAULTS, field), flag, help=text)
        for name, flag, field, text in _SECONDS
    ] + [keyword("window_m", float | None, None, "--window-m", help=WINDOW_M_HELP)]
    if selection:
        params += [keyword(n, str | None, None, flag, help=text) for n, flag, text in _SELECTION]
    return params


def _resolve(values: dict[str, Any]) -> dict[str, Any]:
    log_format = values.pop("log_format")
    with bad_inputs():
        typed: dict[str, Any] = {
            "recording": ImportOptions(
                format=None if log_format is None else log_format.value,
                odom_topic=values.pop("odom_topic"),
                truth_topic=values.pop("truth_topic"),
                window_m=values.pop("window_m"),
                progress=TerminalBar(),  # stderr, a terminal only, after 2 s
                **{field: values.pop(name) for name, _, field, _ in _SECONDS},
            )
        }
        if "exclude" in values:
            typed["exclude"] = parse_exclude(values.pop("exclude"))
    if "family" in values:
        typed["selection"] = Selection(values.pop("family"), values.pop("direction"))
    return typed


def source_options(
    format_flags: tuple[str, ...] = ("--format", "--log-format"),
    selection: bool = True,
    exclude: bool = True,
) -> Callable[[Command], Command]:
    """Add the recording options (and ``--exclude``, ``--family``/``--direction``
    unless turned off) to a command whose keyword parameters ``recording``,
    ``exclude`` and ``selection`` then receive them typed; a bad value exits 2."""
    added = _parameters(format_flags, selection)
    if exclude:
        added.insert(0, keyword("exclude", str | None, None, "--exclude", help=EXCLUDE_HELP))
    return add_options(added, ("recording", "selection", "exclude"), _resolve)
