"""The calibration report (station/report*.py), the quality verdict (station/report/quality.py) and
``handeye calibrate --report``."""

from __future__ import annotations

import base64
import json
import re
from html.parser import HTMLParser

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.geometry.board import BoardGeometry, board_corners
from handeye.base.errors import HandEyeError
from handeye.calibration.session import Posture, Session, create_session, read_session, write_posture, write_truth
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session, truth_dict
from handeye.geometry.transforms import invert_transforms, rotation_error_deg, transform_from_pose, transform_from_rotation_translation
from handeye.rapid.literals import pose_literal
from handeye.station.cli import main
from handeye.calibration.quality_words import rotation_axis_coverage
from handeye.station.report.assessment import comparison_results, corner_repeatability
from handeye.station.report.quality import QualityThresholds, ThresholdError, load_thresholds, verdict
from handeye.station.report.document import write_report

from helpers import assessed, scene

GOOD_NOISE = NoiseConfig(sigma_rob_deg=0.001, sigma_cam_mm=0.05, camera_model="gaussian", seed=1)
PLOTS = ("per-posture residuals", "rotation-axis coverage", "method comparison",
         "repeatability of the board corners, top and side views", "per-corner RMS deviation")


def _write(path, session, truth=None):
    create_session(path, session)
    for posture in session.postures:
        write_posture(path, posture)
    if truth is not None:
        write_truth(path, truth)
    return path


@pytest.fixture(scope="module")
def good_session(tmp_path_factory):
    sc = scene(12)
    path = tmp_path_factory.mktemp("report") / "good"
    return _write(path, sample_session(sc, GOOD_NOISE), truth_dict(sc, GOOD_NOISE))


