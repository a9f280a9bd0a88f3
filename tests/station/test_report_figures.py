"""The report's figures are readable: no two pieces of text (tick labels, axis labels, titles, value
labels, legends) overlap, in every figure of reports on different data (issue 9: the method
comparison's rotation axis had its tick labels run into each other)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import handeye.station.report.figures as report_figures
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.station.report.assessment import COMPARISON_METHODS, comparison_results, method_comparison
from handeye.station.report.document import write_report

from helpers import assessed, scene

GOOD_NOISE = NoiseConfig(sigma_rob_deg=0.001, sigma_cam_mm=0.05, camera_model="gaussian", seed=1)


def _drawn_texts(fig):
    """Every piece of text the figure draws, with its bounding box in pixels."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    texts = []
    for ax in fig.axes:
        if ax.axison:
            for axis in (ax.xaxis, ax.yaxis):
                for tick in axis._update_ticks():  # the ticks inside the view, the ones drawn
                    texts += [label for label in (tick.label1, tick.label2) if label.get_visible()]
                texts += [axis.label, axis.offsetText]
        texts += [ax.title, ax._left_title, ax._right_title]
        texts += [t for t in ax.texts]
        legend = ax.get_legend()
        if legend is not None:
            texts += legend.get_texts()
    for legend in fig.legends:
        texts += legend.get_texts()
    texts += fig.texts
    out = []
    for text in texts:
        if not text.get_visible() or not text.get_text().strip():
            continue
        if hasattr(text, "_check_xy") and not text._check_xy(renderer):  # an annotation not drawn (clipped)
            continue
        out.append((text.get_text(), text.get_window_extent(renderer)))
    return out


def overlapping_texts(fig, gap_px: float = 2.0) -> list:
    """Pairs of texts that overlap or come closer than ``gap_px`` (labels that touch read as one:
    '0.00000.0025')."""
    pairs = []
    for (a, box_a), (b, box_b) in itertools.combinations(_drawn_texts(fig), 2):
        dx = min(box_a.x1, box_b.x1) - max(box_a.x0, box_b.x0)  # > 0: the boxes share columns
        dy = min(box_a.y1, box_b.y1) - max(box_a.y0, box_b.y0)
        if dx > -gap_px and dy > -gap_px and (dx > 0 or dy > 0):
            pairs.append((a, b))
    return pairs


@pytest.fixture
def figures(monkeypatch):
    """The figures ``write_report`` renders, in order (``report_figures.to_png`` still writes the PNG)."""
    captured = []
    original = report_figures.to_png

    def capture(fig):
        captured.append(fig)
        return original(fig)

    monkeypatch.setattr(report_figures, "to_png", capture)
    return captured


def _session(postures=12, setup="eye_in_hand", noise=GOOD_NOISE, shifted=()):
    session = sample_session(scene(postures, setup), noise)
    for index in shifted:  # a misdetected board: far off
        session.postures[index].points_mm = session.postures[index].points_mm + np.array([60.0, -40.0, 40.0])
    return problem_from_session(session)


CASES = {
    "good": dict(),
    "adjacent gross outliers": dict(postures=16, shifted=(3, 4, 5)),
    "noise-free": dict(noise=NoiseConfig(seed=1)),
    "eye-to-hand": dict(setup="eye_to_hand"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_no_text_overlaps_in_any_report_figure(case, figures, tmp_path):
    problem = _session(**CASES[case])
    result = calibrate(problem)
    write_report(tmp_path / "r.html", assessed(problem, result, "s", methods=COMPARISON_METHODS))
    assert len(figures) == 5
    for fig in figures:
        assert overlapping_texts(fig) == [], fig.axes[0].get_title()


def test_method_comparison_rotation_ticks_do_not_run_into_each_other(figures):
    """The figure of issue 9: rotation differences of 0.002-0.011 deg (ticks every 0.0025 deg used to
    print as '0.00000.00250.0050...')."""
    problem = _session()
    result = calibrate(problem)
    rows = method_comparison(problem, result, comparison_results(problem, known={"robust": result}))
    for r, d in zip(rows, (0.0, 0.0021, 0.0104, 0.0104, 0.0111, 0.0094)):  # the demo's values
        r["d_rotation_deg"] = d
    report_figures.plot_method_comparison(rows)
    fig = figures[-1]
    assert overlapping_texts(fig) == []
    rotation = next(ax for ax in fig.axes if ax.get_title().startswith("rotation difference"))
    labels = [t.get_text() for t in rotation.get_xticklabels() if t.get_text()]
    assert 2 <= len(labels) <= 5 and len(set(labels)) == len(labels)
    for ax in fig.axes:  # every panel's tick labels are plain numbers: no offset text far from the axis
        assert ax.xaxis.offsetText.get_text() == ""


def test_overlap_check_can_fail():
    """The checker itself finds overlapping tick labels (so the tests above can fail)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2.0, 1.5))
    ax = fig.add_subplot()
    ax.set_xlim(0, 0.015)
    ax.set_xticks(np.arange(0, 0.0151, 0.0025))
    ax.set_xticklabels([f"{v:.4f}" for v in np.arange(0, 0.0151, 0.0025)])
    assert overlapping_texts(fig)
