"""The session report: estimates recomputed from a journal, written as HTML + SVG.

:func:`load_report` replays a session folder's journal and recomputes what the
report shows (SI throughout): the final joint maximum-likelihood estimate, the
estimate after each trial (convergence), every design's observables phi1..phi5
and the model's mean and covariance of its pose change at the estimate.
:func:`write_report` writes, into one folder and referring to nothing outside
it: ``index.html``, the SVG plots, ``parameters.json`` (the estimate's JSON
object, as ``odohil estimate --json`` prints it) and
``odometry_covariance.yaml`` (the error model for a sensor-fusion filter).
"""

from __future__ import annotations

import html
import json
import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from odohil import units
from odohil.errors import MeasurementError
from odohil.science.estimators import (
    EstimateResult,
    IncrementalEstimator,
    ParameterEstimate,
    estimate,
)
from odohil.science.estimators.estimate import leave_out
from odohil.science.moments import pose_moments
from odohil.science.observables import Observables, observables
from odohil.science.parameters import PAPER_UNITS, PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import Design, FloatArray
from odohil.session.journal import read_journal
from odohil.session.state import CompletedTrial, SessionState, replay, session_observations

CHI2_95_2D = float(stats.chi2.ppf(0.95, 2))
"""Squared Mahalanobis radius of a 95 % ellipse in two dimensions."""


def to_paper(name: str, value: float) -> float:
    """One parameter value (or standard error) from SI to the paper's units."""
    if name == "E_R":
        return units.rad_per_m_to_deg_per_m(value)
    if name == "K_theta":
        return units.rad2_per_m_to_deg2_per_m(value)
    return value


@dataclass(frozen=True, eq=False)
class DesignReport:
    """One design of the session.

    Attributes:
        design: the design.
        poses: (n, 3) solved pose changes of its trials (x m, y m, Delta rad).
        measurement_cov: mean measurement covariance of its trials, (3, 3).
        phi: phi1..phi5 (None with fewer than 2 trials).
        model_mean: the model's mean pose change at the estimate, (3,), or None.
        model_cov: the model's covariance at the estimate, (3, 3), or None.
    """

    design: Design
    poses: FloatArray
    measurement_cov: FloatArray
    phi: Observables | None
    model_mean: FloatArray | None
    model_cov: FloatArray | None

    @property
    def signed_distance_m(self) -> float:
        """Signed encoder distance of one trial (2kl for the turn variant), m."""
        return self.design.path().signed_distance_m


@dataclass(frozen=True)
class ConvergencePoint:
    """The estimate after ``n_trials`` trials (SI values and standard errors)."""

    n_trials: int
    values: tuple[float, float, float, float]
    stderr: tuple[float, float, float, float]


@dataclass(frozen=True, eq=False)
class SessionReport:
    """Everything the report shows (SI).

    Attributes:
        folder: the session folder.
        state: the replayed session.
        result: the final estimate, or None when the trials give none.
        problem: why there is no estimate (empty otherwise).
        designs: per design, in plan order of first appearance.
        convergence: the incremental estimate after each trial that gave one.
    """

    folder: Path
    state: SessionState
    result: EstimateResult | None
    problem: str
    designs: tuple[DesignReport, ...]
    convergence: tuple[ConvergencePoint, ...]


