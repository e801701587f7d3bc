"""Options of commands that read a recorded log (``odohil import``, and
``estimate``, ``export``, ``validate``, which take a recording in place of a
trial file): the format, the bag topics, the time association and the rest
thresholds, as Annotated types to declare, and :func:`import_options` to
gather them; ``--family``/``--direction`` select general-path trials
(:class:`odohil.session.outcome.Selection`)."""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated

import typer

from odohil.science.rest_cutting import MIN_EDGE_REST_S, MIN_REST_S
from odohil.session.logs import ImportOptions
from odohil.session.logs.recording import DEFAULT_MAX_TIME_DIFF_S, MAX_TRUTH_GAP_S


class FormatChoice(StrEnum):
    """The log formats odohil reads (docs/recording.md)."""

    csv = "csv"
    tum = "tum"
    rosbag = "rosbag"
    optiodom = "optiodom"


LogFormatOption = Annotated[
    FormatChoice | None,
    typer.Option(
        "--format", "--log-format", help="The log format (default: guessed from the paths)."
    ),
]
LogFormatOnlyOption = Annotated[
    FormatChoice | None,
    typer.Option(
        "--log-format",
        help="The log format of a recording (default: guessed from the paths).",
    ),
]
"""``odohil export``, whose ``--format`` is the export's."""
OdomTopicOption = Annotated[
    str, typer.Option("--odom-topic", help="Bags: the odometry topic (nav_msgs/msg/Odometry).")
]
TruthTopicOption = Annotated[
    str,
    typer.Option(
        "--truth-topic",
        help="Bags: the ground-truth topic (geometry_msgs/msg/PoseStamped or "
        "nav_msgs/msg/Odometry).",
    ),
]
MaxTimeDiffOption = Annotated[
    float,
    typer.Option(
        "--max-time-diff",
        help="TUM, bags: largest stamp difference of an odometry and ground-truth pair, s.",
    ),
]
TimeOffsetOption = Annotated[
    float, typer.Option("--time-offset", help="TUM, bags: added to the ground truth's stamps, s.")
]
MinRestOption = Annotated[
    float, typer.Option("--min-rest", help="Shortest rest between two trials, s.")
]
MinEdgeRestOption = Annotated[
    float,
    typer.Option(
        "--min-edge-rest",
        help="Shortest rest at either end of a trial cut by a trial column or file, s.",
    ),
]
MaxTruthGapOption = Annotated[
    float, typer.Option("--max-truth-gap", help="Longest time without ground truth in a trial, s.")
]

FamilyOption = Annotated[
    str | None,
    typer.Option(
        "--family",
        help="Use only the general-path trials of this path family (straight, spin, arc, "
        "square, ...: what `odohil import` lists), e.g. the straight runs of a recording "
        "that also holds spins.",
    ),
]
DirectionOption = Annotated[
    str | None,
    typer.Option(
        "--direction",
        help="Use only the general-path trials of this direction (forward, backward, cw, "
        "ccw, mixed).",
    ),
]

ODOM_TOPIC_DEFAULT = ImportOptions().odom_topic
TRUTH_TOPIC_DEFAULT = ImportOptions().truth_topic
MAX_TIME_DIFF_DEFAULT = DEFAULT_MAX_TIME_DIFF_S
MIN_REST_DEFAULT = MIN_REST_S
MIN_EDGE_REST_DEFAULT = MIN_EDGE_REST_S
MAX_TRUTH_GAP_DEFAULT = MAX_TRUTH_GAP_S


def import_options(
    log_format: FormatChoice | None,
    odom_topic: str,
    truth_topic: str,
    max_time_diff: float,
    time_offset: float,
    min_rest: float,
    min_edge_rest: float,
    max_truth_gap: float,
) -> ImportOptions:
    """The options as the session layer takes them.

    Raises:
        ParameterError: a time that is not positive (or not finite); the
            message names the option.
    """
    return ImportOptions(
        format=None if log_format is None else log_format.value,
        odom_topic=odom_topic,
        truth_topic=truth_topic,
        max_time_diff_s=max_time_diff,
        time_offset_s=time_offset,
        min_rest_s=min_rest,
        min_edge_rest_s=min_edge_rest,
        max_truth_gap_s=max_truth_gap,
    )
