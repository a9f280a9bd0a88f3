"""``handeye calibrate``: solve a session and print or write the camera pose."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "solve a session for the camera pose (cam2tool0, or cam2base eye-to-hand)"

#: How the help introduces each kind of method (``calibration.methods.KINDS``), and the citation its
#: rows share (a row citing another work names it).
_KIND_HEADINGS = {
    "estimator": ("Estimators:", "handeye, after Deniz & Cakir (2018)"),
    "paper": ("The paper's variants (Deniz & Cakir 2018):", "Deniz & Cakir (2018)"),
    "classic": ("AX = XB solvers (src/handeye/calibration/classic/README.md says what each published one minimises):", None),
}


def methods_help(width: int = 100) -> str:
    """The ``--method`` section of the help: every row of the methods table (a plug-in's too), by kind."""
    import textwrap

    from ...calibration import DEFAULT_METHOD, METHODS, method_names

    lines = [f"Methods (--method); without it the recommended default ({DEFAULT_METHOD}) runs:"]
    for kind, (heading, shared) in _KIND_HEADINGS.items():
        names = method_names(kind)
        if not names:
            continue
        column = max(len(name) for name in names) + 4
        lines.append(heading)
        for name in names:
            row = METHODS[name]
            text = row.reference.rstrip(".") if shared is None else row.summary
            if shared is not None and row.citation != shared:
                text += f" ({row.citation})"
            text = ("(default) " if name == DEFAULT_METHOD else "") + text
            lines += textwrap.wrap(text, width, initial_indent=f"  {name:<{column - 2}}",
                                   subsequent_indent=" " * column, break_on_hyphens=False)
    lines.append("Other installed packages add methods through the entry-point group handeye.methods; "
                 "they are listed above, under their kind.")
    return "\n".join(lines) + "\n\n"


EPILOG = """\
Before solving, the robot and board poses are checked against the X-free invariants of AX = XB: a
session no rigid camera mount fits is refused with the likely cause; a few gross postures that alone
break the check (robot and camera poses swapped, one posture in another rotation convention, a posture
of another session) are named and left out, listed with the outliers (JSON "excluded_before_solve").
Also before solving, the session's lengths are checked: a session that looks like metres, a posture in
another unit, a flange beyond the robot's reach or corners whose spacing is not target.square_mm
(within 5 %) is refused with the reason. A session really written in metres is converted only
when asked: --units m.

The text report gives the pose as a RAPID tframe literal, the quality figures and each posture's
residual. --json FILE writes the machine-readable result ('-' for standard output); its key
"station" says where the data come from: "real", "mock" (the embedded mock station), "simulated"
(truth.yaml beside the session) or "unknown" (imported or older sessions). Mock and simulated
sessions are flagged in the text and the HTML report: they are not a calibration of a real robot.

Every solve is saved in SESSION/result.yaml (atomically): the camera pose, its uncertainty, the
method, the code version, the time and a hash of the posture files it was solved from. handeye
writeback and handeye verify use that result and refuse it once postures are added or changed
(run calibrate again); a folder that cannot be written is a warning, the result above stands.

--report [FILE] also writes the calibration report: one self-contained HTML file (plots embedded,
no network needed) with a PASS/FAIL verdict against the quality thresholds, the tframe literal,
uncertainty and cross-validated accuracy, outliers, per-posture residuals, rotation-axis coverage, a
comparison with other methods ranked by their held-out (cross-validated) error, also printed and in
the JSON ("method_comparison"), and the repeatability of the board corners in base.
Without FILE it is SESSION/report.html (then put --report after SESSION). The verdict uses the
default thresholds, or those of --thresholds FILE.yaml (lines 'key: number', or a station config's
'quality:' section; a commented example with the defaults: src/handeye/station/quality_thresholds.yaml); keys:
  max_d_org_mm (1.0)  max_posture_residual_mm (2.0)  max_sigma_translation_mm (0.2)
  max_sigma_rotation_deg (0.02)  min_inlier_postures (12)  max_outlier_fraction (0.2)
  min_rotation_axis_spread_deg (10)  min_median_rotation_deg (15)
  min_camera_offset_mm (20)  max_camera_offset_mm (500)   (eye-in-hand: camera frame's distance
                                                          from the flange)
d_org is eq. 22 over the postures the result kept, on every board corner (the three compact points
when the session holds board poses only), the same for every method the report compares.
With --report or --thresholds the JSON gains a "verdict" key. A failed verdict still exits 0 (the
calibration itself succeeded); read "verdict.passed" in the JSON to act on it.

Examples:
  handeye calibrate my_session --method mcb --json result.json
  handeye calibrate my_session --report                      # writes my_session/report.html
  handeye calibrate my_session --report out.html --thresholds station_quality.yaml
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("calibrate", help=HELP, description=HELP, epilog=lambda: methods_help() + EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("session", metavar="SESSION", help="session folder (handeye-session/1)")
    p.add_argument("--method", metavar="NAME", help="solver (see below); default: the recommended one")
    p.add_argument("--json", metavar="FILE", help="write the result as JSON ('-' = stdout)")
    p.add_argument("--quiet", action="store_true", help="no text report (with --json FILE)")
    p.add_argument("--report", metavar="FILE", nargs="?", const="",
                   help="write the HTML calibration report (default FILE: SESSION/report.html)")
    p.add_argument("--thresholds", metavar="FILE.yaml", help="quality thresholds for the verdict (default: built in)")
    p.add_argument("--units", choices=("mm", "m"), default="mm",
                   help="length unit the session was written in (default mm, the format's; m converts on reading)")
    p.add_argument("--kinematics", action="store_true",
                   help="also identify the arm's joint zeros and link lengths with the camera (sessions with joints)")
    p.add_argument("--standoff", metavar="MM", type=float, default=750.0,
                   help="with --kinematics: the inspection stand-off along the camera axis (default 750 mm)")
    return p


def run(args: argparse.Namespace) -> int:
    import sys

    from ..report.assessment import assess, comparison_methods
    from ..calibrate import calibrate_session_folder, report_path_for
    from ..output import check_output_file, write_json
    from ..report.as_json import calibration_json
    from ..report.text import calibration_summary

    if args.json:  # an unwritable --json fails before any solving
        check_output_file(args.json)
    if not 0 < args.standoff <= 5000:  # so does a stand-off that is no distance
        from ...base import UsageError

        raise UsageError(f"--standoff must be more than 0 and at most 5000 mm; got {args.standoff:g}")
    from ...calibration import method_row

    method_row(args.method)  # an unknown --method, too (the table, a plug-in's methods included)
    wants_report = args.report is not None
    thresholds = None
    if args.thresholds:  # a bad thresholds file fails before any solving
        from ..report.quality import load_thresholds

        thresholds = load_thresholds(args.thresholds)
    report_path = report_path_for(args.session, args.report) if wants_report else None
    if report_path is not None and not report_path.parent.is_dir():
        from ...base import HandEyeError

        raise HandEyeError(f"cannot write the report {report_path}: folder {report_path.parent} does not exist")
    from ..progress import delayed_progress

    with delayed_progress("calibrate") as update:  # shown only when solving takes over a second
        outcome = calibrate_session_folder(args.session, args.method, args.units, progress=update)
    _warn_joint_mismatch(outcome.session)
    saved = _save_result(outcome, args.units)
    kinematics = None
    if args.kinematics:
        from ..kinematics_step import identify_outcome

        kinematics = identify_outcome(outcome, args.standoff)
        _save_standoff(outcome, kinematics[1])
    assessment = assess(outcome, thresholds, judge=wants_report or bool(args.thresholds),
                        methods=comparison_methods() if wants_report else ())
    written = None
    if report_path is not None:  # wants_report
        from ..report.document import write_report

        title = f"Hand-eye calibration report: {outcome.session_path.resolve().name}"
        written = write_report(report_path, assessment, title=title, extra_sections=_kinematics_sections(kinematics))
    if args.json:
        data = calibration_json(assessment)
        if kinematics is not None:
            from ..kinematics_step import kinematics_json

            data["kinematics"] = kinematics_json(*kinematics)
        write_json(args.json, data)
    stream = sys.stderr if args.json == "-" else sys.stdout
    if not args.quiet and args.json != "-":
        print(calibration_summary(assessment))
        if kinematics is not None:
            from ..kinematics_step import kinematics_lines

            print("\n" + "\n".join(kinematics_lines(*kinematics)))
    if not args.quiet and saved is not None:
        print(f"\nResult saved to {saved} (handeye writeback and verify use it)", file=stream)
    if not args.quiet and assessment.verdict is not None:
        if written is not None:
            print(f"\nReport written to {written}", file=stream)
        print(assessment.verdict.line(), file=stream)
    from ..plant.hooks import after_calibrate  # the plant's broker, when the session's station has plant:

    after_calibrate(args, outcome, assessment)
    return 0


def _save_result(outcome, units: str):
    """``SESSION/result.yaml`` (``station.result_file``); a folder that cannot be written is one warning
    line on stderr: the calibration stands, writeback and verify will solve it again."""
    import sys

    from ...base import OutputError
    from ..result_file import save_result

    try:
        return save_result(outcome, units)
    except OutputError as exc:
        print(f"handeye calibrate: warning: the result was not saved ({exc}); handeye writeback and verify will "
              "solve the session again", file=sys.stderr)
        return None


def _save_standoff(outcome, standoff) -> None:
    """``SESSION/standoff.json`` (``station.standoff_file``: what ``verify`` compares against); a folder
    that cannot be written is one warning line on stderr."""
    import sys

    from ...base import OutputError
    from ..standoff_file import save_prediction

    if standoff is None:
        return
    try:
        save_prediction(outcome.session_path, outcome.problem.posture_ids, standoff)
    except (OSError, OutputError) as exc:
        print(f"handeye calibrate: warning: the stand-off prediction was not saved ({exc}); verify will not "
              "compare against it", file=sys.stderr)


def _kinematics_sections(kinematics: tuple | None) -> tuple:
    """The report's kinematics section (none without ``--kinematics``)."""
    if kinematics is None:
        return ()
    from ..kinematics_report import kinematics_section
    from ..kinematics_step import kinematics_lines

    ident, standoff = kinematics  # kinematics_step.identify_outcome
    return (kinematics_section(ident, standoff, kinematics_lines(ident, standoff)),)


def _warn_joint_mismatch(session) -> None:
    """One warning line on stderr when postures' joint angles do not reproduce their flange poses."""
    import sys

    from ...calibration import session_joint_mismatch

    found = session_joint_mismatch(session)
    if found is not None:
        print(f"handeye calibrate: warning: {found.line()}: the default estimator models the robot's noise on the "
              "flange poses instead of the joints (details.kinematics), and handeye verify refuses the session; "
              "check those postures' files (joints_deg and tool0_in_base are one reading of the controller)",
              file=sys.stderr)
