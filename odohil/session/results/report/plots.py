"""The report's plots, drawn with matplotlib and rendered to SVG text in memory.

Figures are made with :class:`matplotlib.figure.Figure` directly (no pyplot,
no global state, no display: the Agg-family renderers only) and saved to SVG
with text kept as text and every id prefixed with the plot's key, so that
several plots can be inlined in one HTML page. Every plot marks the trials the report points out
with the same styles: flagged, excluded, ambiguous and down-weighted trials
each have their own marker and legend entry, and are labelled by trial number.
"""

from __future__ import annotations

import io
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import matplotlib as mpl
import numpy as np
from matplotlib import patheffects
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse
from matplotlib.ticker import MaxNLocator

from odohil import units
from odohil.science import distributions
from odohil.science.estimators import ParameterEstimate
from odohil.science.parameters import PARAMETER_NAMES
from odohil.science.paths import FloatArray
from odohil.session.results.report.data import (
    DOWN_WEIGHT_BELOW,
    DesignReport,
    SessionReport,
    TrialPoint,
)
from odohil.session.results.validation import ValidationPlot
from odohil.units import parameter_to_paper as _to_paper

CHI2_95_2D = distributions.chi2_ppf(0.95, 2)
"""Squared Mahalanobis radius of a 95 % ellipse in two dimensions."""

BLUE, RED, GREY, ORANGE, PURPLE, DARK = (
    "#1f77b4",
    "#d62728",
    "#7f7f7f",
    "#ff7f0e",
    "#9467bd",
    "#222222",
)
_DESIGN_COLOURS = (BLUE, "#2ca02c", "#8c564b", PURPLE, "#17becf", ORANGE)
_DESIGN_MARKERS = ("o", "s", "^", "D", "v", "P")
_HALO = [patheffects.withStroke(linewidth=2.5, foreground="white")]
"""A white edge around the trial numbers, readable over markers and lines."""
_RC: Any = {  # matplotlib types rcParams keys as literals
    "svg.fonttype": "none",
    "font.family": "sans-serif",
    "font.size": 9.0,
    "axes.titlesize": 10.0,
    "legend.fontsize": 8.0,
    "axes.grid": True,
    "grid.color": "#e5e5e5",
}
_NO_METADATA: dict[str, str | None] = {"Creator": None, "Date": None, "Format": None, "Type": None}


@dataclass(frozen=True)
class Plot:
    """One rendered plot.

    Attributes:
        key: a short name, unique in the report (also its HTML anchor).
        title: what it shows.
        svg: the ``<svg>`` element (no XML declaration), referring to nothing
            outside itself.
    """

    key: str
    title: str
    svg: str


def report_plots(report: SessionReport) -> tuple[Plot, ...]:
    """Every plot of the report, in the order the page shows them."""
    plots = [
        _render(f"end-points-{i}", f"End points, {d.design.label()}", end_points_figure(d))
        for i, d in enumerate(report.designs, start=1)
    ]
    if any(d.phi is not None for d in report.designs):
        plots.append(_render("phi1", "phi1 against distance", phi1_figure(report)))
    if report.convergence:
        plots.append(_render("convergence", "Convergence", convergence_figure(report)))
    if report.result is not None:
        plots.append(_render("model-check", "Model check", model_check_figure(report)))
    for i, validation in enumerate(report.validations, start=1):
        for j, data in enumerate(validation.plots, start=1):
            title = f"Validation, {data.label}"
            plots.append(_render(f"validation-{i}-{j}", title, validation_figure(data)))
    return tuple(plots)


def _render(key: str, title: str, figure: Figure) -> Plot:
    with mpl.rc_context(_RC):
        buffer = io.StringIO()
        figure.savefig(buffer, format="svg", metadata=_NO_METADATA)
    text = buffer.getvalue()
    svg = re.sub(r"<metadata>.*?</metadata>\s*", "", text[text.index("<svg") :], flags=re.DOTALL)
    return Plot(key, title, _own_ids(svg, key))


def _own_ids(svg: str, key: str) -> str:
    """The SVG with every id, and every in-document reference to one, prefixed
    with ``key``: matplotlib numbers its ids per figure (``figure_1``,
    ``axes_1``...), which would clash between the plots of one page."""
    svg = re.sub(r'\bid="([^"]+)"', lambda m: f'id="{key}-{m.group(1)}"', svg)
    svg = re.sub(r'href="#([^"]+)"', lambda m: f'href="#{key}-{m.group(1)}"', svg)
    return re.sub(r"url\(#([^)]+)\)", lambda m: f"url(#{key}-{m.group(1)})", svg)