def _literal_pose(text):
    """Parse ``[[x,y,z],[q1,q2,q3,q4]]`` into a 4x4 transform."""
    numbers = [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?", text)]
    assert len(numbers) == 7, text
    return transform_from_pose(numbers[:3], numbers[3:])


def _assert_self_contained(page: str):
    assert "http://" not in page and "https://" not in page
    assert "<script" not in page.lower() and "<link" not in page.lower() and "url(" not in page
    assert "href=" not in page
    sources = re.findall(r'src="([^"]*)"', page)
    assert sources, "no images"
    for src in sources:
        assert src.startswith("data:image/png;base64,"), src[:60]
        png = base64.b64decode(src.split(",", 1)[1])
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        width, height = int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")
        assert width >= 400 and height >= 150
    return sources


def test_cli_report_is_self_contained_with_pose_verdict_and_every_plot(good_session, tmp_path, capsys):
    out = tmp_path / "result.json"
    assert main(["calibrate", str(good_session), "--report", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    report = good_session / "report.html"
    assert report.is_file()
    assert f"Report written to {report}" in printed
    assert "verdict: PASS (10 of 10 checks)" in printed
    page = report.read_text()
    sources = _assert_self_contained(page)
    assert len(sources) == len(PLOTS)
    for alt in PLOTS:
        assert f'alt="{alt}"' in page
    for heading in ("1. Per-posture residuals", "2. Rotation-axis coverage", "3. Method comparison",
                    "4. Repeatability of the board corners in base", "5. Quality metrics", "Quality checks"):
        assert heading in page
    assert 'class="verdict pass">PASS<' in page

    # the literal in the report is the solved pose, and the solved pose is the truth
    data = json.loads(out.read_text())
    x = transform_from_pose(data["camera_pose"]["position_mm"], data["camera_pose"]["quaternion_wxyz"])
    literal = pose_literal(x)
    assert literal in page and literal in printed
    truth = scene(12).x_true
    reported = _literal_pose(re.search(r'<code class="literal">([^<]+)</code>', page).group(1))
    assert np.linalg.norm(reported[:3, 3] - truth[:3, 3]) < 0.5
    assert rotation_error_deg(reported, truth) < 0.05

    # every compared method is in the table; truth errors shown for a synthetic session
    for method in ("ml (chosen)", "robust", "mcb", "mc", "park", "tsai", "daniilidis"):
        assert f">{method}<" in page
    assert "truth error (mm)" in page

    # JSON: the command's keys unchanged, plus the verdict
    assert {"method", "setup", "camera_pose", "metrics", "outliers", "runtime_s"} <= set(data)
    assert data["verdict"]["passed"] is True
    assert [c["name"] for c in data["verdict"]["checks"]] == list(QualityThresholds().to_dict())


def test_outlier_postures_are_listed_with_their_residuals_and_plotted_apart(tmp_path):
    sc = scene(12)
    session = sample_session(sc, GOOD_NOISE)
    for index in (3, 8):  # a board measured 8 mm off: misdetection
        session.postures[index].points_mm = session.postures[index].points_mm + np.array([6.0, -4.0, 4.0])
    problem = problem_from_session(session)
    result = calibrate(problem)
    assert result.outliers == [3, 8]
    judged = verdict(result, problem)
    outlier_check = next(c for c in judged.checks if c.name == "max_outlier_fraction")
    assert outlier_check.passed and "3 (" in outlier_check.advice and "8 (" in outlier_check.advice

    path = write_report(tmp_path / "r.html", assessed(problem, result, "synthetic", methods=("robust", "mcb", "tsai")))
    page = path.read_text()
    _assert_self_contained(page)
    for index in (3, 8):
        assert f"posture {index}: {result.residuals_mm[index]:.2f} mm" in page
    assert "d_org incl. outliers (mm)" in page

    # repeatability: the mean is over the inliers, so a shifted posture's board centre moves by the shift
    rep = corner_repeatability(problem, result)
    assert not rep["inliers"][3] and not rep["inliers"][8]
    assert np.all(np.linalg.norm(rep["centre_deviation"][rep["inliers"]], axis=1) < 0.2)
    for index in (3, 8):
        chain = problem.hand[index] @ result.x
        expected = chain[:3, :3] @ np.array([6.0, -4.0, 4.0])
        assert np.linalg.norm(rep["centre_deviation"][index] - expected) < 0.3


@pytest.mark.parametrize("method", ["ml", "robust", "mcb"])
def test_the_residual_section_names_the_points_the_same_for_every_method(tmp_path, method):
    # one posture residual (calibration/quality_words.py) for the estimators and the others alike
    from html import escape

    from handeye.calibration.quality_words import posture_residual_meaning

    problem = problem_from_session(sample_session(scene(12), GOOD_NOISE))
    result = calibrate(problem, method)
    page = write_report(tmp_path / "r.html", assessed(problem, result, "synthetic")).read_text()
    assert f"Each bar: the {escape(posture_residual_meaning('corners'))}; the fixed frame is base." in page
    assert "on the board corners" in posture_residual_meaning("corners")


def test_bad_session_fails_with_advice(tmp_path, capsys):
    sc = scene(8)
    noise = NoiseConfig(sigma_cam_mm=5.0, seed=3)
    path = _write(tmp_path / "bad", sample_session(sc, noise))
    report = tmp_path / "bad_report.html"
    assert main(["calibrate", str(path), "--report", str(report), "--quiet", "--json", str(tmp_path / "r.json")]) == 0
    assert capsys.readouterr().out == ""
    data = json.loads((tmp_path / "r.json").read_text())["verdict"]
    assert data["passed"] is False
    failed = {c["name"]: c for c in data["checks"] if not c["passed"]}
    assert {"max_d_org_mm", "min_inlier_postures", "max_sigma_translation_mm"} <= set(failed)
    assert all(c["advice"] for c in failed.values())
    assert "capture at least 4 more" in failed["min_inlier_postures"]["advice"]
    assert failed["max_d_org_mm"]["value"] > 1.0
    page = report.read_text()
    assert 'class="verdict fail">FAIL<' in page
    assert "capture at least 4 more" in page


def _planar_rotation_problem():
    """Flange rotations about tool0 x and y only (never about z): exact data, board anywhere."""
    x = transform_from_rotation_translation(Rotation.from_euler("xyz", [3, -2, 85], degrees=True).as_matrix(),
                                            [60.0, -110.0, 95.0])
    target2base = transform_from_rotation_translation(Rotation.from_euler("x", 180, degrees=True).as_matrix(),
                                                      [900.0, 100.0, 50.0])
    base = transform_from_rotation_translation(Rotation.from_euler("y", 180, degrees=True).as_matrix(),
                                               [900.0, 100.0, 900.0])
    corners = board_corners((13, 8), 30.0)
    rng = np.random.default_rng(7)
    postures = []
    for i in range(14):
        tilt = np.r_[rng.uniform(-30, 30, 2), 0.0]  # a rotation vector in the x-y plane of tool0
        motion = transform_from_rotation_translation(Rotation.from_rotvec(tilt, degrees=True).as_matrix(),
                                                     rng.uniform(-80, 80, 3))
        tool02base = base @ motion
        target2cam = invert_transforms(tool02base @ x) @ target2base
        points = corners @ target2cam[:3, :3].T + target2cam[:3, 3]
        postures.append(Posture(index=i, tool0_in_base=tool02base, points_mm=points))
    session = Session(setup="eye_in_hand", robot=None, target=BoardGeometry((13, 8), 30.0), postures=postures)
    return problem_from_session(session), x


def test_axis_coverage_finds_the_direction_never_turned_about():
    problem, x_true = _planar_rotation_problem()
    coverage = rotation_axis_coverage(problem)
    assert abs(coverage.weakest_direction[2]) > 0.95  # tool0 z
    assert coverage.spread_deg < 8.0
    assert coverage.rms_about_axes_deg[2] < 0.3 * min(coverage.rms_about_axes_deg[:2])
    result = calibrate(problem, "mcb")
    assert rotation_error_deg(result.x, x_true) < 1e-6  # two axes do determine X on exact data
    check = next(c for c in verdict(result, problem).checks if c.name == "min_rotation_axis_spread_deg")
    assert not check.passed and "tool0 z" in check.advice and "axis 6" in check.advice

    good = rotation_axis_coverage(problem_from_session(sample_session(scene(12), GOOD_NOISE)))
    assert good.spread_deg > 10.0  # the synthetic plan turns about every direction


def test_verdict_follows_the_thresholds(good_session, tmp_path, capsys):
    problem = problem_from_session(read_session(good_session))
    result = calibrate(problem)
    assert verdict(result, problem).passed
    strict = verdict(result, problem, QualityThresholds(min_inlier_postures=20, max_sigma_translation_mm=1e-4))
    assert not strict.passed
    assert {c.name for c in strict.failed} == {"min_inlier_postures", "max_sigma_translation_mm"}
    no_sigma = verdict(calibrate(problem, "mcb"), problem)
    sigma = next(c for c in no_sigma.checks if c.name == "max_sigma_translation_mm")
    assert sigma.value is None and not sigma.passed and "without --method" in sigma.advice

    # a station config's quality section is read, the rest ignored
    config = tmp_path / "station.yaml"
    config.write_text("controller: {protocol: socket}\nquality:\n  min_inlier_postures: 20\n")
    assert load_thresholds(config).min_inlier_postures == 20
    assert main(["calibrate", str(good_session), "--thresholds", str(config), "--quiet",
                 "--json", str(tmp_path / "j.json")]) == 0
    assert json.loads((tmp_path / "j.json").read_text())["verdict"]["passed"] is False


@pytest.mark.parametrize("mapping, words", [
    ({"max_dorg_mm": 1.0}, ["unknown key 'max_dorg_mm'", "max_d_org_mm"]),
    ({"max_d_org_mm": -1.0}, ["max_d_org_mm", "positive"]),
    ({"max_sigma_rotation_deg": "small"}, ["max_sigma_rotation_deg", "number"]),
    ({"min_inlier_postures": 2.5}, ["min_inlier_postures", "whole number"]),
    ({"max_outlier_fraction": 1.5}, ["max_outlier_fraction", "between 0 and 1"]),
    ({"max_posture_residual_mm": True}, ["max_posture_residual_mm", "number"]),
    ({"min_rotation_axis_spread_deg": 40}, ["min_rotation_axis_spread_deg", "35.3"]),
    ([1, 2], ["mapping"]),
])
def test_threshold_errors_name_the_key(mapping, words):
    with pytest.raises(ThresholdError) as info:
        QualityThresholds.from_dict(mapping)
    message = str(info.value)
    assert "\n" not in message and isinstance(info.value, HandEyeError)
    for word in words:
        assert word in message


@pytest.mark.parametrize("text, words", [
    ("max_dorg_mm: 1.0\n", ["unknown key 'max_dorg_mm'"]),
    ("max_d_org_mm: -0.5\n", ["max_d_org_mm", "positive"]),
    ("max_d_org_mm: [1\n", ["not valid YAML"]),
])
def test_cli_bad_thresholds_file_is_one_line_exit_1(good_session, tmp_path, capsys, text, words):
    bad = tmp_path / "thresholds.yaml"
    bad.write_text(text)
    report = tmp_path / "never.html"
    assert main(["calibrate", str(good_session), "--report", str(report), "--thresholds", str(bad)]) == 1
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert err.startswith("handeye calibrate: error:") and "\n" not in err and "Traceback" not in err
    assert str(bad) in err
    for word in words:
        assert word in err
    assert captured.out == "" and not report.exists()


def test_cli_report_into_missing_folder_is_refused(good_session, tmp_path, capsys):
    assert main(["calibrate", str(good_session), "--report", str(tmp_path / "no" / "r.html")]) == 1
    err = capsys.readouterr().err.strip()
    assert "does not exist" in err and "\n" not in err


def test_comparison_skips_methods_that_cannot_solve(good_session):
    problem = problem_from_session(read_session(good_session))
    results = comparison_results(problem, ("robust", "mcy", "tsai"))  # mcy needs the truth: CalibrationError
    assert list(results) == ["robust", "tsai"]
    truth = scene(12)
    for r in results.values():
        assert np.linalg.norm(r.x[:3, 3] - truth.x_true[:3, 3]) < 2.0


def test_shipped_thresholds_file_matches_the_defaults():
    from pathlib import Path

    import handeye.station

    shipped = Path(handeye.station.__file__).parent / "quality_thresholds.yaml"
    assert load_thresholds(shipped) == QualityThresholds()


# ------------------------------------------------------------------ issue 9: one d_org, FAIL literals, MOCK
class _Tables(HTMLParser):
    """Every <table> of a page as rows of cell texts (header cells included)."""

    def __init__(self):
        super().__init__()
        self.tables, self._cell = [], None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr" and self.tables:
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.tables[-1][-1].append(" ".join("".join(self._cell).split()))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _tables(page):
    parser = _Tables()
    parser.feed(page)
    return parser.tables


def _header_d_org(page) -> float:
    """The d_org the report's header (summary facts) shows."""
    return float(re.search(r"<div>d_org</div><div>(?:<span[^>]*>)?([0-9.]+) mm", page).group(1))


def _outlier_session(tmp_path):
    sc = scene(12)
    session = sample_session(sc, GOOD_NOISE)
    for index in (3, 8):  # a board measured 8 mm off: misdetection
        session.postures[index].points_mm = session.postures[index].points_mm + np.array([6.0, -4.0, 4.0])
    return _write(tmp_path / "outliers", session)


def test_d_org_is_one_figure_in_header_table_chart_verdict_text_and_json(tmp_path, capsys, monkeypatch):
    """A session with outliers: the header's d_org is the chosen method's d_org in the comparison table
    and chart, the verdict's max_d_org_mm value, the JSON metrics and the text summary (on main the
    header showed the result's own metric and the table another definition under the same name)."""
    import handeye.station.report.figures as report_figures

    figures = []
    original = report_figures.to_png
    monkeypatch.setattr(report_figures, "to_png", lambda fig: (figures.append(fig), original(fig))[1])
    path = _outlier_session(tmp_path)
    out = tmp_path / "r.json"
    assert main(["calibrate", str(path), "--report", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["outliers"] == [3, 8]
    page = (path / "report.html").read_text()

    header = _header_d_org(page)
    table = next(t for t in _tables(page) if t[0][0] == "method")
    d_org_columns = [k for k, name in enumerate(table[0]) if name.startswith("d_org") and "incl. outliers" not in name]
    assert len(d_org_columns) == 1, table[0]  # one column called d_org; the all-postures one is named apart
    chosen = next(row for row in table[1:] if row[0].endswith("(chosen)"))
    assert float(chosen[d_org_columns[0]]) == header

    # the header says which postures and points
    assert "over the 10 inlier postures (2 outliers left out), 104 board corners per posture" in page
    assert "d_org incl. outliers" in page

    # the chart's d_org panel: the chosen method's bar (the top one) has the header's value
    chart = figures[2]
    panels = [ax for ax in chart.axes if ax.get_title().startswith("d_org") and "incl. outliers" not in ax.get_title()]
    assert len(panels) == 1
    bars = sorted(panels[0].patches, key=lambda bar: -bar.get_y())
    assert round(bars[0].get_width(), 3) == header

    check = next(c for c in data["verdict"]["checks"] if c["name"] == "max_d_org_mm")
    assert round(check["value"], 3) == header
    assert round(data["metrics"]["d_org_mm"], 3) == header
    assert re.search(rf"d_org\s+{header:.3f} mm", printed)
    assert "over the 10 inlier postures (2 outliers left out)" in printed

    # the all-postures figure is larger (the outliers scatter) and carries its own name everywhere
    all_column = next(k for k, name in enumerate(table[0]) if "incl. outliers" in name)
    assert float(chosen[all_column]) > 3 * header
    assert re.search(rf"d_org incl\. outliers\s+{float(chosen[all_column]):.3f} mm", printed)


def test_a_failed_result_is_greyed_out_and_says_do_not_write(tmp_path):
    sc = scene(8)
    session = sample_session(sc, NoiseConfig(sigma_cam_mm=5.0, seed=3))
    problem = problem_from_session(session)
    result = calibrate(problem)
    judged = verdict(result, problem)
    assert not judged.passed
    literal = pose_literal(result.x)
    tool = "[TRUE,[[1,2,3],[1,0,0,0]],[1.8,[0,0,60],[1,0,0,0],0,0,0]]"
    page = write_report(tmp_path / "fail.html", assessed(problem, result, "s", tooldata_literal=tool)).read_text()
    assert "FAIL &ndash; do not write this into the robot" in page
    # no copyable literal left: both are struck through, grey and not selectable
    assert '<code class="literal">' not in page
    assert f'<del class="void">{literal}</del>' in page and f'<del class="void">{tool}</del>' in page
    style = re.search(r"\.void\{([^}]*)\}", page).group(1)
    assert "line-through" in style and "user-select:none" in style and "#9e9e9e" in style
    banner = page.index("do not write this into the robot")
    assert banner < page.index(f'<del class="void">{literal}</del>')


def test_a_passed_result_stays_copyable(good_session, tmp_path):
    problem = problem_from_session(read_session(good_session))
    result = calibrate(problem)
    judged = verdict(result, problem)
    assert judged.passed
    page = write_report(tmp_path / "pass.html", assessed(problem, result, good_session)).read_text()
    assert f'<code class="literal">{pose_literal(result.x)}</code>' in page
    assert "do not write" not in page and 'class="void"' not in page and 'class="donotwrite"' not in page
    style = re.search(r"\n\.literal\{([^}]*)\}", page).group(1)
    assert "user-select:all" in style


def test_cli_text_marks_a_failed_literal(tmp_path, capsys):
    path = _write(tmp_path / "bad", sample_session(scene(8), NoiseConfig(sigma_cam_mm=5.0, seed=3)))
    assert main(["calibrate", str(path), "--thresholds", str(_shipped_thresholds())]) == 0
    printed = capsys.readouterr().out
    assert "verdict: FAIL" in printed
    line = next(line for line in printed.splitlines() if "[[" in line)
    assert line.strip().startswith("FAIL - do not write this into the robot")


def _shipped_thresholds():
    from pathlib import Path

    import handeye.station

    return Path(handeye.station.__file__).parent / "quality_thresholds.yaml"


def test_shipped_thresholds_file_lists_every_key_with_its_default():
    import yaml

    assert yaml.safe_load(_shipped_thresholds().read_text()) == QualityThresholds().to_dict()
