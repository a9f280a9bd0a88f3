"""``handeye mock controller``: a simulated IRB 1400 controller on 127.0.0.1, until Ctrl-C."""

from __future__ import annotations

import argparse
from typing import cast

from . import argtypes
from .argtypes import Subcommands

HELP = "run a mock (simulated IRB 1400 controller on 127.0.0.1) until Ctrl-C"

CONTROLLER_HELP = "run the mock robot controller ({protocols}) until Ctrl-C"

CONTROLLER_EPILOG = """\
The mock EXECUTES the RAPID program: the modules `handeye rapid generate` writes for --protocol
(the built-in station's 12 postures, or those, timeouts, PC address and write key of --config), or
the modules of --program DIR (e.g. a capture's SESSION/rapid), run by handeye's RAPID interpreter on
a simulated IRB 1400: joints and flange pose from its kinematics, motion time from the axis speeds
(x --time-scale). A module the interpreter cannot run is refused at start with its name and line;
a program that stops on an error ends the mock with that error. A program that ends by itself (EXIT,
Stop) or has not opened its link 3 s after it started is reported in one line on stderr; a socket
program that ends before it listens is refused at start.

Protocols and default ports:
{protocols}
--port 0 picks a free port; the line printed at start says where it listens.

The link recovers as the RAPID modules do: a PC silent for --idle-timeout seconds (default: the
config's controller.idle_timeout_s, else 5) is disconnected (socket) or its session forgotten
(serial), and a new connection from the PC takes over at once. The socket program accepts only
its PC address (controller.pc_address of --config, --allow-client, default 127.0.0.1). Tool
writes need the station's write key (controller.write_key of --config, or --write-key; HeKey.sys is
generated and loaded with it); without one they are refused. The mock listens on 127.0.0.1:
another --host lets the machines of that network reach it (a warning says so); it is for testing
only.

Rehearse an edited program: a station engineer's additions to the generated modules (a MoveJ to a
safe via point before the first posture, a MoveL retreat with Offs/RelTool, a WaitDI on the cell
door, an UNDO handler) run here as they would on the controller:
  handeye capture --config station.yaml --session S --plan-only     (writes S/rapid)
  (edit S/rapid/HeMain.mod)
  handeye mock controller --program S/rapid --config station.yaml --camera-port 5021 &
  handeye capture --config station.yaml --session S --yes
With --config, the moves are checked against the config's cell as a controller's motion supervision
would: a MoveJ/MoveAbsJ along its joint path, a MoveL along its TCP line (sampled every 5 mm, each
sample through the inverse kinematics); a move that would enter a volume stops the program at that
line, naming the volume. With or without --config, a move that would bring the camera or its bracket
into the arm's own links, or two links into each other (the robot file's self-collision pairs), stops
it at that line naming the pair (self-collision: camera against link 3). Check a program's targets
beforehand with handeye cell check. The robtargets' configuration (cf1, cf4, cf6, cfx) is respected (ConfJ/ConfL
\\Off: the nearest solution). The cell's I/O signals are diCellDoor and diCellReady (inputs, 1 at
start) and doCellLamp and doCellBusy (outputs); --signal NAME:TYPE=VALUE adds one, and a test or the
pendant sets an input over the camera port ({{"cmd": "signal", "name": "diCellDoor", "value": 0}}).
What the interpreter cannot run is refused at start with module:line and its name (src/handeye/rapid/PROTOCOL.md
lists what it runs).

--camera-port PORT also serves the simulated XB3 on the arm's flange (frames rendered from where the
arm really is, a hidden camera mount, a printed board) for a rehearsal station: a station config
with camera.backend: mock and camera.mock_arm: HOST:PORT runs capture, calibrate and writeback
against this mock exactly as on the real station; every output then says MOCK for the camera.

--pendant-port PORT serves the FlexPendant on 127.0.0.1:PORT, one line per request, one reply
(OK ... or ERR <why>), to play the operator of a guided capture (capture --guided, the program of
rapid generate --guided) from outside: "JOG j1 j2 j3 j4 j5 j6" jogs the arm there (axis angles,
deg; a jog whose path comes within the cell margin of a keep-out volume stops there: ERR jog stopped:
...), "START" continues a program stopped by Stop \\NoRegain, "KEY n" answers the pendant's prompt
(TPReadFK function key 1-5, UIMessageBox button n), "STATE" replies the execution state (running,
prompt, stopped, ended, error, none), the keys offered and the last pendant line. Play it with
handeye mock pendant (nothing else to install; with - it reads one request per line from stdin):
  handeye mock controller --config station.yaml --camera-port 5021 --pendant-port 5022 &
  handeye mock pendant --port 5022 STATE
The mock's state lives in its process: a restart resets its arm, its program and its tool data (a
write-back is lost), and its faults (mock.faults of --config) are read at start only: restart it
with the faults config to rehearse a drift.

Example:
  handeye mock controller --protocol modbus --port 5020 &
  handeye robot joints --protocol modbus --host 127.0.0.1 --port 5020 --json
  handeye mock controller --program cal_2026_11_21/rapid --config station.yaml
"""


