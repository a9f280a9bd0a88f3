"""``handeye rapid generate``: the RAPID modules of the station (posture sequencing, PC link, camera tool)."""

from __future__ import annotations

import argparse
from typing import cast

from .argtypes import Subcommands

HELP = "write the RAPID modules for the robot controller"

GENERATE_HELP = "render the RAPID program of a station (default: the built-in mock station) into a folder"

GENERATE_EPILOG = """\
Writes three modules to load together into the robot task:
  HeMain.mod     main routine; the approved postures as CONST jointtargets (the robot goes only
                 there, MoveAbsJ ... fine, at the configured speed); waits for the PC's ACK at each
one link module, by protocol (every registered controller back end's):
{link_modules}
  HeTool.mod     PERS tooldata of the camera (identity frame until calibrated)
  HeCell.mod     only with motion.speed_override_pct < 100 or cell.world_zones: true: VelSet, and
                 the cell's keep-out volumes as world zones (World Zones option 608-1) on the
                 camera's nominal TCP; main calls HeCellSetup first
  HeKey.sys      only with controller.write_key in --config: a system module holding the write
                 key (a secret) that tool writes need. Load it ONCE on the controller (system
                 modules stay loaded when the program modules are replaced); never copy it into
                 sessions or version control. `handeye capture` never writes it.
Postures outside the joint limits are refused; every module is checked before it is written.
The protocol is documented in src/handeye/rapid/PROTOCOL.md.

Station config: the station YAML (src/handeye/station/config/example_station.yaml documents every key). These keys
shape the RAPID program; all are optional, missing ones come from the built-in station:
  robot: IRB1400
  controller: {protocol: socket, pc_address: 192.168.125.10, controller_address: auto,
               port: 1025, serial_channel: "sio1:", ack_timeout_s: 30, idle_timeout_s: 5,
               write_key: YOUR-SECRET-KEY}
  motion: {speed_tcp_mm_s: 200, speed_ori_deg_s: 100, speed_override_pct: 100}
  cell: {keep_out: [...], world_zones: false}      # see src/handeye/station/config/example_station.yaml
  tool: {name: tHeCamera, mass_kg: 1.0, cog_mm: [0, 0, 60]}
  postures: [[a1, a2, a3, a4, a5, a6], ...]        # controller axis angles, degrees (one per robot axis)
controller_address auto binds to GetSysInfo(\\LanIp); a virtual controller needs 127.0.0.1.
(`handeye capture` plans the postures itself and writes its program into the session.)

--guided writes the guided capture's program instead of HeMain (every link but rws): HeGuide.mod
(no jointtarget, never moves the robot) asks the PC what the posture set lacks, shows it on the
FlexPendant (--prompt fk: TPReadFK, S4C+ and every RobotWare; messagebox: UIMessageBox, RobotWare
6/7; default guided.prompt of the config), stops with Stop \\NoRegain for the operator to jog in
manual mode, and on Start offers CJointT()/CRobT() to the PC, then waits for its verdict. The link
module carries the GUIDE request (Modbus: the guide_verdict and guide_hint registers). Robot Web
Services needs no program for a guided capture.

Example:
  handeye rapid generate --config station.yaml -o rapid_out
  handeye rapid generate --config station.yaml -o rapid_guided --guided
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    from ...drivers import rapid_protocol_choices
    from .argtypes import left_out_lines, registry_choice

    p = sub.add_parser("rapid", help=HELP, description=HELP)
    what = cast(Subcommands, p.add_subparsers(dest="rapid_command", metavar="COMMAND"))  # a OneLineParser's parsers: a callable epilog is theirs
    from ..backend_help import link_module_lines

    protocols = rapid_protocol_choices()  # a name is checked when given: no plug-in is imported to build this

    def epilog() -> str:
        return (GENERATE_EPILOG.replace("{link_modules}", "\n".join(link_module_lines()))
                + left_out_lines(protocols, "--protocol"))

    g = what.add_parser("generate", help=GENERATE_HELP, description=GENERATE_HELP, epilog=epilog,
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    g.add_argument("--config", metavar="STATION.yaml", help="station config (default: the built-in mock station)")
    g.add_argument("-o", "--output", required=True, metavar="DIR", help="folder for the .mod files (created)")
    g.add_argument("--protocol", choices=protocols, type=registry_choice(protocols), metavar="PROTOCOL",
                   help="link module to write: a protocol with a RAPID link module, listed below (default: "
                        "controller.protocol of the config)")
    g.add_argument("--guided", action="store_true",
                   help="the guided capture's program (HeGuide: pendant prompts, Stop \\NoRegain, offers the posture)")
    g.add_argument("--prompt", choices=("fk", "messagebox"),
                   help="--guided: TPReadFK (fk) or UIMessageBox (messagebox, RobotWare 6/7); default guided.prompt")
    p.set_defaults(_rapid_parser=p)
    return p


def run(args: argparse.Namespace) -> int:
    if getattr(args, "rapid_command", None) != "generate":
        args._rapid_parser.print_help()
        return 2
    from ...drivers import RAPID_LINKS
    from ...base import UsageError
    from ...rapid import render_guided_program, render_key, render_program, station_link, write_modules
    from ...rapid import default_station, station_from_dict
    from ..config.station import load_config

    if args.prompt and not args.guided:
        raise UsageError("--prompt applies to --guided only")
    prompt = args.prompt or "fk"
    if args.config:
        config = load_config(args.config)
        prompt = args.prompt or config.guided.prompt
        postures = config.postures if config.postures is not None else default_station().postures
        station = station_from_dict(config.rapid_dict(postures), args.config, links=RAPID_LINKS)
    else:
        station = default_station().with_(links=RAPID_LINKS)
    modules = (render_guided_program(station, args.protocol, prompt) if args.guided
               else render_program(station, protocol=args.protocol))
    paths = write_modules(modules, args.output)
    for path in paths:
        print(path)
    names = ", ".join(p.name for p in paths)
    protocol = args.protocol or station.protocol
    if not station_link(station, protocol).write_key:
        print(f"{protocol}: tool writes are authorised by the controller itself (no write key, no HeKey.sys); "
              "handeye capture uploads, loads and starts these modules itself")
    elif station.write_key is not None:
        (key_path,) = write_modules([render_key(station)], args.output)
        print(key_path)
        print(f"{key_path.name} holds the station's write key (a secret, readable by you only): load it ONCE into the "
              "robot task as a system module (it stays loaded when the program modules are replaced); never copy it "
              "into sessions or version control")
    else:
        print("no controller.write_key in the config: these modules refuse every tool write (set one and regenerate "
              "to write the calibrated tool data from the PC)")
    print(f"load {names} into the robot task (e.g. T_ROB1), then start main; protocol: src/handeye/rapid/PROTOCOL.md")
    return 0