def load_report(folder: str | Path, exclude: Collection[int] = frozenset()) -> SessionReport:
    """Replay the session in ``folder`` and recompute the estimates (the
    default robust method), leaving out the trial numbers in ``exclude``.

    Raises:
        JournalError: no readable, consistent journal there.
        MeasurementError: an excluded number that is no completed trial's.
    """
    path = Path(folder)
    state = replay(read_journal(path).records)
    trials = state.completed
    observations = session_observations(state)
    leave_out(observations, exclude)  # every excluded number must be a trial's
    result: EstimateResult | None = None
    problem = ""
    try:
        result = estimate(observations, exclude=exclude)
    except MeasurementError as exc:
        problem = str(exc)
    convergence: list[ConvergencePoint] = []
    incremental = IncrementalEstimator()
    kept = [o for o in observations if o.trial not in exclude]
    for n, obs in enumerate(kept, start=1):
        fit = incremental.add(obs)
        if fit is None:
            continue
        diag = np.diag(np.asarray(fit.covariance, dtype=np.float64))
        se = np.sqrt(np.where(np.isfinite(diag), np.clip(diag, 0.0, None), np.inf))
        convergence.append(ConvergencePoint(n, fit.params.as_tuple(), (se[0], se[1], se[2], se[3])))
    designs = _designs(trials, result.params if result else None)
    return SessionReport(path, state, result, problem, designs, tuple(convergence))


def _designs(
    trials: Sequence[CompletedTrial], params: ErrorParameters | None
) -> tuple[DesignReport, ...]:
    by_design: dict[Design, list[CompletedTrial]] = {}
    for trial in sorted(trials, key=lambda t: t.trial):
        by_design.setdefault(trial.design, []).append(trial)
    out = []
    for design, members in by_design.items():
        poses = np.array([t.pose_change for t in members], dtype=np.float64)
        meas = np.mean([np.array(t.cov, dtype=np.float64) for t in members], axis=0)
        model_mean = model_cov = None
        if params is not None:
            moments = pose_moments(design.path(), params)
            model_mean, model_cov = moments.mean, moments.cov
            # Headings are known modulo 2 pi: unwrap the trials near the model mean.
            poses[:, 2] = model_mean[2] + _wrap(poses[:, 2] - model_mean[2])
        phi = observables(poses) if len(members) >= 2 else None
        out.append(DesignReport(design, poses, meas, phi, model_mean, model_cov))
    return tuple(out)


def _wrap(angle: FloatArray) -> FloatArray:
    return np.asarray((angle + math.pi) % (2.0 * math.pi) - math.pi)


# --- exports ---------------------------------------------------------------


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


# --- SVG -------------------------------------------------------------------

_W, _H = 520, 360
_LEFT, _RIGHT, _TOP, _BOTTOM = 72, 20, 34, 52
_COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")


def nice_ticks(low: float, high: float, count: int = 5) -> list[float]:
    """Round tick values covering [low, high]."""
    if not (math.isfinite(low) and math.isfinite(high)) or high <= low:
        return [low]
    raw = (high - low) / count
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1.0, 2.0, 2.5, 5.0, 10.0) if m * power >= raw)
    first = math.ceil(low / step - 1e-9) * step
    ticks = []
    value = first
    while value <= high + 1e-9 * step:
        ticks.append(0.0 if abs(value) < 1e-12 * step else value)
        value += step
    return ticks


def _span(values: Sequence[float], pad: float = 0.08) -> tuple[float, float]:
    finite = [v for v in values if math.isfinite(v)]
    if not finite:
        return (-1.0, 1.0)
    low, high = min(finite), max(finite)
    if high - low < 1e-12 * max(1.0, abs(high)):
        half = max(abs(high) * 0.1, 1e-9)
        return (low - half, high + half)
    margin = (high - low) * pad
    return (low - margin, high + margin)


