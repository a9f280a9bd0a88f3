"""The numbered sections of the calibration report after its head: the quality checks, per-posture
residuals, rotation-axis coverage, the method comparison, repeatability, the quality metrics, the
data checks made before solving and the capture plan's preview. Each shows what the assessment
holds; nothing here solves."""

from __future__ import annotations

import numpy as np

from ...calibration import bounded_pairs, pairs_used
from ...calibration import D_ORG_ALL_NAME, METRIC_MEANINGS, hand_frame
from .assessment import Assessment
from .quality import CHECK_LABELS, Verdict, direction_name, format_check_value
from .figures import plot_axis_coverage, plot_method_comparison, plot_point_rms, plot_repeatability, plot_residuals
from .html import escape, img, num
from .summary import excluded_html

__all__ = ["checks_section", "residuals_section", "coverage_section", "comparison_section", "repeatability_section",
           "metrics_table", "findings_section", "preview_section"]


def _checks_table(verdict: Verdict) -> str:
    rows = []
    for c in verdict.checks:
        label = CHECK_LABELS.get(c.name, (c.name,))[0]
        comparator = "&le;" if c.name.startswith("max_") else "&ge;"
        status = '<span class="ok">pass</span>' if c.passed else '<span class="ko">FAIL</span>'
        rows.append(
            f'<tr class="{"" if c.passed else "bad"}"><td>{status}</td><td>{escape(label)}<br><code class="note">{escape(c.name)}'
            f'</code></td><td class="num">{escape(format_check_value(c.name, c.value))}</td>'
            f'<td class="num">{comparator} {escape(format_check_value(c.name, c.limit))}</td><td>{escape(c.advice)}</td></tr>')
    return ("<table><tr><th></th><th>check (threshold key)</th><th>value</th><th>limit</th><th>what to do</th></tr>"
            + "".join(rows) + "</table>")


def _comparison_table(rows: list[dict]) -> str:
    with_all = any(r["d_org_incl_outliers_mm"] is not None for r in rows)
    with_truth = any(r["truth_errors"] for r in rows)
    head = ["method", "held-out (mm)", "x (mm)", "y (mm)", "z (mm)", "&Delta; position (mm)", "&Delta; rotation (deg)",
            "d_org (mm)"]
    if with_all:
        head.append(f"{escape(D_ORG_ALL_NAME)} (mm)")
    if with_truth:
        head += ["truth error (mm)", "truth error (deg)"]
    head += ["outliers", "solve (ms)"]
    out = ["<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>"]
    for r in rows:
        cells = [escape(r["method"] + (" (chosen)" if r["chosen"] else ""))]
        cells.append(f'<td class="num">{num(r.get("held_out_mm"))}</td>')
        cells += [f'<td class="num">{v:.3f}</td>' for v in r["position_mm"]]
        cells += [f'<td class="num">{r["d_position_mm"]:.3f}</td>', f'<td class="num">{r["d_rotation_deg"]:.4f}</td>',
                  f'<td class="num">{r["d_org_mm"]:.3f}</td>']
        if with_all:
            cells.append(f'<td class="num">{num(r["d_org_incl_outliers_mm"])}</td>')
        if with_truth:
            t = r["truth_errors"] or {}
            cells += [f'<td class="num">{num(t.get("translation_error_mm"))}</td>',
                      f'<td class="num">{num(t.get("rotation_error_deg"), "{:.4f}")}</td>']
        cells += [f"<td>{escape(', '.join(map(str, r['outliers'])) or '-')}</td>",
                  f'<td class="num">{1000 * r["runtime_s"]:.1f}</td>']
        first = f"<td>{cells[0]}</td>"
        out.append(f'<tr class="{"chosen" if r["chosen"] else ""}">' + first + "".join(cells[1:]) + "</tr>")
    return "".join(out) + "</table>"


