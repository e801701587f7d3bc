"""The export files: an estimate as the text a fusion stack's configuration takes.

The numbers come from :mod:`odohil.science.exports`; this module only lays
them out, as ROS 2 parameter files (``node_name: ros__parameters: ...``) for
diff_drive_controller, robot_localization and Nav2 AMCL, a nav_msgs/Odometry
covariance, and a JSON document (SI). Every file states the estimate's
verdict, every linearisation (as a comment, and as a key of an
``odohil_export`` block where the format is a parameter file), and the
entries raised to the variance floor.

YAML is written by :func:`yaml_scalar` and a few line helpers, not a library:
the files are flat (maps of numbers and lists of numbers), and every float is
written with a decimal point and a signed exponent so that YAML 1.1 parsers
(libyaml, which ROS's parameter parser uses, and PyYAML) read a float, not a
string. The tests read every file back with PyYAML.

:func:`write_exports` writes all formats into a folder, :func:`export_files`
gives them as the report's ``ExportFile`` values (``odohil report`` passes them
to ``write_report(..., extra_exports=...)``), :func:`export_text` gives one
format's text (``odohil export``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from odohil import units
from odohil.errors import ParameterError
from odohil.science.estimators.result import EstimateResult
from odohil.science.exports import (
    ROBOT_LOCALIZATION_STATES,
    UNOBSERVED_VARIANCE,
    VARIANCE_FLOOR,
    Linearisation,
    amcl_alphas,
    corrections,
    diff_drive_covariance,
    odometry_covariance,
    parameter_covariance,
    process_noise,
    step_covariance,
    turn_errors,
)
from odohil.session.results.report.exports import ExportFile

__all__ = [
    "EXPORT_FORMATS",
    "FORMATS",
    "ExportFormat",
    "export_files",
    "export_text",
]

DIFF_DRIVE_NODE = "diff_drive_controller"
ROBOT_LOCALIZATION_NODE = "ekf_filter_node"
AMCL_NODE = "amcl"
EXPORT_NODE = "odohil_export"
_PER_LINE = 6


def yaml_scalar(value: float | int | bool | str) -> str:
    """One YAML scalar: floats with a decimal point and a signed exponent when
    they have one (``1.0e-06``), strings double-quoted (JSON escapes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ParameterError(f"cannot export a non-finite number ({value!r})")
        text = repr(value)
        mantissa, sep, exponent = text.partition("e")
        if "." not in mantissa:
            mantissa += ".0"
        return mantissa + (sep + exponent if sep else "")
    return json.dumps(value)


def yaml_list(values: Sequence[float], indent: int) -> str:
    """A flow sequence of floats, ``_PER_LINE`` a line, continuation lines
    indented by ``indent`` spaces."""
    items = [yaml_scalar(float(v)) for v in values]
    rows = [", ".join(items[i : i + _PER_LINE]) for i in range(0, len(items), _PER_LINE)]
    return "[" + (",\n" + " " * indent).join(rows) + "]"


def _header(fmt: str, result: EstimateResult, source: str, what: str) -> list[str]:
    verdict = result.verdict
    lines = []
    if not verdict.trusted:
        lines += [
            f"# WARNING: this estimate is {verdict.status.upper()}; exported with --force.",
            *[f"#   reason: {r}" for r in verdict.reasons],
        ]
    p = result.params
    lines += [
        f"# odohil export, format {fmt}: {what}",
        f"# From {source or 'an estimate'}: {units.plural(result.n_trials, 'trial')}, "
        f"method {result.method}, "
        f"verdict {verdict.status}.",
        f"# Model (SI): E_R {p.e_r:.6g} rad/m, E_T {p.e_t:.6g}, K_theta {p.k_theta:.6g} rad^2/m, "
        f"K_rho {p.k_rho:.6g} m; docs/exports.md gives every formula.",
    ]
    return lines


def _corrections_comment(result: EstimateResult) -> list[str]:
    c = corrections(result)
    return [
        "# Systematic corrections, to apply in the odometry itself (no key here takes them):",
        f"#   distance scale 1 + E_T = {c.distance_scale:.6f} "
        f"(stderr {c.distance_scale_stderr:.2g}): multiply encoder distances by it;",
        f"#   heading drift E_R = {c.heading_drift_rad_per_m:.6g} rad per signed metre "
        f"(stderr {c.heading_drift_stderr:.2g}): add it to the encoder heading.",
        *_turn_comment(result),
    ]


def _turn_comment(result: EstimateResult) -> list[str]:
    """The turn errors of a general-path fit: no key of any consumer takes
    them, so the file says so (docs/exports.md)."""
    found = turn_errors(result)
    if not found:
        return []
    lines = ["# Turn errors (turns_exact = false; no key here takes them, apply in the odometry):"]
    for name, value, stderr in found:
        if name == "K_spin":
            lines.append(
                f"#   K_spin = {value:.6g} rad^2/rad (stderr {stderr:.2g}): heading variance "
                "per radian turned in place, not in the covariances above;"
            )
        else:
            lines.append(
                f"#   {name} = {value:.6g} (stderr {stderr:.2g}): multiply the encoder's "
                "turned angle by 1 + it;"
            )
    return lines


def _floor_comment(floored: Sequence[str]) -> list[str]:
    if not floored:
        return []
    return [
        f"# Raised to the variance floor {VARIANCE_FLOOR:g} (the model gives less; a filter needs "
        f"a positive variance): {', '.join(floored)}."
    ]


def _export_block(fmt: str, result: EstimateResult, keys: dict[str, float | str]) -> list[str]:
    """A second node of the parameter file holding what the export assumed
    (no controller reads it)."""
    reasons = "; ".join(result.verdict.reasons) or "none"
    lines = [
        f"{EXPORT_NODE}:  # what this export assumed; read by no node",
        "  ros__parameters:",
        f"    format: {yaml_scalar(fmt)}",
        f"    verdict: {yaml_scalar(result.verdict.status)}",
        f"    verdict_reasons: {yaml_scalar(reasons)}",
        f"    variance_floor: {yaml_scalar(VARIANCE_FLOOR)}",
        f"    unobserved_variance: {yaml_scalar(UNOBSERVED_VARIANCE)}",
    ]
    lines += [f"    {k}: {yaml_scalar(v)}" for k, v in keys.items()]
    return lines


def ros2_diff_drive_text(result: EstimateResult, lin: Linearisation, source: str = "") -> str:
    """diff_drive_controller parameters: the two covariance diagonals."""
    dd = diff_drive_covariance(result.params, lin)
    lines = [
        *_header("ros2-diff-drive", result, source, "diff_drive_controller covariance diagonals"),
        f"# Linearisation: speed {lin.speed_m_per_s:g} m/s, publish_rate {lin.rate_hz:g} Hz, so "
        f"one step is {lin.step_m:g} m in {lin.period_s:g} s.",
        "# pose_covariance_diagonal (x, y, z, roll, pitch, yaw): the pose change of one step",
        "#   (m^2, rad^2); the absolute pose covariance grows without bound, no constant is it.",
        "# twist_covariance_diagonal (vx, vy, vz, wx, wy, wz): one step's variances / period^2",
        "#   ((m/s)^2, (rad/s)^2). z, roll, pitch and their rates are not observed by odometry:",
        f"#   {UNOBSERVED_VARIANCE:g}. Rename the node to your controller's name.",
        *_floor_comment(dd.floored),
        *_corrections_comment(result),
        f"{DIFF_DRIVE_NODE}:",
        "  ros__parameters:",
        f"    publish_rate: {yaml_scalar(lin.rate_hz)}",
        f"    pose_covariance_diagonal: {yaml_list(dd.pose_covariance_diagonal, 6)}",
        f"    twist_covariance_diagonal: {yaml_list(dd.twist_covariance_diagonal, 6)}",
        *_export_block(
            "ros2-diff-drive",
            result,
            {
                "speed_m_per_s": lin.speed_m_per_s,
                "publish_rate_hz": lin.rate_hz,
                "step_m": lin.step_m,
                "floored": ", ".join(dd.floored) or "none",
            },
        ),
    ]
    return "\n".join(lines) + "\n"


def odometry_msg_text(result: EstimateResult, lin: Linearisation, source: str = "") -> str:
    """nav_msgs/Odometry ``pose.covariance`` at one step, with the per-step formula."""
    step = lin.step_m
    odo = odometry_covariance(result.params, step)
    g = 1.0 + result.params.e_t
    k_theta, k_rho = result.params.k_theta, result.params.k_rho
    lines = [
        *_header("odometry-msg", result, source, "nav_msgs/Odometry pose.covariance of one step"),
        "# Per step of a metres (the step's own frame; row-major 6x6 over x, y, z, roll, pitch,",
        "#   yaw):",
        "#   var x = K_rho a, var y = (1+E_T)^2 K_theta a^3 / 3, var yaw = K_theta a,",
        "#   cov(y, yaw) = (1+E_T) K_theta a^2 / 2; z, roll, pitch not observed "
        f"({UNOBSERVED_VARIANCE:g}).",
        f"# Numbers at step a = {step:g} m "
        f"(speed {lin.speed_m_per_s:g} m/s at {lin.rate_hz:g} Hz).",
        *_floor_comment(odo.floored),
        *_corrections_comment(result),
        "per_step_formula:",
        f"  step_m: {yaml_scalar(step)}",
        f"  speed_m_per_s: {yaml_scalar(lin.speed_m_per_s)}",
        f"  rate_hz: {yaml_scalar(lin.rate_hz)}",
        f"  x_variance_m2_per_m: {yaml_scalar(k_rho)}  # times a",
        f"  y_variance_m2_per_m3: {yaml_scalar(g**2 * k_theta / 3.0)}  # times a^3",
        f"  yaw_variance_rad2_per_m: {yaml_scalar(k_theta)}  # times a",
        f"  y_yaw_covariance_rad_per_m: {yaml_scalar(g * k_theta / 2.0)}  # times a^2",
        f"  variance_floor: {yaml_scalar(VARIANCE_FLOOR)}",
        f"  floored: {yaml_scalar(', '.join(odo.floored) or 'none')}",
        f"  verdict: {yaml_scalar(result.verdict.status)}",
        f"  verdict_reasons: {yaml_scalar('; '.join(result.verdict.reasons) or 'none')}",
        "pose:",
        f"  covariance: {yaml_list(odo.covariance, 4)}",
    ]
    return "\n".join(lines) + "\n"


def robot_localization_text(result: EstimateResult, lin: Linearisation, source: str = "") -> str:
    """robot_localization's ``process_noise_covariance`` (225 numbers) at a speed."""
    pn = process_noise(result.params, lin.speed_m_per_s)
    lines = [
        *_header(
            "robot-localization", result, source, "robot_localization process_noise_covariance"
        ),
        f"# Per second at speed v = {lin.speed_m_per_s:g} m/s (robot_localization adds "
        "Q * dt each prediction):",
        "#   x, y: K_rho v (m^2/s; the along-track rate on both world axes), yaw: K_theta v "
        "(rad^2/s).",
        f"#   The other states ({', '.join(pn.from_template)}) keep robot_localization's template",
        "#   values: odometry calibration does not inform them. 15x15 row-major over",
        f"#   {', '.join(ROBOT_LOCALIZATION_STATES)}.",
        "# Use it when the filter predicts with the odometry; when it fuses the odometry's twist,",
        "#   give that twist the covariance of the ros2-diff-drive export instead.",
        *_floor_comment(pn.floored),
        *_corrections_comment(result),
        f"{ROBOT_LOCALIZATION_NODE}:",
        "  ros__parameters:",
        f"    process_noise_covariance: {yaml_list(pn.matrix, 6)}",
        *_export_block(
            "robot-localization",
            result,
            {"speed_m_per_s": pn.speed_m_per_s, "floored": ", ".join(pn.floored) or "none"},
        ),
    ]
    return "\n".join(lines) + "\n"


def amcl_text(result: EstimateResult, lin: Linearisation, source: str = "") -> str:
    """Nav2 AMCL's alpha1..alpha5 at its update distance."""
    a = amcl_alphas(result.params, lin)
    d = a.update_min_d_m
    lines = [
        *_header("amcl", result, source, "Nav2 AMCL odometry model alphas"),
        f"# Linearised at AMCL's update distance update_min_d = {d:g} m and angle "
        f"update_min_a = {a.update_min_a_rad:g} rad.",
        "#   alpha1 rotation noise from rotation: the model's in-place turns are exact, so the",
        "#     floor (tune it if the robot turns on its wheels, e.g. a differential drive);",
        "#   alpha2 rotation noise from translation = K_theta / (2 d): a straight update's two",
        "#     rotations add up to the heading variance K_theta d;",
        "#   alpha3 translation noise from translation = K_rho / d: variance K_rho d;",
        "#   alpha4 translation noise from rotation: the floor, as alpha1;",
        "#   alpha5 strafe noise from translation (omni model only) = (1+E_T)^2 K_theta / (3 d).",
        "# The update angle enters no alpha (turns carry no error in the model).",
        *_floor_comment(a.floored),
        *_corrections_comment(result),
        "#   Uncorrected, the heading drift per update (E_R d) is comparable with its noise.",
        f"{AMCL_NODE}:",
        "  ros__parameters:",
        '    robot_model_type: "nav2_amcl::DifferentialMotionModel"',
        f"    alpha1: {yaml_scalar(a.alpha1)}",
        f"    alpha2: {yaml_scalar(a.alpha2)}",
        f"    alpha3: {yaml_scalar(a.alpha3)}",
        f"    alpha4: {yaml_scalar(a.alpha4)}",
        f"    alpha5: {yaml_scalar(a.alpha5)}",
        f"    update_min_d: {yaml_scalar(d)}",
        f"    update_min_a: {yaml_scalar(a.update_min_a_rad)}",
        *_export_block(
            "amcl",
            result,
            {
                "update_min_d_m": d,
                "update_min_a_rad": a.update_min_a_rad,
                "floored": ", ".join(a.floored) or "none",
            },
        ),
    ]
    return "\n".join(lines) + "\n"


def json_document(result: EstimateResult, lin: Linearisation, source: str = "") -> dict[str, Any]:
    """The SI document: verdict, parameters, their covariance, the corrections,
    the variance rates and the per-step covariance at ``lin``'s step."""
    c = corrections(result)
    step = lin.step_m
    q = step_covariance(result.params, step)
    return {
        "format": "odohil-odometry-model",
        "units": "SI",
        "source": source,
        "verdict": result.verdict.to_json_dict(),
        "method": result.method,
        "n_trials": result.n_trials,
        "excluded": list(result.excluded),
        "parameters": {p.name: p.to_json_dict() for p in result.parameters},
        "parameter_covariance": {
            "order": [p.name for p in result.parameters],
            "matrix": [[_finite(v) for v in row] for row in parameter_covariance(result)],
        },
        "corrections": {
            "distance_scale": {
                "value": c.distance_scale,
                "stderr": _finite(c.distance_scale_stderr),
                "apply": "multiply encoder distances by it (1 + E_T)",
            },
            "heading_drift_rad_per_m": {
                "value": c.heading_drift_rad_per_m,
                "stderr": _finite(c.heading_drift_stderr),
                "apply": "add it to the encoder heading per signed metre driven (E_R)",
            },
        },
        "turn_errors": {
            name: {
                "value": value,
                "stderr": _finite(stderr),
                "apply": "heading variance per radian turned in place, rad^2/rad"
                if name == "K_spin"
                else "multiply the encoder's turned angle by 1 + it",
            }
            for name, value, stderr in turn_errors(result)
        },
        "variance_rates": {
            "heading_rad2_per_m": result.params.k_theta,
            "along_track_m2_per_m": result.params.k_rho,
        },
        "per_step": {
            "step_m": step,
            "speed_m_per_s": lin.speed_m_per_s,
            "rate_hz": lin.rate_hz,
            "frame": "the step's own: along-track m, cross-track m, heading rad",
            "covariance": [[float(v) for v in row] for row in q],
        },
    }


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def json_text(result: EstimateResult, lin: Linearisation, source: str = "") -> str:
    """:func:`json_document` as indented JSON text."""
    return json.dumps(json_document(result, lin, source), indent=2, allow_nan=False) + "\n"


@dataclass(frozen=True)
class ExportFormat:
    """One export format: a new one is its writer and one entry here.

    Attributes:
        name: its ``--format`` name (``odohil export`` offers every one).
        file_name: the file :func:`write_exports` writes it to.
        description: what it is, for the report's list of exports.
        write: its text from (estimate, linearisation, source).
    """

    name: str
    file_name: str
    description: str
    write: Callable[[EstimateResult, Linearisation, str], str]


EXPORT_FORMATS: dict[str, ExportFormat] = {
    f.name: f
    for f in (
        ExportFormat(
            "ros2-diff-drive",
            "ros2_diff_drive.yaml",
            "diff_drive_controller pose and twist covariance diagonals (ROS 2)",
            ros2_diff_drive_text,
        ),
        ExportFormat(
            "odometry-msg",
            "odometry_msg.yaml",
            "nav_msgs/Odometry pose covariance of one step, with its formula",
            odometry_msg_text,
        ),
        ExportFormat(
            "robot-localization",
            "robot_localization.yaml",
            "robot_localization process_noise_covariance (15x15, per second)",
            robot_localization_text,
        ),
        ExportFormat(
            "amcl",
            "amcl.yaml",
            "Nav2 AMCL alpha1..alpha5 at its update distance",
            amcl_text,
        ),
        ExportFormat(
            "json",
            "odometry_model.json",
            "the error model in SI: verdict, parameter covariance, corrections",
            json_text,
        ),
    )
}
"""Every export format, by name, in the order the report lists them."""
FORMATS: tuple[str, ...] = tuple(EXPORT_FORMATS)
FILE_NAMES: dict[str, str] = {name: f.file_name for name, f in EXPORT_FORMATS.items()}
"""The file each format is written to by :func:`write_exports`."""


def export_text(
    fmt: str, result: EstimateResult, lin: Linearisation | None = None, source: str = ""
) -> str:
    """One format's text (``fmt`` among :data:`FORMATS`)."""
    if fmt not in EXPORT_FORMATS:
        raise ParameterError(f"unknown export format {fmt!r}; choose from {', '.join(FORMATS)}")
    return EXPORT_FORMATS[fmt].write(result, lin or Linearisation(), source)


def export_files(
    result: EstimateResult,
    lin: Linearisation | None = None,
    formats: Sequence[str] = FORMATS,
    source: str = "",
) -> tuple[ExportFile, ...]:
    """Every format as the report's :class:`ExportFile` (name, text,
    description), for ``write_report(report, folder, extra_exports=...)``."""
    return tuple(
        ExportFile(
            EXPORT_FORMATS[fmt].file_name,
            export_text(fmt, result, lin, source),
            EXPORT_FORMATS[fmt].description,
        )
        for fmt in formats
    )


def write_exports(
    result: EstimateResult,
    folder: str | Path,
    lin: Linearisation | None = None,
    formats: Sequence[str] = FORMATS,
    source: str = "",
) -> list[Path]:
    """Write each format into ``folder`` (created) under :data:`FILE_NAMES`;
    return the paths. The caller decides whether an untrusted estimate may
    be written (the files state its verdict either way)."""
    files = export_files(result, lin, formats, source)
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for file in files:
        path = out / file.name
        path.write_text(file.text, encoding="utf-8")
        paths.append(path)
    return paths