class SvgPlot:
    """A minimal x-y plot written as SVG text (one axes, ticks, labels)."""

    def __init__(
        self,
        title: str,
        x_label: str,
        y_label: str,
        x_range: tuple[float, float],
        y_range: tuple[float, float],
        equal: bool = False,
    ) -> None:
        self.title, self.x_label, self.y_label = title, x_label, y_label
        self.x0, self.x1 = x_range
        self.y0, self.y1 = y_range
        if equal:
            self._equalise()
        self.parts: list[str] = []

    def _equalise(self) -> None:
        width, height = _W - _LEFT - _RIGHT, _H - _TOP - _BOTTOM
        per_px = max((self.x1 - self.x0) / width, (self.y1 - self.y0) / height)
        cx, cy = (self.x0 + self.x1) / 2, (self.y0 + self.y1) / 2
        self.x0, self.x1 = cx - per_px * width / 2, cx + per_px * width / 2
        self.y0, self.y1 = cy - per_px * height / 2, cy + per_px * height / 2

    def px(self, x: float) -> float:
        """Data x to pixels."""
        return _LEFT + (x - self.x0) / (self.x1 - self.x0) * (_W - _LEFT - _RIGHT)

    def py(self, y: float) -> float:
        """Data y to pixels."""
        return _H - _BOTTOM - (y - self.y0) / (self.y1 - self.y0) * (_H - _TOP - _BOTTOM)

    def polyline(self, xs: Sequence[float], ys: Sequence[float], colour: str, **attrs: str) -> None:
        """A line through the points."""
        points = " ".join(f"{self.px(x):.2f},{self.py(y):.2f}" for x, y in zip(xs, ys, strict=True))
        extra = "".join(f' {k.replace("_", "-")}="{v}"' for k, v in attrs.items())
        self.parts.append(
            f'<polyline points="{points}" fill="none" stroke="{colour}" stroke-width="1.6"{extra}/>'
        )

    def polygon(
        self, xs: Sequence[float], ys: Sequence[float], colour: str, opacity: float
    ) -> None:
        """A filled polygon."""
        points = " ".join(f"{self.px(x):.2f},{self.py(y):.2f}" for x, y in zip(xs, ys, strict=True))
        self.parts.append(
            f'<polygon points="{points}" fill="{colour}" fill-opacity="{opacity}" stroke="none"/>'
        )

    def dots(self, xs: Sequence[float], ys: Sequence[float], colour: str, r: float = 3.0) -> None:
        """Markers at the points."""
        for x, y in zip(xs, ys, strict=True):
            self.parts.append(
                f'<circle cx="{self.px(x):.2f}" cy="{self.py(y):.2f}" r="{r}" fill="{colour}" '
                'fill-opacity="0.75"/>'
            )

    def cross(self, x: float, y: float, colour: str, size: float = 7.0) -> None:
        """A + marker."""
        cx, cy = self.px(x), self.py(y)
        self.parts.append(
            f'<path d="M{cx - size:.2f},{cy:.2f}H{cx + size:.2f}M{cx:.2f},{cy - size:.2f}'
            f'V{cy + size:.2f}" stroke="{colour}" stroke-width="2.2"/>'
        )

    def error_bar(self, x: float, low: float, high: float, colour: str) -> None:
        """A vertical bar from low to high at x."""
        cx = self.px(x)
        self.parts.append(
            f'<path d="M{cx:.2f},{self.py(low):.2f}V{self.py(high):.2f}'
            f'M{cx - 4:.2f},{self.py(low):.2f}h8M{cx - 4:.2f},{self.py(high):.2f}h8" '
            f'stroke="{colour}" stroke-width="1.4"/>'
        )

    def legend(self, entries: Sequence[tuple[str, str]]) -> None:
        """Labelled colour swatches in the top-left corner of the axes."""
        for i, (label, colour) in enumerate(entries):
            y = _TOP + 14 + 16 * i
            self.parts.append(
                f'<rect x="{_LEFT + 8}" y="{y - 9}" width="10" height="10" fill="{colour}"/>'
                f'<text x="{_LEFT + 23}" y="{y}" font-size="11">{html.escape(label)}</text>'
            )

    def render(self) -> str:
        """The SVG document."""
        out = [
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{_W}" height="{_H}" '
            f'viewBox="0 0 {_W} {_H}" font-family="sans-serif">',
            f'<rect width="{_W}" height="{_H}" fill="white"/>',
            f'<text x="{_W / 2}" y="20" font-size="14" text-anchor="middle">'
            f"{html.escape(self.title)}</text>",
        ]
        left, right, top, bottom = _LEFT, _W - _RIGHT, _TOP, _H - _BOTTOM
        for tick in nice_ticks(self.x0, self.x1):
            x = self.px(tick)
            out.append(
                f'<line x1="{x:.2f}" y1="{top}" x2="{x:.2f}" y2="{bottom}" stroke="#e5e5e5"/>'
                f'<text x="{x:.2f}" y="{bottom + 16}" font-size="11" text-anchor="middle">'
                f"{_tick(tick)}</text>"
            )
        for tick in nice_ticks(self.y0, self.y1):
            y = self.py(tick)
            out.append(
                f'<line x1="{left}" y1="{y:.2f}" x2="{right}" y2="{y:.2f}" stroke="#e5e5e5"/>'
                f'<text x="{left - 6}" y="{y + 4:.2f}" font-size="11" text-anchor="end">'
                f"{_tick(tick)}</text>"
            )
        out.append(
            f'<rect x="{left}" y="{top}" width="{right - left}" height="{bottom - top}" '
            'fill="none" stroke="#333"/>'
        )
        out.append(
            f'<svg x="{left}" y="{top}" width="{right - left}" height="{bottom - top}" '
            f'viewBox="{left} {top} {right - left} {bottom - top}" overflow="hidden">'
        )
        out.extend(self.parts)
        out.append("</svg>")
        out.append(
            f'<text x="{(left + right) / 2}" y="{_H - 12}" font-size="12" text-anchor="middle">'
            f"{html.escape(self.x_label)}</text>"
            f'<text x="16" y="{(top + bottom) / 2}" font-size="12" text-anchor="middle" '
            f'transform="rotate(-90 16 {(top + bottom) / 2})">{html.escape(self.y_label)}</text>'
        )
        out.append("</svg>\n")
        return "\n".join(out)


