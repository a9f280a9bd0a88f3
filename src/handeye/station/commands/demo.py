"""``handeye demo``: the whole station job on the embedded mock robot and camera."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "run the whole station job on the embedded mock robot and camera, and check it against the truth"

EPILOG = """\
What happens (about 15 s on 2 cores):
  1. a simulated IRB 1400 (with small kinematic errors, like a real arm) starts behind a real
     controller server on 127.0.0.1, with a simulated Bumblebee XB3 on its flange at a hidden mount;
  2. the board is measured from the start posture, 30 postures are planned and scored, and the
     RAPID program is generated and loaded;
  3. each posture is visited, grabbed, triangulated and written to the session;
  4. the session is calibrated (the default estimator), judged against the quality thresholds, and the
     HTML report is written;
  5. the camera frame is written into the robot's PERS tooldata, read back and compared;
  6. the recovered camera pose is compared with the hidden truth.
The session and report stay in --session (default ./handeye_demo, replaced on the next run).

Examples:
  handeye demo
  handeye demo --protocol modbus --json demo.json
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    from ...drivers import DEFAULT_PROTOCOL
    from ...mocks import mock_protocol_choices
    from . import argtypes
    from .argtypes import left_out_lines, registry_choice

    protocols = mock_protocol_choices()  # a name is checked when given: no plug-in is imported to build this
    p = sub.add_parser("demo", help=HELP, description=HELP,
                       epilog=lambda: EPILOG + f"\nProtocols a mock serves (--protocol): {protocols.listed()}\n"
                       + left_out_lines(protocols, "--protocol"),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON ('-' = stdout)")
    p.add_argument("--session", default="handeye_demo", metavar="DIR", help="demo folder (default ./handeye_demo)")
    p.add_argument("--protocol", choices=protocols, type=registry_choice(protocols), default=DEFAULT_PROTOCOL,
                   metavar="PROTOCOL", help=f"controller link of the mock robot: one a mock serves, listed below "
                                            f"(default {DEFAULT_PROTOCOL}; handeye plugins says what each installed one can do)")
    p.add_argument("--postures", type=int, default=30, help="postures to plan (default 30)")
    p.add_argument("--seed", type=int, default=7, help="mock station seed: arm errors and sensor noise (default 7)")
    p.add_argument("--board", metavar="TARGET", type=argtypes.target_spec, default=None,
                   help="the board: checkerboard (default), charuco, circles, or one with keys "
                        "(charuco:squares=14x9,square_mm=30,marker_mm=22,dictionary=DICT_5X5_100)")
    p.add_argument("--occlude", metavar="SHARE", type=float, default=None,
                   help="cover a band over 20-40 %% of the board at this share of the postures (0..1; mock.occlude)")
    p.add_argument("--no-report", action="store_true", help="skip the HTML report")
    p.add_argument("--kinematics", action="store_true",
                   help="also identify the arm's joint zeros and link lengths; prints them next to the hidden ones")
    return p


def run(args: argparse.Namespace) -> int:
    from ...base import UsageError
    from ..demo import DemoOptions, run_demo
    from ..output import check_output_file, write_json
    from ..progress import progress_bar

    if not 3 <= args.postures <= 255:
        raise UsageError(f"--postures must be between 3 and 255; got {args.postures}")
    if args.occlude is not None and not 0 <= args.occlude <= 1:
        raise UsageError(f"--occlude must be a share of the postures between 0 and 1; got {args.occlude}")
    occlude = None
    if args.occlude is not None:
        from ...mocks import Occlusion

        occlude = Occlusion(args.occlude)
    if args.json:  # an unwritable --json fails before the run
        check_output_file(args.json)
    from ..runtime import MOCK_BANNER

    quiet = args.json == "-"
    say = (lambda m: None) if quiet else (lambda m: print(m, flush=True))
    say(MOCK_BANNER)
    with progress_bar("demo capture") as update:
        def on_posture(report):
            if not quiet:
                print(("  ok    " if report.ok else "  SKIP  ") + report.message, flush=True)
            update(report.done, report.total, f"posture {report.index}")

        result = run_demo(DemoOptions(args.session, args.postures, args.protocol, args.seed, not args.no_report,
                                      args.kinematics, getattr(args, "board", None), occlude),
                          progress=say, on_posture=on_posture)
    if args.json:
        write_json(args.json, result)
    if not quiet:
        print(_summary(result))
        if "kinematics" in result:
            from ..kinematics_step import demo_lines

            print("\n".join(demo_lines(result["kinematics"])))
    ok = (result["readback_ok"] and result["errors"]["rotation_error_deg"] <= 0.05
          and result["errors"]["translation_error_mm"] <= 0.5)
    return 0 if ok else 1


def _summary(r: dict) -> str:
    got, true = r["camera_pose"], r["truth_camera_pose"]
    e = r["errors"]
    u = r.get("uncertainty") or {}
    lines = [
        "",
        "Camera in tool0    " + "".join(f"{h:>11s}" for h in ("x mm", "y mm", "z mm", "q1", "q2", "q3", "q4")),
        "  recovered   " + "".join(f"{v:11.3f}" for v in got["position_mm"]) + "".join(f"{v:11.6f}" for v in got["quaternion_wxyz"]),
        "  hidden truth" + "".join(f"{v:11.3f}" for v in true["position_mm"]) + "".join(f"{v:11.6f}" for v in true["quaternion_wxyz"]),
        f"  error: {e['translation_error_mm']:.3f} mm, {e['rotation_error_deg']:.4f} deg   (target <= 0.5 mm, <= 0.05 deg)",
    ]
    if u:
        lines.append("  one-sigma uncertainty: position " + ", ".join(f"{v:.3f}" for v in u["translation_mm"])
                     + " mm; rotation " + ", ".join(f"{v:.4f}" for v in u["rotation_deg"]) + " deg")
    lines += [
        f"postures captured: {r['postures_captured']}; outliers: {r['outliers'] or 'none'}; verdict: "
        + ("PASS" if r["verdict"]["passed"] else "FAIL (" + ", ".join(c["name"] for c in r["verdict"]["checks"] if not c["passed"]) + ")"),
        f"written to the MOCK robot: {r['tooldata']}",
        f"MOCK read back: {'identical to the last digit' if r['readback_ok'] else 'DIFFERENT'}",
        f"session: {r['session']}" + (f"; report: {r['report']}" if r.get("report") else ""),
        f"done in {r['wall_s']:.0f} s",
    ]
    return "\n".join(lines)
