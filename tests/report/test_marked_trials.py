"""Flagged, excluded, ambiguous and down-weighted trials: marked in the plots
(each in its own style, with a legend that matches and stays off the data) and
listed by trial number in index.html. Sessions run by the engine against the
in-process fake robot."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from odohil.session.results.report import SessionReport, TrialPoint, load_report
from odohil.session.results.report.plots import (
    convergence_figure,
    end_points_figure,
    model_check_figure,
    phi1_figure,
)
from tests.session.test_selection_session import NO_CROSS_TOML

from .page import assert_self_contained, parse_page
from .run import run_report
from .session_factory import build_session

PLAN = "k=1,l=2,n=6;k=4,l=0.5,n=6"


@pytest.fixture(scope="module")
def kept(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """From trial 5 on the operator types one distance 10 mm long, and keeps it
    when the slip check doubts the trial."""
    folder = tmp_path_factory.mktemp("kept") / "session"
    build_session(folder, PLAN, seed=7, kept_slips_from=5)
    return folder


@pytest.fixture(scope="module")
def ambiguous(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Without cross distances most trials of a short closed path are ambiguous
    (the paper's Nomad's priors resolve a few: without [priors] the unknown
    robot's belief resolves none past the first, and there is no fit to draw)."""
    folder = tmp_path_factory.mktemp("ambiguous") / "session"
    build_session(folder, "k=1,l=1,n=8", seed=4, robot_toml=NO_CROSS_TOML + "\n[priors]\n")
    return folder


def _figures(report: SessionReport) -> Iterator[Figure]:
    yield from (end_points_figure(d) for d in report.designs)
    yield phi1_figure(report)
    yield convergence_figure(report)
    yield model_check_figure(report)


def _collection(figure: Figure, label_start: str) -> PathCollection | None:
    found = [
        c
        for ax in figure.axes
        for c in ax.collections
        if isinstance(c, PathCollection) and str(c.get_label()).startswith(label_start)
    ]
    assert len(found) <= 1
    return found[0] if found else None


def _offsets(figure: Figure, label_start: str) -> list[tuple[float, float]]:
    found = _collection(figure, label_start)
    if found is None:
        return []
    return sorted((float(x), float(y)) for x, y in np.asarray(found.get_offsets()))


def _end_points_mm(trials: list[TrialPoint]) -> list[tuple[float, float]]:
    return sorted((1e3 * t.pose[0], 1e3 * t.pose[1]) for t in trials)


def _same_points(drawn: list[tuple[float, float]], expected: list[tuple[float, float]]) -> None:
    """The same end points (mm), within float rounding: pytest.approx takes
    no nested sequences (pytest >= 9.1 says so), so compare the arrays."""
    got = np.array(drawn, dtype=np.float64).reshape(-1, 2)
    want = np.array(expected, dtype=np.float64).reshape(-1, 2)
    assert got.shape == want.shape, (drawn, expected)
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-9)


def test_a_kept_slip_is_flagged_in_the_plots_and_listed_by_number(
    kept: Path, tmp_path: Path
) -> None:
    report = load_report(kept)
    flagged = [t for t in report.trials if t.flagged]
    assert flagged, "the slip check doubted no trial"
    assert all(t.note for t in flagged)
    for design in report.designs:
        mine = [t for t in flagged if t.design == design.design.label()]
        figure = end_points_figure(design)
        _same_points(_offsets(figure, "flagged"), _end_points_mm(mine))
        used = [t for t in design.trials if t.used]
        _same_points(_offsets(figure, "trial used"), _end_points_mm(used))
        # Every marked trial is labelled with its number beside it.
        labels = {t.get_text() for t in figure.axes[0].texts}
        assert {str(t.trial) for t in design.trials if t.marked} <= labels
    check = model_check_figure(report)
    assert [x for x, _ in _offsets(check, "flagged")] == [float(t.trial) for t in flagged]

    out = tmp_path / "out"
    run = run_report(kept, out, "--force")
    assert run.returncode == 0, run.stderr
    page = parse_page(out / "index.html")
    assert_self_contained(page)
    listed = {n for n, what in page.pointed_out.items() if "flagged" in what}
    assert listed == {t.trial for t in flagged}
    text = (out / "index.html").read_text()
    for t in flagged:
        row = re.search(rf"<tr><td>{t.trial}</td>.*?</tr>", text, flags=re.DOTALL)
        assert row is not None
        assert "line" not in row.group(0).replace("linear", "")  # by number, not journal line


