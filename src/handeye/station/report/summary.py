"""The head of the calibration report: the origin banner (mock and simulated sessions), the verdict,
the RAPID literals (copyable on a PASS; greyed out, struck through and not selectable under
"FAIL - do not write this into the robot" on a FAIL), the camera pose with its uncertainty and the
session facts (postures, outliers, d_org over the points the header names)."""

from __future__ import annotations

from scipy.spatial.transform import Rotation

from ...calibration import EYE_IN_HAND
from ...calibration import D_ORG_ALL_NAME
from ...rapid import pose_literal, rounded_pose
from .assessment import Assessment
from ..origin import origin_banner
from .quality import Verdict
from .html import escape, kv

__all__ = ["summary_section", "excluded_html"]


#: What the report says about where the data come from (``station.origin``).
_ORIGIN_FACTS = {
    "real": "the real station (capture record in session.yaml)",
    "mock": "a mock station, embedded or a rehearsal (simulated robot and camera)",
    "simulated": "a simulation (truth.yaml beside the session)",
    "unknown": "not recorded (imported or hand-written session)",
}


def _origin_banner(origin: str) -> str:
    banner = origin_banner(origin)
    if banner is None:
        return ""
    word, text = banner
    return f'<div class="origin" data-origin="{escape(origin)}"><b>{escape(word)}</b> &ndash; {escape(text)}</div>'


def _literals(x, tooldata_literal, label: str, verdict) -> list[str]:
    """The RAPID literals: copyable unless the verdict failed; then greyed out, struck through, not
    selectable, under a banner that says not to write them."""
    literals = [(f"{label}, RAPID literal:", pose_literal(x))]
    if tooldata_literal:
        literals.append(("tooldata:", tooldata_literal))
    if verdict is None or verdict.passed:
        return [item for caption, text in literals for item in
                (f'<div style="margin-top:10px">{escape(caption)}</div>', f'<code class="literal">{escape(text)}</code>')]
    body = "".join(f'<div>{escape(caption)} (failed result, for reference only)</div><del class="void">{escape(text)}</del>'
                   for caption, text in literals)
    return ['<div class="donotwrite"><div class="donotwrite-banner">FAIL &ndash; do not write this into the robot'
            "</div>" + body + '<div class="note">Act on the failed checks below, then calibrate again; '
            "<code>handeye writeback</code> refuses a failed result.</div></div>"]


def _verdict_banner(verdict: Verdict | None, scope: str | None = None) -> str:
    if verdict is None:
        return '<div class="verdict none">NO VERDICT</div><div class="verdict-line">no thresholds were applied</div>'
    cls, word = ("pass", "PASS") if verdict.passed else ("fail", "FAIL")
    failed = verdict.failed
    line = ("every quality check passed" if verdict.passed else
            (f"{verdict.cause}. " if verdict.cause else "")
            + f"{len(failed)} of {len(verdict.checks)} checks failed: " + ", ".join(c.name for c in failed)
            + " (see the advice below)")
    scope_html = f'<div class="verdict-line" data-note="verdict-scope">{escape(scope)}</div>' if scope else ""
    return f'<div class="verdict {cls}">{word}</div><div class="verdict-line">{escape(line)}</div>' + scope_html


