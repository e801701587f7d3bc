"""The files the report writes beside ``index.html``: the estimate for other tools.

Each export is an :class:`ExportFile`; :func:`standard_exports` gives the
report's own (``parameters.json`` and ``odometry_covariance.yaml``). More
formats (for ROS and friends) join by passing their files to
:func:`odohil.session.report.write_report`; ``index.html`` lists every export
by name with its description.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from odohil.session.report.data import SessionReport


@dataclass(frozen=True)
class ExportFile:
    """One file written beside ``index.html``.

    Attributes:
        name: its file name in the report folder (no folder part).
        text: its content (UTF-8 text).
        description: what it is, for the report's list of exports.
    """

    name: str
    text: str
    description: str


def standard_exports(report: SessionReport) -> tuple[ExportFile, ...]:
    """``parameters.json`` and ``odometry_covariance.yaml``."""
    return (
        ExportFile(
            "parameters.json",
            json.dumps(parameters_json(report), indent=2) + "\n",
            "the estimate (SI units), as odohil estimate --json prints it",
        ),
        ExportFile(
            "odometry_covariance.yaml",
            covariance_yaml(report),
            "the error model for a sensor-fusion filter",
        ),
    )


def parameters_json(report: SessionReport) -> dict[str, Any]:
    """The estimate's JSON object (SI), or ``{"error": ...}`` without an estimate."""
    if report.result is None:
        return {"error": report.problem, "n_trials": len(report.state.completed)}
    return report.result.to_json_dict()


def covariance_yaml(report: SessionReport) -> str:
    """The odometry error model as a YAML snippet for a sensor-fusion configuration.

    Per metre driven: the heading variance K_theta (rad^2/m) and the
    translation variance K_rho (m^2/m); systematic corrections: heading
    drift E_R (rad per signed metre) and the scale 1 / (1 + E_T).
    """
    result = report.result
    if result is None:
        return f"# odohil: no estimate from this session ({report.problem})\n"
    p = result.params
    se = {e.name: e.stderr for e in result.parameters}
    verdict = result.verdict
    warning = (
        []
        if verdict.trusted
        else [f"# WARNING: this estimate is {verdict.status.upper()}; exported with --force."]
    )
    lines = [
        *warning,
        "# Odometry error model estimated by odohil (Martinelli's four parameters).",
        f"# Session: {report.folder.name}, {result.n_trials} trials, method {result.method}.",
        "odohil_verdict:",
        f"  status: {verdict.status}",
        "  reasons: [" + ", ".join(json.dumps(r) for r in verdict.reasons) + "]",
        "  excluded_trials: [" + ", ".join(str(t) for t in result.excluded) + "]",
        "# Variances grow linearly with the distance driven s (metres):",
        "#   var(heading) = heading_variance_per_m * s,",
        "#   var(position along the path) = translation_variance_per_m * s.",
        "odometry_error_model:",
        "  per_metre_variance:",
        f"    heading_rad2_per_m: {p.k_theta:.6e}  # K_theta, rad^2/m "
        f"(stderr {_num(se['K_theta'])})",
        f"    translation_m2_per_m: {p.k_rho:.6e}  # K_rho, m^2/m = m (stderr {_num(se['K_rho'])})",
        "  systematic:",
        f"    heading_drift_rad_per_m: {p.e_r:.6e}  # E_R, rad per metre of signed "
        f"encoder distance (stderr {_num(se['E_R'])})",
        f"    translation_scale_error: {p.e_t:.6e}  # E_T, no unit: true distance = "
        f"(1 + E_T) * encoder distance (stderr {_num(se['E_T'])})",
        "  corrections:",
        f"    heading_rad_per_m: {p.e_r:.6e}  # add this to the encoder heading per signed metre",
        f"    distance_scale: {1.0 + p.e_t:.9f}  # multiply encoder distances by this",
        "  process_noise_per_metre:  # diagonal, in (x along path m, y across m, yaw rad)",
        f"    - {p.k_rho:.6e}  # m^2 per metre along the path (K_rho)",
        "    - 0.0  # m^2: lateral spread comes from the heading variance",
        f"    - {p.k_theta:.6e}  # rad^2 per metre (K_theta)",
        "",
    ]
    return "\n".join(lines)


def _num(value: float) -> str:
    return f"{value:.3e}" if math.isfinite(value) else "undetermined"