def test_ambiguous_trials_are_drawn_apart_and_listed(ambiguous: Path, tmp_path: Path) -> None:
    report = load_report(ambiguous)
    left_out = [t.trial for t in report.trials if t.ambiguous]
    assert left_out, "expected ambiguous trials without cross distances"
    check = model_check_figure(report)
    # Not in the fit: drawn at d^2 = 0, one diamond per trial.
    assert _offsets(check, "ambiguous") == [(float(n), 0.0) for n in left_out]
    assert [x for x, _ in _offsets(check, "trial used")] == [
        float(t.trial) for t in report.trials if t.used
    ]
    out = tmp_path / "out"
    run = run_report(ambiguous, out, "--force")
    assert run.returncode == 0, run.stderr
    page = parse_page(out / "index.html")
    assert_self_contained(page)
    assert {n for n, what in page.pointed_out.items() if "ambiguous" in what} == set(left_out)


def test_excluded_and_down_weighted_trials_are_marked(bumped: Path) -> None:
    folder = bumped
    report = load_report(folder)
    down = [t.trial for t in report.trials if t.down_weighted]
    assert down == [3]
    check = model_check_figure(report)
    assert [x for x, _ in _offsets(check, "outlier, down-weighted")] == [3.0]

    without = load_report(folder, exclude={3, 5})
    assert [t.trial for t in without.trials if t.excluded] == [3, 5]
    first = end_points_figure(without.designs[0])
    excluded = [t for t in without.designs[0].trials if t.excluded]
    _same_points(_offsets(first, "excluded"), _end_points_mm(excluded))
    assert _offsets(model_check_figure(without), "excluded") == [(3.0, 0.0), (5.0, 0.0)]


def test_legends_stay_off_the_data_and_show_what_is_drawn(kept: Path) -> None:
    report = load_report(kept, exclude={2})
    for figure in _figures(report):
        canvas = FigureCanvasAgg(figure)
        canvas.draw()  # type: ignore[no-untyped-call]  # lays the figure out as when saved
        renderer = canvas.get_renderer()  # type: ignore[no-untyped-call]
        assert figure.legends, "no legend"
        for ax in figure.axes:
            assert ax.get_legend() is None  # legends are the figure's, outside the axes
            box = ax.get_window_extent(renderer)
            for legend in figure.legends:
                assert not legend.get_window_extent(renderer).overlaps(box)
            # Units on every axis label.
            for label in (ax.get_xlabel(), ax.get_ylabel()):
                if label:
                    assert re.search(r"\(.+\)", label), label
            assert ax.get_ylabel()
        assert any(ax.get_xlabel() for ax in figure.axes)
        for legend in figure.legends:
            for handle, text in zip(legend.legend_handles, legend.get_texts(), strict=True):
                label = text.get_text()
                if "region" in label or "interval" in label:
                    assert isinstance(handle, Patch), label  # an area as a patch
                elif "model mean" in label:
                    assert isinstance(handle, Line2D)
                    assert handle.get_marker() == "+"
                    assert handle.get_linestyle() == "None"
                elif label.startswith(("fitted", "final", "outlier level", "mean if")):
                    assert isinstance(handle, Line2D), label  # a line as a line
                    assert handle.get_linestyle() != "None"
                elif label.startswith("estimate after each trial"):
                    assert isinstance(handle, Line2D), label  # a line through points
                    assert handle.get_linestyle() != "None"
                    assert handle.get_marker() == "o"
                elif "standard error" in label:
                    assert handle is not None  # an error bar: marker and bar
                else:
                    assert isinstance(handle, PathCollection), label  # points as points