def _pose_facts(result) -> list:
    """The camera pose and its uncertainty, as (label, HTML) pairs."""
    position, quaternion = rounded_pose(result.x)
    euler = Rotation.from_matrix(result.x[:3, :3]).as_euler("ZYX", degrees=True)
    pose = [
        ("position", f"x {position[0]:.3f} &nbsp; y {position[1]:.3f} &nbsp; z {position[2]:.3f} mm"),
        ("quaternion q1..q4", " &nbsp; ".join(f"{v:.6f}" for v in quaternion)),
        ("Euler ZYX", f"z {euler[0]:.4f} &nbsp; y {euler[1]:.4f} &nbsp; x {euler[2]:.4f} deg"),
    ]
    u = result.uncertainty
    if u is not None:
        pose += [("uncertainty, position", "&plusmn; " + " / ".join(f"{v:.3f}" for v in u["translation_mm"])
                  + " mm (x / y / z, one sigma)"),
                 ("uncertainty, rotation", "&plusmn; " + " / ".join(f"{v:.4f}" for v in u["rotation_deg"])
                  + " deg (about x / y / z, one sigma)")]
    else:
        pose.append(("uncertainty", f"not estimated by method {escape(result.method)} (the default does)"))
    cv = result.cross_validation
    if cv:  # the default estimator's held-out accuracy (src/handeye/calibration/crossval.py)
        pose.append(("cross-validated accuracy", f"{cv['rms_mm']:.3f} mm RMS of held-out board points ({cv['folds']}-fold)"
                     + (f"; the noise model predicts {cv['predicted_rms_mm']:.3f} mm" if "predicted_rms_mm" in cv else "")))
        if cv.get("systematic"):
            pose.append(("systematic error", escape(cv.get("advice", ""))))
    return pose


def _session_facts(a: Assessment) -> list:
    """Session, origin, method, postures, outliers, d_org (and d_org incl. outliers), times, truth errors."""
    result, n, scatter = a.result, a.problem.n, a.d_org
    outliers = [int(i) for i in result.outliers]
    residual_text = ", ".join(f"{i} ({result.residuals_mm.get(i, float('nan')):.2f} mm)" for i in outliers)
    facts = [
        ("session", f"<code>{escape(a.session_path)}</code>"),
        ("data from", escape(_ORIGIN_FACTS.get(a.origin, a.origin))),
        ("set-up", escape(result.setup.replace("_", "-"))),
        ("method", escape(result.method)),
        ("postures", f"{n} captured, {n - len(outliers)} used, {len(outliers)} outlier{'s' if len(outliers) != 1 else ''}"),
        ("outliers (residual)", escape(residual_text) if outliers else "none"),
        ("d_org", f'<span class="num" data-d-org="header">{scatter.mm:.3f} mm</span><br>'
                  f'<span class="note">{escape(scatter.basis())} (eq. 22)</span>'),
    ]
    if result.excluded:
        facts.append(("left out before solving", excluded_html(result.excluded)))
    if scatter.incl_outliers_mm is not None:
        facts.append((D_ORG_ALL_NAME, f"{scatter.incl_outliers_mm:.3f} mm (the same over all {n} postures)"))
    facts.append(("solve time", f"{1000 * result.runtime_s:.1f} ms"))
    if result.truth_errors is not None:
        errors = result.truth_errors
        text = f"{errors['translation_error_mm']:.3f} mm, {errors['rotation_error_deg']:.4f} deg (synthetic session)"
        facts.append(("error vs truth", text))
    return facts


def summary_section(a: Assessment) -> str:
    """The head of the report: origin banner, verdict, RAPID literals, pose and session facts."""
    verdict, eye_in_hand = a.verdict, a.result.setup == EYE_IN_HAND
    literal_label = "tframe (camera in tool0)" if eye_in_hand else "camera pose in base"
    parts = [_origin_banner(a.origin), _verdict_banner(verdict, a.verdict_scope)] + _literals(a.result.x, a.tooldata_literal,
                                                                             literal_label, verdict)
    if eye_in_hand and not a.tooldata_literal and (verdict is None or verdict.passed):
        parts.append('<div class="note">tooldata: the load (mass, centre of gravity) comes from the station '
                     'configuration; <code>handeye writeback</code> writes the full tooldata with this tframe.</div>')
    return ("<section>" + "".join(parts) + '<div class="grid">' + kv(_pose_facts(a.result))
            + kv(_session_facts(a)) + "</div></section>")


def excluded_html(excluded: dict) -> str:
    """Gross postures left out before solving, each with its reason (``CalibrationResult.excluded``)."""
    return "<br>".join(f"posture {int(i)}: {escape(reason)}" for i, reason in excluded.items())