def _protocols(loaded: bool = False) -> tuple[tuple[str, ...], str]:
    """The protocols a mock serves (registry order; with ``loaded``, of the back ends loaded so far only) and
    their lines for the epilog."""
    from ...mocks import mock_protocols, mock_server

    names = mock_protocols(loaded)
    lines = [f"  {name:<8} {mock_server(name).help}, port {mock_server(name).default_port}" for name in names]
    return names, "\n".join(lines)


def _server_options(parser) -> None:
    """One flag per mock server option (``MockServer.options`` of the mock protocols loaded so far: handeye's
    own and the plug-in the command line names, described once)."""
    from ...mocks import mock_settings

    for key, (setting, names) in mock_settings(loaded=True).items():
        parser.add_argument(setting.option, dest=f"server_{key}", type=argtypes.setting_value(setting), default=None,
                            metavar=setting.metavar or key.upper(), help=f"{', '.join(names)}: {setting.help}")


def add_parser(sub: Subcommands, words: list[str] | None = None) -> argparse.ArgumentParser:
    """``words``: the command line; only the plug-in its ``--protocol`` names is loaded (for its mock's own
    flags), every one for ``--help`` or when None (the whole parser)."""
    from ...drivers import CONTROLLERS
    from ...mocks import mock_protocol_choices
    from .argtypes import left_out_lines, load_for_flags, option_word, registry_choice

    wanted = None if words is None else option_word(words, "--protocol")
    load_for_flags(CONTROLLERS, wanted)
    names, _ = _protocols(loaded=True)
    p = sub.add_parser("mock", help=HELP, description=HELP)
    targets = cast(Subcommands, p.add_subparsers(dest="mock_target", metavar="TARGET"))  # a OneLineParser's parsers: a callable epilog is theirs
    controller_help = CONTROLLER_HELP.format(protocols=", ".join(names))
    protocols = mock_protocol_choices()

    def epilog() -> str:  # written when the help is asked for (it lists, and so loads, every plug-in)
        return CONTROLLER_EPILOG.format(protocols=_protocols()[1]) + left_out_lines(protocols, "--protocol")

    c = targets.add_parser("controller", help=controller_help, description=controller_help, epilog=epilog,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    from ...drivers import DEFAULT_PROTOCOL

    c.add_argument("--protocol", choices=protocols, type=registry_choice(protocols), default=DEFAULT_PROTOCOL,
                   metavar="PROTOCOL", help=f"one of the protocols above (default {DEFAULT_PROTOCOL})")
    c.add_argument("--port", type=argtypes.port, default=None, help="TCP port (defaults above; 0 = any free port)")
    c.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    c.add_argument("--config", metavar="STATION.yaml",
                   help="station config: approved postures, ack and idle timeouts, write key (controller.write_key)")
    c.add_argument("--time-scale", type=argtypes.positive, default=1.0, metavar="X",
                   help="wall-clock seconds per simulated second of motion (default 1; 0.1 = 10x faster)")
    c.add_argument("--allow-client", metavar="IP",
                   help="socket: the PC address rendered into the generated program (HE_PC_ADDRESS; default: the "
                        "config's controller.pc_address, 127.0.0.1); --program modules carry their own")
    _server_options(c)
    c.add_argument("--duration", type=argtypes.positive, metavar="S", help="stop after S seconds (default: run until Ctrl-C)")
    c.add_argument("--idle-timeout", type=argtypes.positive, metavar="S",
                   help="drop a silent PC (socket) / forget its session (serial) after S seconds, 0.1..10 "
                        "(default: the config's, else 5)")
    c.add_argument("--program", metavar="DIR",
                   help="run the RAPID modules (.mod/.modx/.sys) of DIR instead of the generated ones")
    c.add_argument("--signal", action="append", default=[], metavar="NAME:TYPE=VALUE",
                   help="a cell I/O signal besides diCellDoor, diCellReady, doCellLamp, doCellBusy "
                        "(diFence:signaldi=1); repeatable")
    c.add_argument("--camera-port", type=argtypes.port, metavar="PORT",
                   help="also serve the simulated XB3 on the flange for a rehearsal station (0 = any free port)")
    c.add_argument("--pendant-port", type=argtypes.port, metavar="PORT",
                   help="also serve the FlexPendant on 127.0.0.1:PORT (JOG j1..j6, START, KEY n, STATE) to play "
                        "the operator of a guided capture (0 = any free port)")
    c.add_argument("--write-key", metavar="KEY",
                   help="the key tool writes need (8-32 letters, digits, _ or -; default: the config's "
                        "controller.write_key). Visible in the process list: prefer --config")
    _add_pendant_parser(targets)
    p.set_defaults(_mock_parser=p)
    return p


PENDANT_HELP = "send requests to a running mock controller's pendant port and print its replies"

PENDANT_EPILOG = """\
Plays the operator of a guided capture by hand, against `handeye mock controller --pendant-port P`.
Each REQUEST is one line to the port (quote it), its reply is printed; with - instead, one request
is read per line from stdin until end of input. Exit status 0 when every reply is OK, 1 when one is
ERR (printed) or the port cannot be reached.

Requests: STATE (execution running|prompt|stopped|ended|error|none, the keys offered, the last
pendant line), KEY n (answer the prompt: TPReadFK key 1-5, UIMessageBox button n), JOG j1 .. j6 (axis
angles, deg), START (continue a program stopped by Stop \\NoRegain).

One posture of a guided capture (the PC's `capture --guided` running against the mock):
  handeye mock pendant --port 5022 STATE          (OK prompt 1=Capture,5=Done | ...)
  handeye mock pendant --port 5022 "KEY 1"        (Capture: the program stops for the jog)
  handeye mock pendant --port 5022 "JOG 10 -20 15 0 60 0"
  handeye mock pendant --port 5022 START          (the posture is offered to the PC, which captures)
repeated for each posture; at the last prompt the Done key ("KEY 5"; "KEY 2" with the guided
program's --prompt messagebox: STATE shows the keys offered) ends the capture.
"""


#: The longest wait for a pendant reply, s (a JOG replies once the arm stands still).
PENDANT_REPLY_S = 10.0


def _add_pendant_parser(targets) -> None:
    t = targets.add_parser("pendant", help=PENDANT_HELP, description=PENDANT_HELP, epilog=PENDANT_EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    t.add_argument("--host", default="127.0.0.1", help="the mock's address (default 127.0.0.1)")
    t.add_argument("--port", type=argtypes.port, default=5022, help="its --pendant-port (default 5022, the port of the examples)")
    t.add_argument("requests", nargs="+", metavar="REQUEST",
                   help='one request line each: STATE, "KEY n", "JOG j1 .. j6", START; - reads them from stdin')


def _run_pendant(args) -> int:
    """Sends each request to the pendant port and prints the reply; 1 when a reply is ERR."""
    import sys

    from ...base import HandEyeError
    from ..guided.pendant_client import PendantClient

    requests = ((line.strip() for line in sys.stdin if line.strip()) if args.requests == ["-"] else args.requests)
    try:
        client = PendantClient(f"{args.host}:{args.port}", timeout_s=PENDANT_REPLY_S)
    except OSError as exc:
        raise HandEyeError(f"cannot reach the pendant port {args.host}:{args.port} ({exc.strerror or exc}): "
                           "start handeye mock controller with --pendant-port, or check --port") from None
    status = 0
    try:
        for request in requests:
            reply = client.ask(request)
            print(reply, flush=True)
            status = status or (0 if reply.startswith("OK") else 1)
    except TimeoutError:
        raise HandEyeError(f"the pendant port {args.host}:{args.port} did not reply within {PENDANT_REPLY_S:g} s; "
                           "is it a mock controller's --pendant-port?") from None
    except OSError as exc:  # ConnectionError too: the port hung up
        raise HandEyeError(f"the pendant port {args.host}:{args.port} closed the link ({exc}); "
                           "is the mock controller still running?") from None
    finally:
        client.close()
    return status


def run(args: argparse.Namespace) -> int:
    if getattr(args, "mock_target", None) == "pendant":
        return _run_pendant(args)
    if getattr(args, "mock_target", None) != "controller":
        args._mock_parser.print_help()
        return 2
    import sys

    from ...base import UsageError
    from ...mocks import MockControllerOptions, run_mock_controller
    from ...rapid import IDLE_TIMEOUT_RANGE

    low, high = IDLE_TIMEOUT_RANGE
    if args.idle_timeout is not None and not low <= args.idle_timeout <= high:
        raise UsageError(f"--idle-timeout must be {low:g} to {high:g} s; got {args.idle_timeout:g}")

    from ...mocks import parse_signal

    try:
        signals = tuple(parse_signal(text) for text in args.signal)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    station = cell = faults = arm = None
    if args.config:
        from ...drivers import RAPID_LINKS
        from ...rapid import default_station, station_from_dict
        from ..config.station import load_config

        config = load_config(args.config)
        postures = config.postures if config.postures is not None else default_station().postures
        station = station_from_dict(config.rapid_dict(postures), args.config, links=RAPID_LINKS)
        cell = config.cell.model()
        faults = config.mock.faults.model()  # mock.faults: what its camera sees changed
        arm = config.mock.arm.model()  # mock.arm: the arm's true deviations (None: random)
    server_options = {name[len("server_"):]: value for name, value in vars(args).items()
                      if name.startswith("server_") and value is not None}
    options = MockControllerOptions(protocol=args.protocol, port=args.port, host=args.host, station=station,
                                    time_scale=args.time_scale, allowed_client=args.allow_client,
                                    server_options=server_options, duration_s=args.duration,
                                    idle_timeout_s=args.idle_timeout, write_key=args.write_key,
                                    program=args.program, camera_port=args.camera_port, cell=cell, signals=signals,
                                    pendant_port=args.pendant_port,
                                     faults=faults, arm=arm)
    return run_mock_controller(options, announce=lambda text: print(text, flush=True),
                               warn=lambda text: print(text, file=sys.stderr, flush=True))