def metrics_table(a: Assessment) -> str:
    result, scatter = a.result, a.d_org
    m = result.metrics
    rows = [
        ("d_org", f"{scatter.mm:.3f} mm", METRIC_MEANINGS["d_org"]),
        ("d_back", f"{m['d_back_mm']:.3f} mm", METRIC_MEANINGS["d_back"]),
        ("dR", f"{m['delta_r']:.5f}", METRIC_MEANINGS["dR"]),
        ("dt", f"{m['delta_t_mm']:.3f} mm", METRIC_MEANINGS["dt"]),
    ]
    if scatter.incl_outliers_mm is not None:
        rows.insert(1, (D_ORG_ALL_NAME, f"{scatter.incl_outliers_mm:.3f} mm",
                        f"{METRIC_MEANINGS[D_ORG_ALL_NAME]} ({a.problem.n} postures)"))
    if result.truth_errors is not None:
        rows += [("rotation error", f"{result.truth_errors['rotation_error_deg']:.4f} deg", "against the synthetic truth"),
                 ("translation error", f"{result.truth_errors['translation_error_mm']:.3f} mm", "against the synthetic truth")]
    body = "".join(f'<tr><td>{escape(x)}</td><td class="num">{escape(y)}</td><td>{escape(z)}</td></tr>' for x, y, z in rows)
    return (f'<table><tr><th>metric</th><th>value</th><th>meaning</th></tr>{body}</table>'
            f'<p class="note">d_org and d_back are computed {escape(scatter.basis())}; dR and dt over the pairs of the '
            f'same postures. Lower is better.</p>')


def checks_section(verdict: Verdict) -> str:
    return ("<h2>Quality checks</h2><section>" + _checks_table(verdict)
            + '<p class="note">Thresholds: defaults of <code>handeye.station.report.quality.QualityThresholds</code>'
              " unless a thresholds file was given (handeye calibrate --thresholds FILE.yaml).</p></section>")


def residuals_section(a: Assessment, fixed_frame: str) -> str:
    result = a.result
    limit = a.verdict.thresholds.max_posture_residual_mm if a.verdict is not None else None
    outliers = [int(i) for i in result.outliers]
    residual_note = ("Outliers (left out of the solution): "
                     + ", ".join(f"posture {i}: {result.residuals_mm.get(i, float('nan')):.2f} mm" for i in outliers)
                     if outliers else "No posture was left out as an outlier.")
    return (
        "<h2>1. Per-posture residuals</h2><section>"
        f'<p class="how">Each bar: the {escape(result.residuals_meaning)}; the fixed frame is {fixed_frame}. '
        f"Bars should be about equal; a bar well above "
        f"the others is a posture to check (board partly hidden or misdetected, robot not at rest)."
        + (f" Dashed line: the limit max_posture_residual_mm = {limit:g} mm." if limit is not None else "") + "</p>"
        + img(plot_residuals(result, a.problem, limit), "per-posture residuals")
        + f'<p class="note">{escape(residual_note)}</p>'
        + (f'<p class="note">Outliers left out before solving (the robot and board poses of the session fit no '
           f"rigid camera mount with them): {excluded_html(result.excluded)}</p>" if result.excluded else "")
        + "</section>")


def coverage_section(a: Assessment) -> str:
    coverage, frame = a.coverage, hand_frame(a.problem.setup)
    return (
        "<h2>2. Rotation-axis coverage</h2><section>"
        f'<p class="how">Every dot is the rotation axis of the flange motion between two used postures, in {frame} '
        f"coordinates, drawn on a unit sphere seen from two sides (an axis and its opposite are the same, so each "
        f"view shows every axis once); colour and size grow with the rotation angle. Regions without dots are "
        f"directions the flange never turned about; the red ring marks the least exercised direction "
        f"({escape(direction_name(coverage.weakest_direction, coverage.frame))}). Right: how much the flange turned "
        f"about each {frame} axis.</p>"
        + img(plot_axis_coverage(coverage), "rotation-axis coverage")
        + f'<p class="note">{len(coverage.axes)} posture pairs with a usable axis; median relative rotation angle '
          f"between two postures {coverage.median_angle_deg:.1f} deg; rotation-axis spread {coverage.spread_deg:.1f} deg "
          f"(0 = all axes in one plane, 35.3 = even over the sphere).</p></section>")


