"""Run a mock controller standalone (what ``handeye mock controller`` calls)."""

from __future__ import annotations

import time
from dataclasses import dataclass

from ...rapid.station import default_station, load_station
from . import DEFAULT_PORTS, MOCK_PROTOCOLS, start_mock_controller

__all__ = ["MockControllerOptions", "run_mock_controller"]


@dataclass(frozen=True)
class MockControllerOptions:
    """Settings of a standalone mock controller.

    Attributes
    ----------
    protocol : str
        ``socket``, ``serial`` or ``modbus``.
    port : int or None
        None: the protocol's default (:data:`DEFAULT_PORTS`); 0: any free port.
    host : str
    config : str or None
        Station YAML for the approved postures and the acknowledgement timeout (None: built-in).
    time_scale : float
        Wall-clock seconds per simulated second of motion.
    allowed_client : str or None
        Socket only: accept only this client address, as the RAPID module does.
    register_map : str or None
        Modbus only: register map YAML.
    duration_s : float or None
        Stop after this long (None: until Ctrl-C).
    """

    protocol: str = "socket"
    port: int | None = None
    host: str = "127.0.0.1"
    config: str | None = None
    time_scale: float = 1.0
    allowed_client: str | None = None
    register_map: str | None = None
    duration_s: float | None = None


def _banner(server, options: MockControllerOptions, postures: int) -> str:
    where = f"{server.host}:{server.port}"
    head = f"mock {options.protocol} controller (simulated IRB 1400, {postures} approved postures)"
    if options.protocol == "serial":
        return (f"{head}: serial line on pyserial URL {server.url}; stop with Ctrl-C\n"
                f"  try: handeye robot joints --protocol serial --url {server.url} --json")
    return (f"{head} listening on {where}; stop with Ctrl-C\n"
            f"  try: handeye robot joints --protocol {options.protocol} --host {server.host} --port {server.port} --json")


def run_mock_controller(options: MockControllerOptions, announce=print) -> int:
    """Start the mock, announce where it listens, serve until Ctrl-C (or ``duration_s``); returns 0."""
    from ...drivers.controller.errors import InvalidRequest

    if options.protocol not in MOCK_PROTOCOLS:
        raise InvalidRequest(f"unknown protocol {options.protocol!r}; choose one of {', '.join(MOCK_PROTOCOLS)}")
    if not options.time_scale > 0:
        raise InvalidRequest(f"--time-scale must be > 0; got {options.time_scale}")
    station = load_station(options.config) if options.config else default_station()
    port = DEFAULT_PORTS[options.protocol] if options.port is None else options.port
    try:
        server = start_mock_controller(options.protocol, host=options.host, port=port, postures=station.postures,
                                       time_scale=options.time_scale, ack_timeout_s=station.ack_timeout_s,
                                       allowed_client=options.allowed_client, register_map=options.register_map)
    except OSError as exc:
        raise InvalidRequest(f"cannot listen on {options.host}:{port} ({exc}); pick another --port "
                             "(0 = any free port)") from None
    try:
        announce(_banner(server, options, len(station.postures)))
        end = None if options.duration_s is None else time.monotonic() + options.duration_s
        while end is None or time.monotonic() < end:
            time.sleep(0.1 if end is None else max(0.0, min(0.1, end - time.monotonic())))
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    announce("mock controller stopped")
    return 0