def _tick(value: float) -> str:
    return f"{value:.6g}"


def ellipse_points(
    mean: FloatArray, cov: FloatArray, radius2: float = CHI2_95_2D, n: int = 90
) -> tuple[list[float], list[float]]:
    """Points of the ellipse {v: (v - mean)^T cov^-1 (v - mean) = radius2} (2-D)."""
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    axes = vectors * np.sqrt(np.clip(values, 0.0, None) * radius2)
    angles = np.linspace(0.0, 2.0 * math.pi, n)
    points = mean[:, None] + axes @ np.vstack([np.cos(angles), np.sin(angles)])
    return [float(v) for v in points[0]], [float(v) for v in points[1]]


def end_positions_svg(design: DesignReport) -> str:
    """Trials' end points (mm) with the model mean and its 95 % ellipse."""
    xs = [1e3 * float(v) for v in design.poses[:, 0]]
    ys = [1e3 * float(v) for v in design.poses[:, 1]]
    ex: list[float] = []
    ey: list[float] = []
    if design.model_mean is not None and design.model_cov is not None:
        cov = design.model_cov[:2, :2] + design.measurement_cov[:2, :2]
        ex, ey = ellipse_points(design.model_mean[:2] * 1e3, cov * 1e6)
    plot = SvgPlot(
        f"End points, {design.design.label()} ({len(xs)} trials)",
        "x of the end point, start frame (mm)",
        "y (mm)",
        _span(xs + ex),
        _span(ys + ey),
        equal=True,
    )
    entries = [("trials", _COLOURS[0])]
    if ex:
        assert design.model_mean is not None
        plot.polygon(ex, ey, _COLOURS[1], 0.12)
        plot.polyline(ex, ey, _COLOURS[1])
        plot.cross(1e3 * float(design.model_mean[0]), 1e3 * float(design.model_mean[1]), "#000")
        entries += [("model 95 % ellipse", _COLOURS[1]), ("model mean (+)", "#000")]
    plot.dots(xs, ys, _COLOURS[0])
    plot.legend(entries)
    return plot.render()