def comparison_section(a: Assessment) -> str:
    if not a.comparison:
        return ('<h2>3. Method comparison</h2><section><p class="note">Not computed '
                "(no comparison results were given).</p></section>")
    rows = a.comparison
    return (
        "<h2>3. Method comparison</h2><section>"
        '<p class="how">The same data solved by other methods, ranked by the held-out error: the RMS distance of a '
        "posture's board points from where a fit without that posture puts them (the same folds for every method, "
        "over the postures the chosen result kept). &Delta; = difference from the chosen result "
        "(position distance, rotation angle). d_org (eq. 22) is computed for every method on the same data, "
        f"{escape(a.d_org.basis())}, as in the header and the verdict, so the column compares "
        "like with like"
        + (f"; {escape(D_ORG_ALL_NAME)}: the same over all {a.problem.n} postures. " if a.result.outliers else ". ")
        + "Methods that agree within a few tenths of a millimetre confirm the result; one far off is usually a "
        "method thrown by outliers or weak geometry.</p>"
        + (f'<p class="note" data-note="d-org">{escape(a.comparison_note)}</p>' if a.comparison_note else "")
        + (f'<p class="note" data-note="rank">{escape(a.rank_note)}</p>' if a.rank_note else "")
        + "".join(f'<p class="note" data-note="not-compared">Not compared: {escape(reason)}</p>'
                  for reason in a.comparison_failures.values())
        + _comparison_table(rows) + img(plot_method_comparison(rows), "method comparison") + "</section>")


def repeatability_section(a: Assessment, fixed_frame: str) -> str:
    rep = a.repeatability
    rms = rep["rms_per_point"]
    radial = np.linalg.norm(rep["centre_deviation"][rep["inliers"]], axis=1)
    scatter_png, clipped = plot_repeatability(a.problem, a.result, rep)
    clipped_note = (f" Outlier postures whose board lies beyond the plotted frame: {', '.join(map(str, clipped))}."
                    if clipped else "")
    return (
        f"<h2>4. Repeatability of the board corners in {fixed_frame}</h2><section>"
        f'<p class="how">The board does not move, so with the right camera pose every posture should put each board '
        f"corner at the same place in {fixed_frame}. The plots show each corner's deviation from its mean position "
        f"over the used postures (grey; outlier postures red) and each posture's board centre (blue), seen from "
        f"above and from the side. A tight round cloud is noise; a posture's centre far from the rest is a posture "
        f"to check; an elongated cloud points at a direction the calibration could not pin down.</p>"
        + img(scatter_png, "repeatability of the board corners, top and side views")
        + f'<p class="note">Board centre over the used postures: RMS '
          f"{float(np.sqrt(np.mean(radial ** 2))) if radial.size else 0.0:.3f} mm, largest "
          f"{float(radial.max()) if radial.size else 0.0:.3f} mm.{escape(clipped_note)}</p>"
        + '<p class="how">Per-corner RMS deviation, laid out as on the board (point 0 = the first corner, the '
          "target origin): a uniform level is camera noise; a "
          "gradient across the board points at a rotation error of the camera pose or a scale error of the stereo "
          "model; single hot corners are detection problems.</p>"
        + img(plot_point_rms(a.problem, rep), "per-corner RMS deviation")
        + f'<p class="note">Per-corner RMS: median {np.median(rms):.3f} mm, largest {rms.max():.3f} mm '
          f"(point {int(np.argmax(rms))}).</p></section>")


def preview_section(png: bytes | None, missing: str | None = None) -> str:
    if png is None:
        return f'<h2>Capture plan: the cell</h2><section><p class="note">Preview not shown: {escape(missing)}</p></section>'
    return ("<h2>Capture plan: the cell</h2><section>"
            '<p class="how">The preview written before the robot moved: the keep-out volumes and the board\'s stand, the '
            "board, the path the flange ran and the postures, numbered as their files (postures/NNN.yaml) and as "
            "this report names them, from above and from the side (base frame, mm).</p>"
            + img(png, "capture plan preview: the cell from above and from the side") + "</section>")


def findings_section(findings: list, postures: int) -> str:
    items = "".join(f"<li>{escape(f)}</li>" for f in findings)
    body = f"<ul>{items}</ul>" if findings else '<p class="note">Nothing odd found in the poses.</p>'
    pairs = pairs_used(len(bounded_pairs(postures)), postures)
    return ("<h2>Data checks before solving</h2><section>" + body
            + f'<p class="how">The pairwise checks ran on {escape(pairs)}.</p></section>')