def _figure(width_in: float, height_in: float) -> Figure:
    with mpl.rc_context(_RC):
        return Figure(figsize=(width_in, height_in), layout="constrained")


# --- the trials' markers ----------------------------------------------------


def _mark_trials(
    ax: Axes, trials: Sequence[TrialPoint], xs: Sequence[float], ys: FloatArray
) -> None:
    """The trials at (xs, ys), with every kind of marked trial in its own style."""
    x = np.asarray(xs, dtype=np.float64)
    y = np.asarray(ys, dtype=np.float64)

    def pick(keep: Sequence[bool]) -> tuple[FloatArray, FloatArray]:
        mask = np.asarray(keep, dtype=bool)
        return x[mask], y[mask]

    used = pick([t.used for t in trials])
    if used[0].size:
        ax.scatter(*used, s=18, color=BLUE, alpha=0.8, label="trial used", zorder=3)
    flagged = pick([t.flagged for t in trials])
    if flagged[0].size:
        ax.scatter(
            *flagged, s=90, marker="s", facecolors="none", edgecolors=ORANGE, linewidths=1.4,
            label="flagged (pose from the marks in doubt)", zorder=4,
        )  # fmt: skip
    down = pick([t.down_weighted for t in trials])
    if down[0].size:
        ax.scatter(
            *down, s=130, marker="o", facecolors="none", edgecolors=RED, linewidths=1.4,
            label=f"outlier, down-weighted (p clean < {DOWN_WEIGHT_BELOW:g})", zorder=4,
        )  # fmt: skip
    excluded = pick([t.excluded for t in trials])
    if excluded[0].size:
        ax.scatter(
            *excluded, s=40, marker="x", color=GREY, linewidths=1.4,
            label="excluded (--exclude)", zorder=3,
        )  # fmt: skip
    ambiguous = pick([t.ambiguous and not t.excluded for t in trials])
    if ambiguous[0].size:
        ax.scatter(
            *ambiguous, s=45, marker="D", facecolors="none", edgecolors=PURPLE, linewidths=1.2,
            label="ambiguous, left out", zorder=3,
        )  # fmt: skip
    for t, xi, yi in zip(trials, x, y, strict=True):
        if t.marked:
            ax.annotate(
                str(t.trial), (xi, yi), xytext=(5, 4), textcoords="offset points",
                fontsize=7, color=DARK, path_effects=_HALO,
            )  # fmt: skip


def _legend_outside(fig: Figure, ax: Axes, below: bool = False) -> None:
    """The axes' legend outside the axes (to their right, or below them), so
    that it never covers the data."""
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return
    if below:
        fig.legend(handles, labels, loc="outside lower center", ncols=2)
    else:
        fig.legend(handles, labels, loc="outside right upper")


# --- the plots --------------------------------------------------------------


def ellipse_axes(cov: FloatArray, radius2: float = CHI2_95_2D) -> tuple[float, float, float]:
    """Width, height and angle (degrees) of the ellipse {v: v^T cov^-1 v = radius2}
    (2-D, in the covariance's units to the half power)."""
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    values = np.clip(values, 0.0, None)
    angle = units.radians_to_degrees(math.atan2(float(vectors[1, 1]), float(vectors[0, 1])))
    return (
        2.0 * math.sqrt(float(values[1]) * radius2),
        2.0 * math.sqrt(float(values[0]) * radius2),
        angle,
    )


def _region_and_mean(
    ax: Axes, mean_m: FloatArray, cov_m2: FloatArray, region: str, mean: str
) -> None:
    """A 95 % ellipse (``cov_m2``, m^2) and its mean (``mean_m``, m), drawn in mm."""
    width, height, angle = ellipse_axes(1e6 * cov_m2)
    centre = (1e3 * float(mean_m[0]), 1e3 * float(mean_m[1]))
    ax.add_patch(
        Ellipse(
            centre, width, height, angle=angle, facecolor=RED, alpha=0.15,
            edgecolor=RED, linewidth=1.2, label=region,
        )
    )  # fmt: skip
    ax.plot(*centre, marker="+", markersize=11, markeredgewidth=2, color=DARK,
            linestyle="none", label=mean)  # fmt: skip


