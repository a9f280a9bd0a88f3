"""``handeye mock controller``: a simulated IRB 1400 controller on 127.0.0.1, until Ctrl-C."""

from __future__ import annotations

import argparse

from . import argtypes

HELP = "run a mock (simulated IRB 1400 controller on 127.0.0.1) until Ctrl-C"

CONTROLLER_HELP = "run the mock robot controller (socket, serial or Modbus TCP) until Ctrl-C"

CONTROLLER_EPILOG = """\
The mock behaves like the RAPID program that `handeye rapid generate` writes: the robot goes only
to the approved postures (the built-in station's 12, or those of --config), one at a time, and
waits for the PC's acknowledgement at each; joints and flange pose come from the IRB 1400
kinematics, motion time from the axis speeds (x --time-scale).

Protocols and default ports:
  socket   TCP line protocol (rapid/PROTOCOL.md), port 1025
  serial   the same line protocol as a byte stream for pyserial's socket://HOST:PORT URL, port 1026
  modbus   Modbus TCP gateway with the I/O handshake (drivers/controller/modbus_map.yaml), port 5020
--port 0 picks a free port; the line printed at start says where it listens.

Example:
  handeye mock controller --protocol modbus --port 5020 &
  handeye robot joints --protocol modbus --host 127.0.0.1 --port 5020 --json
"""


def add_parser(sub):
    p = sub.add_parser("mock", help=HELP, description=HELP)
    targets = p.add_subparsers(dest="mock_target", metavar="TARGET")
    c = targets.add_parser("controller", help=CONTROLLER_HELP, description=CONTROLLER_HELP, epilog=CONTROLLER_EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    c.add_argument("--protocol", choices=("socket", "serial", "modbus"), default="socket", help="default socket")
    c.add_argument("--port", type=argtypes.port, default=None, help="TCP port (defaults above; 0 = any free port)")
    c.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    c.add_argument("--config", metavar="STATION.yaml", help="approved postures and ack timeout from a station config")
    c.add_argument("--time-scale", type=argtypes.positive, default=1.0, metavar="X",
                   help="wall-clock seconds per simulated second of motion (default 1; 0.1 = 10x faster)")
    c.add_argument("--allow-client", metavar="IP", help="socket: accept only this client address, like the RAPID module")
    c.add_argument("--register-map", metavar="MAP.yaml", help="modbus: register map (default: the built-in one)")
    c.add_argument("--duration", type=argtypes.positive, metavar="S", help="stop after S seconds (default: run until Ctrl-C)")
    p.set_defaults(_mock_parser=p)
    return p


def run(args) -> int:
    if getattr(args, "mock_target", None) != "controller":
        args._mock_parser.print_help()
        return 2
    from ...mocks.controller.service import MockControllerOptions, run_mock_controller

    options = MockControllerOptions(protocol=args.protocol, port=args.port, host=args.host, config=args.config,
                                    time_scale=args.time_scale, allowed_client=args.allow_client,
                                    register_map=args.register_map, duration_s=args.duration)
    return run_mock_controller(options, announce=lambda text: print(text, flush=True))
