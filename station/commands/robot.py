"""``handeye robot``: talk to the robot controller (joints and flange pose, program status)."""

from __future__ import annotations

import argparse

from . import argtypes

HELP = "read the robot through the controller link (joints, flange pose, status)"

EPILOG = """\
Link options (the same for every sub-command):
  --protocol socket   TCP to the HeSocket RAPID module:   --host H --port P (default 1025)
  --protocol serial   serial channel (HeSerial module):   --url DEVICE_OR_URL [--baudrate B]
  --protocol modbus   Modbus TCP gateway (HeIo module):   --host H --port P (default 502) [--register-map MAP]

Example (against `handeye mock controller`):
  handeye robot joints --protocol socket --host 127.0.0.1 --port 1025 --json
prints {"joints_deg": [...], "tool0_in_base": {"position_mm": [...], "quaternion_wxyz": [...]}}.
"""

DEFAULT_PORTS = {"socket": 1025, "modbus": 502}


def _link_options(p) -> None:
    p.add_argument("--protocol", choices=("socket", "serial", "modbus"), default="socket", help="default socket")
    p.add_argument("--host", default="127.0.0.1", help="controller or gateway address (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=None, help="TCP port (default: socket 1025, modbus 502)")
    p.add_argument("--url", help="serial: device (/dev/ttyUSB0, COM3) or pyserial URL (socket://127.0.0.1:1026)")
    p.add_argument("--baudrate", type=int, default=9600, help="serial: baud rate (default 9600)")
    p.add_argument("--register-map", metavar="MAP.yaml", help="modbus: register map (default: the built-in one)")
    p.add_argument("--timeout", type=argtypes.positive, default=2.0, metavar="S", help="seconds per call (default 2)")
    p.add_argument("--idle-timeout", type=argtypes.positive, default=5.0, metavar="S",
                   help="the controller's idle timeout (controller.idle_timeout_s, default 5): connecting may wait "
                        "that long plus --timeout while the controller frees itself from a silent client")


def add_parser(sub):
    p = sub.add_parser("robot", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    what = p.add_subparsers(dest="robot_command", metavar="COMMAND")
    j = what.add_parser("joints", help="joint angles and tool0 pose", description="read CJointT and CRobT(tool0, wobj0)",
                        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    _link_options(j)
    j.add_argument("--json", action="store_true", help="print JSON (joints_deg, tool0_in_base)")
    s = what.add_parser("status", help="program state and current posture", epilog=EPILOG,
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    _link_options(s)
    s.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(_robot_parser=p)
    return p


def _options(args) -> dict:
    from ...drivers.controller.errors import InvalidRequest

    options = {"timeout": args.timeout, "retries": 1, "idle_timeout": args.idle_timeout}
    if args.protocol == "serial":
        if not args.url:
            raise InvalidRequest("--protocol serial needs --url (a device like /dev/ttyUSB0 or socket://HOST:PORT)")
        options.update(url=args.url, baudrate=args.baudrate)
    else:
        options.update(host=args.host, port=args.port if args.port is not None else DEFAULT_PORTS[args.protocol])
        if args.protocol == "modbus" and args.register_map:
            options["register_map"] = args.register_map
    return options


def run(args) -> int:
    if getattr(args, "robot_command", None) not in ("joints", "status"):
        args._robot_parser.print_help()
        return 2
    import json

    from ...drivers.controller import open_controller, read_robot_state

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
            if args.json:
                print(json.dumps(data))
            else:
                print(f"{info.program} (protocol {info.protocol_version}, {info.postures} approved postures): "
                      f"{status.state} at posture {status.posture}")
    return 0