def _finish_end_points(fig: Figure, ax: Axes, title: str, count: int) -> None:
    """Equal mm axes in the start frame, the title with its trial count, the legend below."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_title(f"{title} ({units.plural(count, 'trial')})")
    ax.set_xlabel("x of the end point, start frame (mm)")
    ax.set_ylabel("y of the end point, start frame (mm)")
    _legend_outside(fig, ax, below=True)


def end_points_figure(design: DesignReport) -> Figure:
    """One design's trial end points (mm, start frame) with the model's mean and
    95 % ellipse at the estimate (pose spread plus measurement error)."""
    fig = _figure(5.4, 4.6)
    with mpl.rc_context(_RC):
        ax = fig.add_subplot()
        if design.model_mean is not None and design.model_cov is not None:
            cov = design.model_cov[:2, :2] + design.measurement_cov[:2, :2]
            _region_and_mean(ax, design.model_mean, cov, "model's 95 % region", "model mean")
        poses = np.array([t.pose for t in design.trials], dtype=np.float64).reshape(-1, 3)
        _mark_trials(ax, design.trials, list(1e3 * poses[:, 0]), 1e3 * poses[:, 1])
        title = f"End points, {design.design.label()}"
        _finish_end_points(fig, ax, title, len(design.trials))
    return fig


def validation_figure(data: ValidationPlot) -> Figure:
    """A validation path's trial end points (mm, start frame) against the
    calibrated model's predicted 95 % ellipse (pose spread, measurement error
    and the estimate's own uncertainty)."""
    fig = _figure(5.4, 4.6)
    ellipse = data.ellipse
    with mpl.rc_context(_RC):
        ax = fig.add_subplot()
        _region_and_mean(ax, ellipse.mean, ellipse.cov, "predicted 95 % region", "predicted mean")
        points = 1e3 * ellipse.points
        ax.plot(points[:, 0], points[:, 1], marker="o", linestyle="none", color=DARK,
                markersize=5, label="validation trials")  # fmt: skip
        _finish_end_points(fig, ax, f"Validation, {data.label}", len(data.numbers))
    return fig


def phi1_figure(report: SessionReport) -> Figure:
    """Mean heading change per design against the signed distance driven per
    trial, with the fitted E_R rho line (the paper's Fig. 2)."""
    rows = [d for d in report.designs if d.phi is not None]
    xs = [d.signed_distance_m for d in rows]
    ys = [units.radians_to_degrees(d.phi.phi1) for d in rows if d.phi is not None]
    errs = [
        units.radians_to_degrees(math.sqrt(max(d.phi.phi2, 0.0) / d.phi.n_trials))
        for d in rows
        if d.phi is not None
    ]
    fig = _figure(6.2, 3.8)
    with mpl.rc_context(_RC):
        ax = fig.add_subplot()
        if report.result is not None:
            reach = max([abs(x) for x in xs] + [1.0]) * 1.08
            line_x = np.linspace(min(0.0, *xs) * 1.08 if xs else 0.0, reach, 2)
            slope = units.rad_per_m_to_deg_per_m(report.result.params.e_r)
            ax.plot(line_x, slope * line_x, color=RED, linewidth=1.4, label="fitted E_R · 2kl")
        # One colour and hollow marker per design: designs of equal 2kl sit on one another.
        for n, (row, x, y, err) in enumerate(zip(rows, xs, ys, errs, strict=True)):
            ax.errorbar(
                [x], [y], yerr=[err], fmt=_DESIGN_MARKERS[n % len(_DESIGN_MARKERS)],
                color=_DESIGN_COLOURS[n % len(_DESIGN_COLOURS)], markersize=7, capsize=3,
                markerfacecolor="none", markeredgewidth=1.5, elinewidth=1.2,
                label=f"phi1 ± 1 standard error, {row.design.label()}",
            )  # fmt: skip
        ax.axhline(0.0, color=GREY, linewidth=0.8)
        ax.set_title("phi1: mean heading change per design")
        ax.set_xlabel("signed distance driven per trial, 2kl (m)")
        ax.set_ylabel("phi1, mean heading change (deg)")
        _legend_outside(fig, ax)
    return fig