def phi1_svg(report: SessionReport) -> str:
    """Mean heading change per design against the signed distance (the paper's Fig. 2)."""
    rows = [d for d in report.designs if d.phi is not None]
    xs = [d.signed_distance_m for d in rows]
    ys = [units.radians_to_degrees(d.phi.phi1) for d in rows if d.phi is not None]
    errs = [
        units.radians_to_degrees(math.sqrt(d.phi.phi2 / d.phi.n_trials))
        for d in rows
        if d.phi is not None
    ]
    line_x = [0.0, max([*xs, 1.0]) * 1.05]
    line_y: list[float] = []
    if report.result is not None:
        slope = units.rad_per_m_to_deg_per_m(report.result.params.e_r)
        line_y = [slope * x for x in line_x]
    plot = SvgPlot(
        "phi1: mean heading change per design",
        "signed distance driven per trial, 2kl (m)",
        "phi1 (deg)",
        _span([*xs, *line_x]),
        _span(
            [y + e for y, e in zip(ys, errs, strict=True)]
            + [y - e for y, e in zip(ys, errs, strict=True)]
            + line_y
            + [0.0]
        ),
    )
    entries = [("phi1 +- 1 standard error", _COLOURS[0])]
    if line_y:
        plot.polyline(line_x, line_y, _COLOURS[1])
        entries.append(("fitted E_R * rho", _COLOURS[1]))
    for x, y, e in zip(xs, ys, errs, strict=True):
        plot.error_bar(x, y - e, y + e, _COLOURS[0])
    plot.dots(xs, ys, _COLOURS[0], r=4.0)
    plot.legend(entries)
    return plot.render()


def convergence_svg(report: SessionReport, index: int) -> str:
    """One parameter's estimate after each trial with its 95 % band (paper units)."""
    name = PARAMETER_NAMES[index]
    pts = [p for p in report.convergence if math.isfinite(p.stderr[index])]
    ns = [float(p.n_trials) for p in pts]
    values = [to_paper(name, p.values[index]) for p in pts]
    # The same interval rule as the estimate's (log scale for the variance rates).
    bands = [ParameterEstimate.build(name, p.values[index], p.stderr[index]).ci95 for p in pts]
    low = [to_paper(name, b[0]) for b in bands]
    high = [to_paper(name, b[1]) for b in bands]
    final = (
        [] if report.result is None else [to_paper(name, report.result.params.as_tuple()[index])]
    )
    n_max = float(max([*ns, 2.0]))
    plot = SvgPlot(
        f"{name}: estimate after each trial",
        "trials",
        f"{name} ({PAPER_UNITS[name]})",
        (0.0, n_max + 1.0),
        _span(low + high + values + final, pad=0.05),
    )
    if ns:
        plot.polygon(ns + ns[::-1], high + low[::-1], _COLOURS[0], 0.18)
        plot.polyline(ns, values, _COLOURS[0])
        plot.dots(ns, values, _COLOURS[0], r=2.5)
    entries = [("estimate, 95 % band", _COLOURS[0])]
    if final:
        plot.polyline([0.0, n_max + 1.0], final * 2, _COLOURS[1], stroke_dasharray="5,4")
        entries.append(("final estimate", _COLOURS[1]))
    plot.legend(entries)
    return plot.render()


