"""The calibration report: one self-contained HTML file a station engineer reads offline.

Everything is inside the file: CSS inline, plots as base64 PNG ``data:`` URIs, no scripts, no links
to other files or the network, so it opens on a station PC without internet and can be mailed as is.

Contents: a banner when the data come from the embedded mock station or a simulation
(``station.origin``); the verdict (PASS/FAIL) with the camera pose as a RAPID literal (copyable on a
PASS; greyed out, struck through and not selectable under "FAIL - do not write this into the robot"
on a FAIL), its uncertainty and the outliers; the quality checks with advice; five figures and
tables (per-posture residuals, rotation-axis coverage, method comparison, repeatability of the board
corners in the fixed frame, quality metrics and truth errors); the data checks made before solving;
the capture plan's preview of the cell when the session holds one (``SESSION/preview.png``).
d_org is everywhere the one of ``calibration.quality_words.result_d_org``, and the header says which
postures and points it is computed over.

A presenter of ``station.report.assessment.Assessment``: every figure and table shows what the assessment
holds (the verdict, the quality words, the method comparison, the repeatability); nothing here solves.

Modules: ``report_figures`` (the plots), ``report_html`` (CSS, escaping, embedded images),
``report_summary`` (the head: banners, verdict, literals, facts), ``report_sections`` (the numbered
sections); this one assembles the page (:func:`write_report`).
"""

from __future__ import annotations

import datetime as _dt
from pathlib import Path

from ...base import HandEyeError
from ...calibration import EYE_IN_HAND
from ...base import write_text_atomic
from .assessment import Assessment
from .html import CSS, FOOTER, escape
from .sections import (
    checks_section,
    comparison_section,
    coverage_section,
    findings_section,
    metrics_table,
    preview_section,
    repeatability_section,
    residuals_section,
)
from .summary import summary_section

__all__ = ["write_report"]


def write_report(path_html: str | Path, assessment: Assessment, title: str = "Hand-eye calibration report",
                 extra_sections: tuple = ()) -> Path:
    """Write the calibration report of an assessment as one self-contained HTML file.

    Parameters
    ----------
    path_html : str or Path
        The file to write (written atomically; its folder must exist).
    assessment : Assessment
        From ``station.report.assessment.assess``: the result, its verdict (the PASS/FAIL banner and the
        checks, when judged), the method comparison (when compared), the data checks, the origin (mock
        and simulated sessions get a banner saying they are not a calibration of a real robot).
    title : str
    extra_sections : tuple of str
        HTML sections added before the footer (the arm's kinematics, ``station.kinematics_report``).

    Returns
    -------
    Path

    Raises
    ------
    HandEyeError
        When the folder does not exist or the file cannot be written.
    """
    path = Path(path_html)
    if not path.parent.is_dir():
        raise HandEyeError(f"cannot write the report {path}: folder {path.parent} does not exist")
    a = assessment
    fixed_frame = "base" if a.problem.setup == EYE_IN_HAND else "tool0"
    now = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
    sections = [f"<h1>{escape(title)}</h1>",
                f'<div class="sub">{escape(a.session_path)} &middot; {escape(a.result.setup.replace("_", "-"))} &middot; '
                f"method {escape(a.result.method)} &middot; generated {escape(now)}</div>", summary_section(a)]
    if a.verdict is not None:
        sections.append(checks_section(a.verdict))
    from .corners import corners_section  # partial views (ChArUco): "" for a checkerboard session

    sections += [corners_section(a.problem)] if corners_section(a.problem) else []
    sections += [residuals_section(a, fixed_frame), coverage_section(a), comparison_section(a),
                 repeatability_section(a, fixed_frame),
                 "<h2>5. Quality metrics</h2><section>" + metrics_table(a) + "</section>"]
    if a.findings is not None:
        sections.append(findings_section(a.findings, a.problem.n))
    if a.plan_preview is not None or a.plan_preview_missing is not None:
        sections.append(preview_section(a.plan_preview, a.plan_preview_missing))
    sections += list(extra_sections)
    sections.append(FOOTER)
    document = ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{escape(title)}</title>"
                f"<style>{CSS}</style></head><body><main>" + "\n".join(sections) + "</main></body></html>\n")
    try:
        write_text_atomic(path, document)
    except OSError as exc:
        raise HandEyeError(f"cannot write the report {path}: {exc.strerror or exc}") from None
    return path