def convergence_figure(report: SessionReport) -> Figure:
    """Each parameter's estimate after each trial with its 95 % interval (paper
    units), and the final estimate."""
    fig = _figure(9.0, 5.6)
    with mpl.rc_context(_RC):
        axes = fig.subplots(2, 2, sharex=True)
        for index, (name, ax) in enumerate(zip(PARAMETER_NAMES, axes.flat, strict=True)):
            _convergence_axes(ax, report, index, name)
            if index >= 2:
                ax.set_xlabel("trials used (count)")
        handles, labels = axes.flat[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncols=len(handles))
        fig.suptitle("Each estimate after each trial")
    return fig


def _convergence_axes(ax: Axes, report: SessionReport, index: int, name: str) -> None:
    points = [p for p in report.convergence if math.isfinite(p.stderr[index])]
    ns = [p.n_trials for p in points]
    values = [_to_paper(name, p.values[index]) for p in points]
    # The same interval rule as the estimate's (log scale for the variance rates).
    bands = [ParameterEstimate.build(name, p.values[index], p.stderr[index]).ci95 for p in points]
    low = [_to_paper(name, b[0]) for b in bands]
    high = [_to_paper(name, b[1]) for b in bands]
    final = []
    if report.result is not None:
        final = [_to_paper(name, report.result.params.as_tuple()[index])]
    y_low, y_high = _convergence_limits(values + final, low + high)
    # Cut the band just beyond the axes: a huge early bound would not render.
    reach = y_high - y_low
    band_low = np.clip(low, y_low - reach, y_high + reach)
    band_high = np.clip(high, y_low - reach, y_high + reach)
    ax.fill_between(ns, band_low, band_high, color=BLUE, alpha=0.18, linewidth=0,
                    label="95 % interval")  # fmt: skip
    ax.plot(ns, values, "o-", color=BLUE, markersize=2.5, linewidth=1.2,
            label="estimate after each trial (Gaussian fit)")  # fmt: skip
    if report.result is not None:
        ax.axhline(final[0], color=RED, linestyle="--", linewidth=1.2,
                   label=f"final estimate ({report.result.method} fit)")  # fmt: skip
    ax.set_ylim(y_low, y_high)
    ax.set_ylabel(f"{name} ({units.parameter_unit(name, 'paper') or 'no unit'})")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))


def _convergence_limits(core: Sequence[float], band: Sequence[float]) -> tuple[float, float]:
    """Y limits showing the estimates and their bands, the bands cut at twice the
    estimates' own spread beyond them (an early band can be astronomically wide)."""
    finite = [v for v in core if math.isfinite(v)] or [0.0]
    low, high = min(finite), max(finite)
    spread = high - low or max(abs(high), 1e-12)
    wide = [v for v in band if math.isfinite(v)]
    low = max(min([*wide, low]), low - 2.0 * spread)
    high = min(max([*wide, high]), high + 2.0 * spread)
    margin = 0.05 * (high - low)
    return (low - margin, high + margin)


def model_check_figure(report: SessionReport) -> Figure:
    """Each trial's squared Mahalanobis distance from the model at the estimate,
    with its mean (3) and the outlier level; trials left out at the bottom."""
    trials = report.trials
    in_fit = [t for t in trials if t.mahalanobis2 is not None]
    n = len(in_fit)
    limit = distributions.chi2_isf(0.01 / max(n, 1), 3)
    fig = _figure(7.4, 3.8)
    with mpl.rc_context(_RC):
        ax = fig.add_subplot()
        ax.axhline(
            3.0, color=GREY, linestyle=":", linewidth=1.2, label="mean if the model fits (3)"
        )
        ax.axhline(limit, color=RED, linestyle="--", linewidth=1.2,
                   label="outlier level (1 %, Bonferroni)")  # fmt: skip
        shown = [t for t in trials if t.mahalanobis2 is not None or not t.used]
        d2 = np.array([t.mahalanobis2 or 0.0 for t in shown], dtype=np.float64)
        _mark_trials(ax, shown, [float(t.trial) for t in shown], d2)
        ax.set_ylim(bottom=-0.04 * max([limit, *d2.tolist()]))
        ax.set_title("Model check: squared Mahalanobis distance per trial")
        ax.set_xlabel("trial number (left-out trials drawn at 0)")
        ax.set_ylabel("d² (no unit; χ² with 3 dof)")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        _legend_outside(fig, ax)
    return fig
