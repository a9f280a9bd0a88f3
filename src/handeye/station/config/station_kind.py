"""Which station a command runs on: the real one, or a mock. One decision for every command.

Every capture path (planned, guided by joints, guided by the pendant), ``verify`` and its quick
update record where their data come from (``capture.station`` in ``session.yaml``: ``mock`` or
``real``, read back by :func:`~handeye.station.origin.session_origin`); ``handeye writeback`` refuses
a mock session for a real controller, and ``calibrate`` says MOCK SESSION for one. All of them ask
:func:`station_kind`, so a session made with any mock part is never recorded as real:

- the configuration: the embedded mock station (``controller.protocol: mock``), a simulated camera
  (``camera.backend: mock``, or any camera back end registered as ``simulated``), the camera of
  ``handeye mock controller`` on its arm (``camera.mock_arm``: a rehearsal);
- the connected station (:class:`~handeye.station.runtime.StationLink`): the embedded mock
  (``link.mock``), a rehearsal camera (``link.rehearsal``), or a driver that says it is talking to a
  simulation (its ``simulated`` attribute: the standalone mock's Robot Web Services announce
  themselves as ``handeye-mock``);
- the data it derives from (``verify``'s quick update is SESSION's calibration moved by the check's
  measurements): a session that is not ``real`` makes the new one a mock one too.

Only when none of these holds is the station ``real``. A session on disk whose record says ``real`` but
whose recorded configuration has a mock part (written before this decision was one) is read as ``mock``
(:func:`recorded_mock_parts`, used by ``session_origin``).
"""

from __future__ import annotations

from ..origin import MOCK, REAL

__all__ = ["hardware_mock_parts", "mock_parts", "recorded_mock_parts", "station_kind", "station_tag"]


def _simulated_camera(backend: str) -> bool:
    """True for ``mock`` and for any camera back end registered as simulated."""
    from ...drivers import CAMERAS

    if backend == MOCK:
        return True
    try:
        entry = CAMERAS.get(backend)
    except Exception:  # noqa: BLE001 - a plug-in that fails to load is not a simulation we know of
        return False
    return bool(getattr(entry, "simulated", False))


def hardware_mock_parts(protocol, backend, mock_arm) -> list[str]:
    """What of a station's hardware words is a mock: ``controller.protocol``, ``camera.backend`` and
    ``camera.mock_arm`` of a config, or of the config a session recorded (``capture.config``)."""
    parts = []
    if protocol == MOCK:
        parts.append("the embedded mock station (controller.protocol: mock)")
    if mock_arm is not None:
        parts.append(f"the camera of `handeye mock controller` at {mock_arm} (camera.mock_arm: a rehearsal)")
    elif protocol != MOCK and isinstance(backend, str) and _simulated_camera(backend):
        parts.append(f"a simulated camera (camera.backend: {backend})")
    return parts


def recorded_mock_parts(record) -> list[str]:
    """:func:`hardware_mock_parts` of the station configuration a capture record holds (``capture.config``;
    nothing when it holds none)."""
    config = record.get("config") if isinstance(record, dict) else None
    if not isinstance(config, dict):
        return []
    controller, camera = config.get("controller"), config.get("camera")
    controller = controller if isinstance(controller, dict) else {}
    camera = camera if isinstance(camera, dict) else {}
    return hardware_mock_parts(controller.get("protocol"), camera.get("backend"), camera.get("mock_arm"))


def _link_parts(link) -> list[str]:
    parts = []
    if getattr(link, "mock", None) is not None:
        parts.append("the embedded mock station's controller and camera")
    if getattr(link, "rehearsal", None):
        parts.append(f"the rehearsal camera of `handeye mock controller` at {link.rehearsal}")
    for what in ("controller", "camera"):
        if getattr(getattr(link, what, None), "simulated", False) is True:
            parts.append(f"a {what} that says it is a simulation ({type(getattr(link, what)).__name__})")
    return parts


def mock_parts(config, link=None, source_origin: str | None = None) -> list[str]:
    """What makes a station a mock one, each in a few words (empty: the real station).

    Parameters
    ----------
    config : StationConfig
    link : StationLink, optional
        The connected station (its drivers), when there is one.
    source_origin : str, optional
        Where the data the new session derives from were made (``station.origin`` words): anything
        but ``real`` is a mock part.
    """
    camera = config.camera
    parts = hardware_mock_parts(config.controller.protocol, camera.backend, getattr(camera, "mock_arm", None))
    if link is not None:
        parts += [p for p in _link_parts(link) if p not in parts]
    if source_origin is not None and source_origin != REAL:
        parts.append(f"data derived from a {source_origin} session")
    return parts


def station_kind(config, link=None, source_origin: str | None = None) -> str:
    """``mock`` when any part of the station (or the data derived from) is a mock, else ``real``
    (see the module's description; parameters as :func:`mock_parts`)."""
    return MOCK if mock_parts(config, link, source_origin) else REAL


def station_tag(config, link=None) -> str:
    """``"MOCK "`` for a mock station, the prefix of every line a command prints about it; else ``""``."""
    return "MOCK " if station_kind(config, link) == MOCK else ""
