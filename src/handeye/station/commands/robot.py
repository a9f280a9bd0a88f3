"""``handeye robot``: talk to the robot controller (joints and flange pose, program status)."""

from __future__ import annotations

import argparse
from typing import cast

from . import argtypes
from .argtypes import Subcommands

HELP = "read the robot through the controller link (joints, flange pose, status)"

EXAMPLE = """\
Example (against `handeye mock controller`):
  handeye robot joints --protocol socket --host 127.0.0.1 --port 1025 --json
prints {"joints_deg": [...], "tool0_in_base": {"position_mm": [...], "quaternion_wxyz": [...]}}.
"""


def _epilog() -> str:
    """Link options of every registered back end (``station.backend_help``, from the registry), then the example
    (written when the help is asked for: it loads every plug-in, under the time bound)."""
    from ..backend_help import protocol_lines

    return "Link options (the same for every sub-command):\n" + "\n".join(protocol_lines()) + "\n\n" + EXAMPLE


def _link_options(p, backends) -> None:
    """``--protocol``, ``--host``, ``--port`` and one flag per link setting of the back ends loaded so far
    (``link_settings()``: handeye's own, and the plug-in the command line names, :func:`add_parser`)."""
    from ...drivers import DEFAULT_PROTOCOL, link_settings
    from .argtypes import registry_choice

    ports = ", ".join(f"{name} {backends[name].default_port}" for name in backends.loaded_names()
                      if backends[name].default_port)
    protocols = backends.choices()  # checking the value loads that plug-in only
    p.add_argument("--protocol", choices=protocols, type=registry_choice(protocols), default=DEFAULT_PROTOCOL,
                   metavar="PROTOCOL", help=f"one of the protocols below (default {DEFAULT_PROTOCOL})")
    p.add_argument("--host", default="127.0.0.1", help="controller or gateway address (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=None, help=f"TCP port (default: {ports})")
    for key, (setting, names) in link_settings().items():
        p.add_argument(setting.option, dest=f"link_{key}", type=argtypes.setting_value(setting), default=None,
                       metavar=setting.metavar or setting.key.upper(),
                       help=f"{', '.join(names)}: {setting.help}")
    p.add_argument("--timeout", type=argtypes.positive, default=2.0, metavar="S", help="seconds per call (default 2)")
    p.add_argument("--idle-timeout", type=argtypes.positive, default=5.0, metavar="S",
                   help="the controller's idle timeout (controller.idle_timeout_s, default 5): connecting may wait "
                        "that long plus --timeout while the controller frees itself from a silent client")


def add_parser(sub: Subcommands, words: list[str] | None = None) -> argparse.ArgumentParser:
    """``words``: the command line; only the plug-in its ``--protocol`` names is loaded (for its own link
    flags), every one for ``--help`` or when None (the whole parser)."""
    from ...drivers import CONTROLLERS
    from .argtypes import load_for_flags, option_word

    load_for_flags(CONTROLLERS, None if words is None else option_word(words, "--protocol"))
    p = sub.add_parser("robot", help=HELP, description=HELP, epilog=_epilog,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    what = cast(Subcommands, p.add_subparsers(dest="robot_command", metavar="COMMAND"))  # a OneLineParser's parsers: a callable epilog is theirs
    j = what.add_parser("joints", help="joint angles and tool0 pose", description="read CJointT and CRobT(tool0, wobj0)",
                        epilog=_epilog, formatter_class=argparse.RawDescriptionHelpFormatter)
    _link_options(j, CONTROLLERS)
    j.add_argument("--json", action="store_true", help="print JSON (joints_deg, tool0_in_base)")
    s = what.add_parser("status", help="program state and current posture", epilog=_epilog,
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    _link_options(s, CONTROLLERS)
    s.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(_robot_parser=p)
    return p


def _options(args) -> dict:
    """``open_controller`` options: where the controller is, as the back end's registry entry builds them."""
    from ...drivers import CONTROLLERS, ControllerLink

    settings = {name[len("link_"):]: value for name, value in vars(args).items() if name.startswith("link_")}
    link = ControllerLink(host=args.host, port=args.port, **settings)
    options = {"timeout": args.timeout, "retries": 1, "idle_timeout": args.idle_timeout}
    return {**CONTROLLERS[args.protocol].link_options(link), **options}


def run(args: argparse.Namespace) -> int:
    if getattr(args, "robot_command", None) not in ("joints", "status"):
        args._robot_parser.print_help()
        return 2
    import json

    from ...drivers import open_controller
    from ...drivers import read_robot_state

    with open_controller(args.protocol, **_options(args)) as controller:
        if args.robot_command == "joints":
            state = read_robot_state(controller)
            if args.json:
                print(json.dumps(state))
            else:
                pose = state["tool0_in_base"]
                print("joints (deg):     " + "  ".join(f"{v:9.4f}" for v in state["joints_deg"]))
                print("tool0 in base mm: " + "  ".join(f"{v:9.3f}" for v in pose["position_mm"]))
                print("quaternion wxyz:  " + "  ".join(f"{v:9.6f}" for v in pose["quaternion_wxyz"]))
        else:
            info, status = controller.info(), controller.status()
            data = {"state": status.state, "posture": status.posture, "postures": info.postures,
                    "program": info.program, "protocol_version": info.protocol_version}
            controller_state = getattr(controller, "controller_state", None)
            if controller_state is not None:  # RWS: the controller's own state too
                data["controller"] = controller_state()
            if args.json:
                print(json.dumps(data))
            else:
                print(f"{info.program} (protocol {info.protocol_version}, {info.postures} approved postures): "
                      f"{status.state} at posture {status.posture}")
                if "controller" in data:
                    c = data["controller"]
                    print(f"controller: {c['ctrlstate']}, mode {c['opmode']}, RAPID {c['execution']}, "
                          f"RobotWare {c['robotware']}")
    return 0
