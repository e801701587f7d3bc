"""Pose sources: where a trial's real pose change comes from (``--measure``).

- protocol.py: :class:`PoseSource`, :class:`TrialContext`, :class:`MeasuredPose`;
- registry.py: the ``odohil.pose_sources`` kinds by name (the built-in ones
  named by string in odohil/session/plugins.py, so the registry imports none);
- kinds.py: the built-in kinds ``fake``, ``file`` and ``tcp``;
- plausibility.py: a measured pose against the encoders and the model;
- truth.py: the fake robot's true pose; files.py: trial and pose files as poses;
- tape/: the tape with the floor-marks solver (source.py), where its
  distances come from (distances.py) and its journal records (records.py);
- mocap/: motion capture over tcp.

The face is protocol.py's and registry.py's; the sources are imported from
their modules.
"""

from odohil.session.measure.protocol import (
    Covariance3,
    MeasuredPose,
    MeasurementLog,
    Pose,
    PoseSource,
    TrialContext,
    as_covariance,
    as_pose,
)
from odohil.session.measure.registry import (
    Connection,
    MeasureOption,
    OpenContext,
    OpenedSource,
    PoseSourceKind,
    Preflight,
    check_measure,
    find_kind,
    journaled_measure,
    kind_names,
    kinds,
    open_measure,
    parse_measure,
)

__all__ = [
    "Connection",
    "Covariance3",
    "MeasureOption",
    "MeasuredPose",
    "MeasurementLog",
    "OpenContext",
    "OpenedSource",
    "Pose",
    "PoseSource",
    "PoseSourceKind",
    "Preflight",
    "TrialContext",
    "as_covariance",
    "as_pose",
    "check_measure",
    "find_kind",
    "journaled_measure",
    "kind_names",
    "kinds",
    "open_measure",
    "parse_measure",
]