def model_check_svg(report: SessionReport) -> str:
    """Each trial's squared Mahalanobis distance from the model, with the outlier level."""
    result = report.result
    assert result is not None
    d2 = list(result.model_check.mahalanobis2)
    n = len(d2)
    excluded = set(result.excluded)
    trials = [
        float(t.trial)
        for t in report.state.completed
        if not t.ambiguous and t.trial not in excluded
    ]
    limit = float(stats.chi2.isf(0.01 / max(n, 1), 3))
    plot = SvgPlot(
        "Model check: squared Mahalanobis distance per trial",
        "trial",
        "d^2 (chi^2 with 3 dof if the model fits)",
        (0.0, max([*trials, 1.0]) + 1.0),
        (0.0, max([*d2, limit]) * 1.1),
    )
    x_line = [0.0, max([*trials, 1.0]) + 1.0]
    plot.polyline(x_line, [3.0, 3.0], "#777", stroke_dasharray="3,3")
    plot.polyline(x_line, [limit, limit], _COLOURS[1], stroke_dasharray="6,4")
    plot.dots(trials, d2, _COLOURS[0])
    plot.legend(
        [
            ("trials", _COLOURS[0]),
            ("mean (3)", "#777"),
            ("outlier level (1 %, Bonferroni)", _COLOURS[1]),
        ]
    )
    return plot.render()


# --- HTML ------------------------------------------------------------------

_CSS = """
body { font-family: sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
table { border-collapse: collapse; margin: 1em 0; }
th, td { border: 1px solid #bbb; padding: 0.3em 0.7em; text-align: right; }
th { background: #f0f0f0; }
td.l, th.l { text-align: left; }
.plots img { margin: 0.5em; border: 1px solid #ddd; }
.bad { color: #b00; } .good { color: #070; }
"""


