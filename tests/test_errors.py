"""The exceptions: five kinds shared by every back end, each naming the back end; one ConfigError
for every configuration problem; everything under HandEyeError."""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

import pytest

from handeye.base.errors import ConfigError, HandEyeError
from handeye.drivers import errors as E
from handeye.drivers.controller import open_controller
from handeye.drivers.controller.backends import CONTROLLERS

REPO = Path(__file__).resolve().parents[1]
#: Exceptions that never leave their module (turned into one of the package's before they do).
INTERNAL = {"LinkDown",
            # a key written twice, caught inside the YAML and JSON readers and turned into their one-line error
            "DuplicateKeyError", "_DuplicateJsonKey",
            # an alias bomb and a JSON of too many keys, caught inside the same readers likewise
            "AliasBombError", "_TooManyJsonKeys",
            # the mock RWS server's error answers (turned into HTTP responses, never raised out of it)
            "HttpError",
            # the RAPID interpreter's control flow (RETURN, RETRY, TRYNEXT, EXIT, Stop, a task asked to stop):
            # BaseExceptions that never leave a running task
            "ReturnSignal", "RetrySignal", "TryNextSignal", "ExitSignal", "StopSignal", "TaskStopped"}


def test_five_kinds_shared_by_every_back_end():
    assert set(E.KINDS) == {"connection", "timeout", "protocol", "refused", "configuration"}
    assert all(issubclass(kind, HandEyeError) for kind in E.KINDS.values())
    # the controller side's names are the shared kinds themselves, not copies
    assert E.ControllerTimeout is E.LinkTimeout and E.ControllerConnectionError is E.LinkConnectionError
    assert E.ControllerRefused is E.Refused


def test_a_kind_carries_the_back_ends_name():
    error = E.LinkTimeout("PING: no reply within 1 s", backend="modbus")
    assert (error.backend, error.detail, str(error)) == ("modbus", "PING: no reply within 1 s", "modbus: PING: no reply within 1 s")
    refused = E.Refused("busy", 5, backend="socket")
    assert refused.code == 5 and str(refused) == "socket: busy"
    assert str(E.ProtocolError("garbage")) == "garbage" and E.ProtocolError("garbage").backend is None
    assert str(ConfigError("register map x: bad", backend="modbus")) == "modbus: register map x: bad"


def test_one_config_error_for_every_configuration():
    from handeye.drivers.controller.modbus_map import load_register_map
    from handeye.rapid.errors import StationConfigError
    from handeye.rapid.station import station_from_dict
    from handeye.station.config.station import ConfigError as StationConfigErrorOfTheStation
    from handeye.station.config.station import config_from_dict

    assert StationConfigError is ConfigError is StationConfigErrorOfTheStation is E.ConfigError
    for bad in (lambda: config_from_dict({"camrea": {}}), lambda: station_from_dict({"controller": {"port": 0}}),
                lambda: load_register_map(REPO / "nothere.yaml")):
        with pytest.raises(ConfigError):
            bad()


@pytest.mark.parametrize("protocol", CONTROLLERS.names())
def test_every_back_end_raises_the_shared_kind_with_its_name(protocol):
    where = {"url": "socket://127.0.0.1:1"} if protocol == "serial" else {"host": "127.0.0.1", "port": 1}
    with pytest.raises(E.LinkConnectionError) as info:
        open_controller(protocol, timeout=0.3, retries=0, idle_timeout=0.1, **where)
    assert info.value.backend == protocol and str(info.value).startswith(f"{protocol}: connect: no link")


def _exception_classes():
    for room in ("base", "geometry", "robot", "calibration", "drivers", "rapid", "mocks", "station"):
        for path in sorted((REPO / "src" / "handeye" / room).rglob("*.py")):
            if path.name in ("__init__.py", "__main__.py") or "alias_module(__name__" in path.read_text():
                continue  # (an old path's alias: its module is walked at its new path)
            module = importlib.import_module("handeye." + ".".join(path.relative_to(REPO / "src" / "handeye").with_suffix("").parts))
            for name, obj in vars(module).items():
                if inspect.isclass(obj) and issubclass(obj, BaseException) and obj.__module__ == module.__name__:
                    yield name, obj


def test_every_exception_of_the_package_is_a_handeye_error_and_none_is_a_per_back_end_copy():
    classes = dict(_exception_classes())
    assert classes
    strays = sorted(name for name, cls in classes.items() if not issubclass(cls, HandEyeError) and name not in INTERNAL)
    assert not strays, strays
    copies = sorted(name for name in classes if name.startswith(("Socket", "Serial", "Modbus")))
    assert copies == ["ModbusExceptionResponse"]  # a Modbus exception response: a protocol error with its code
