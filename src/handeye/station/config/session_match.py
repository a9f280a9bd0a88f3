"""Was a session captured on the station a config describes? Its controller, camera, robot and board.

A capture records the station configuration it ran with (``session.yaml``, ``capture.config``:
``StationConfig.to_dict``); ``handeye verify`` revisits a session's postures on the connected station,
which only means something when that is the station the session was captured on. What identifies it:

- the controller: its link protocol (``mock`` is the embedded mock station) and, for a real link,
  the address it was reached at (``controller.host``);
- the camera: its back end and the settings that back end declares to pick one device (``guid`` of
  an XB3), compared when both sides name one (a session that opened "the only XB3" names none);
- the robot model and the board (corner counts and square size).

A session without the record (captured before it existed) is compared on what it holds: mock or
real (``capture.station``), the robot and the board.
"""

from __future__ import annotations

from .station import MOCK, StationConfig
from ..origin import MOCK as MOCK_ORIGIN, session_origin

__all__ = ["station_differences", "station_mismatch"]


def _controller(record: dict) -> str:
    protocol = str(record.get("protocol"))
    if protocol == MOCK:
        return "mock (the embedded mock station)"
    return f"{protocol} at {record.get('host')}"


def _controller_differs(recorded: dict, config: StationConfig) -> bool:
    if recorded.get("protocol") != config.controller.protocol:
        return True
    return config.controller.protocol != MOCK and recorded.get("host") != config.controller.host


def _camera_keys(backend: str) -> list[str]:
    """The non-secret settings the camera back end ``backend`` declares (``guid`` of the XB3)."""
    from ...drivers import camera_settings  # noqa: PLC0415

    return [key for key, (setting, names) in camera_settings().items()
            if backend in names and not getattr(setting, "secret", False)]


def _camera(backend: str, values: dict) -> str:
    named = [f"{key} {values[key]}" for key in _camera_keys(backend) if values.get(key) is not None]
    return backend + (f" ({', '.join(named)})" if named else "")


def _camera_differs(recorded: dict, config: StationConfig) -> bool:
    backend = config.camera.backend
    if recorded.get("backend") != backend:
        return True
    for key in _camera_keys(backend):
        there, here = recorded.get(key), getattr(config.camera, key, None)
        if there is not None and here is not None and str(there) != str(here):
            return True
    return False


def _config_camera(config: StationConfig) -> dict:
    keys = _camera_keys(config.camera.backend)
    return {"backend": config.camera.backend, **{key: getattr(config.camera, key, None) for key in keys}}


def _board(target) -> str:
    return f"{target.corners[0]}x{target.corners[1]}, {target.square_mm:g} mm"


def station_differences(session, config: StationConfig) -> list[str]:
    """What differs between the station ``session`` was captured on and the one ``config`` describes.

    Parameters
    ----------
    session : Session
        As read from disk (its capture record in ``extra['capture']``).
    config : StationConfig

    Returns
    -------
    list of str
        One phrase per difference, ``"another controller: mock (...) there, socket at 10.0.0.2 here"``;
        empty when nothing differs.
    """
    capture = session.extra.get("capture") if isinstance(session.extra, dict) else None
    recorded = capture.get("config") if isinstance(capture, dict) else None
    recorded = recorded if isinstance(recorded, dict) else {}
    out = []
    controller, camera = recorded.get("controller"), recorded.get("camera")
    if isinstance(controller, dict) and _controller_differs(controller, config):
        out.append(f"another controller: {_controller(controller)} there, "
                   f"{_controller({'protocol': config.controller.protocol, 'host': config.controller.host})} here")
    if isinstance(camera, dict) and _camera_differs(camera, config):
        out.append(f"another camera: {_camera(str(camera.get('backend')), camera)} there, "
                   f"{_camera(config.camera.backend, _config_camera(config))} here")
    if not isinstance(controller, dict):
        there = session_origin(session) == MOCK_ORIGIN
        here = config.is_mock or config.is_rehearsal
        if there != here:
            word = {True: "a mock station", False: "a real station"}
            out.append(f"another station: {word[there]} there, {word[here]} here")
    if (session.robot or "").lower() != config.robot.lower():
        out.append(f"another robot: {session.robot} there, {config.robot} here")
    target = session.target
    if target is None or tuple(target.corners) != tuple(config.target.corners) \
            or abs(target.square_mm - config.target.square_mm) > 1e-6:
        out.append(f"another board: {'none recorded' if target is None else _board(target)} there, "
                   f"{_board(config.target)} here")
    return out


def station_mismatch(session, session_dir, config: StationConfig) -> str | None:
    """The one-line refusal when ``session`` was not captured on ``config``'s station, else None."""
    differences = station_differences(session, config)
    if not differences:
        return None
    return (f"{session_dir} was captured on another station than {config.source} ({'; '.join(differences)}): "
            f"verify a session captured on this station (handeye capture, calibrate), or verify {session_dir} "
            "with the station config it was captured with (its session.yaml, capture.config; --mock for the "
            "embedded mock station); nothing moved")