def write_report(report: SessionReport, out_dir: str | Path) -> list[Path]:
    """Write the report into ``out_dir`` (created); returns the files written.

    Raises:
        OSError: the folder cannot be written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files: dict[str, str] = {}
    end_plots = []
    for i, design in enumerate(report.designs, start=1):
        name = f"end_points_{i}.svg"
        files[name] = end_positions_svg(design)
        end_plots.append(name)
    conv_plots = []
    extra_plots = []
    if report.designs:
        files["phi1.svg"] = phi1_svg(report)
        extra_plots.append("phi1.svg")
    if report.convergence:
        for i, name in enumerate(PARAMETER_NAMES):
            file = f"convergence_{name}.svg"
            files[file] = convergence_svg(report, i)
            conv_plots.append(file)
    if report.result is not None:
        files["model_check.svg"] = model_check_svg(report)
    files["parameters.json"] = json.dumps(parameters_json(report), indent=2) + "\n"
    files["odometry_covariance.yaml"] = covariance_yaml(report)
    files["index.html"] = _html(report, end_plots, extra_plots, conv_plots)
    written = []
    for name, text in files.items():
        path = out / name
        path.write_text(text, encoding="utf-8")
        written.append(path)
    return written


def _html(report: SessionReport, end_plots: list[str], extra: list[str], conv: list[str]) -> str:
    state = report.state
    e = html.escape
    plan = state.plan.to_text() if state.plan else "none"
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>odohil report: {e(report.folder.name)}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>Odometry calibration report: {e(report.folder.name)}</h1>",
        f"<p>Plan <code>{e(plan)}</code>; {len(state.completed)} of "
        f"{state.plan.n_trials if state.plan else 0} trials completed"
        f"{' (session finished)' if state.finished else ' (session not finished)'}; "
        f"{state.voided} attempt(s) voided. Robot description: "
        f"<code>{e(str(state.header.get('robot_path') or 'journaled'))}</code>.</p>",
        "<h2>Estimates</h2>",
    ]
    result = report.result
    if result is None:
        parts.append(f'<p class="bad">No estimate: {e(report.problem)}</p>')
    else:
        status = result.verdict.status
        reasons = "; ".join(result.verdict.reasons)
        parts.append(
            f'<p class="{"good" if result.verdict.trusted else "bad"}">Verdict: '
            f"<strong>{e(status)}</strong>{e(': ' + reasons if reasons else '')}</p>"
        )
        parts.append(_estimates_table(result))
        parts.append(f"<p>Method: {e(result.method)}. {e(' '.join(result.notes))}</p>")
        suff = result.sufficiency
        css = "good" if suff.sufficient else "bad"
        parts.append(f'<p class="{css}">Sufficiency: {e(suff.verdict)}</p>')
        if suff.suggestions:
            parts.append("<ul>")
            for s in suff.suggestions:
                more = "not reachable" if s.more_trials is None else f"{s.more_trials} more trials"
                parts.append(f"<li>{e(s.design_label)}: {e(more)}</li>")
            parts.append("</ul>")
    parts.append("<h2>Observables per design</h2>")
    parts.append(_phi_table(report))
    parts.append('<h2>End points</h2><div class="plots">')
    parts.extend(f'<img src="{e(name)}" alt="{e(name)}">' for name in end_plots)
    parts.append("</div>")
    parts.append(
        "<p>Dots: solved end points of the trials in the start frame. Ellipse: the "
        "model's 95 % region at the estimate (pose spread plus measurement error).</p>"
    )
    if extra:
        parts.append('<h2>Heading drift (the paper\'s Fig. 2)</h2><div class="plots">')
        parts.extend(f'<img src="{e(name)}" alt="{e(name)}">' for name in extra)
        parts.append("</div>")
    if conv:
        parts.append('<h2>Convergence</h2><div class="plots">')
        parts.extend(f'<img src="{e(name)}" alt="{e(name)}">' for name in conv)
        parts.append("</div>")
    if result is not None:
        mc = result.model_check
        css = "good" if mc.fits else "bad"
        parts.append("<h2>Model check</h2>")
        parts.append(
            f'<p class="{css}">{e(mc.verdict)} (chi^2 = {mc.chi2:.3g}, dof {mc.dof}, '
            f"p = {mc.p_value:.3g}).</p>"
        )
        parts.append('<div class="plots"><img src="model_check.svg" alt="model check"></div>')
    parts.append(
        '<h2>Exports</h2><ul><li><a href="parameters.json">parameters.json</a>: the '
        'estimate (SI units)</li><li><a href="odometry_covariance.yaml">'
        "odometry_covariance.yaml</a>: the error model for a sensor-fusion filter</li></ul>"
    )
    parts.append("</body></html>\n")
    return "\n".join(parts)


def _estimates_table(result: EstimateResult) -> str:
    rows = [
        "<table><tr><th class=l>parameter</th><th>estimate</th><th>standard error</th>"
        "<th>95 % interval</th><th class=l>unit</th></tr>"
    ]
    for p in result.parameters:
        lo, hi = (to_paper(p.name, v) for v in p.ci95)
        rows.append(
            f"<tr><td class=l>{p.name}</td><td>{to_paper(p.name, p.value):.4g}</td>"
            f"<td>{_fmt(to_paper(p.name, p.stderr))}</td><td>[{_fmt(lo)}, {_fmt(hi)}]</td>"
            f"<td class=l>{PAPER_UNITS[p.name]}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _phi_table(report: SessionReport) -> str:
    rows = [
        "<table><tr><th class=l>design</th><th>n</th><th>phi1 (deg)</th><th>phi2 (deg^2)</th>"
        "<th>phi3 (mm)</th><th>phi4 (mm)</th><th>phi5 (mm^2)</th></tr>"
    ]
    for d in report.designs:
        if d.phi is None:
            rows.append(
                f"<tr><td class=l>{html.escape(d.design.label())}</td><td>{len(d.poses)}</td>"
                "<td colspan=5 class=l>needs 2 trials</td></tr>"
            )
            continue
        phi = d.phi
        rows.append(
            f"<tr><td class=l>{html.escape(d.design.label())}</td><td>{phi.n_trials}</td>"
            f"<td>{units.radians_to_degrees(phi.phi1):.4g}</td>"
            f"<td>{units.rad2_to_deg2(phi.phi2):.4g}</td><td>{1e3 * phi.phi3:.4g}</td>"
            f"<td>{1e3 * phi.phi4:.4g}</td><td>{1e6 * phi.phi5:.4g}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _fmt(value: float) -> str:
    return f"{value:.3g}" if math.isfinite(value) else "undetermined"
