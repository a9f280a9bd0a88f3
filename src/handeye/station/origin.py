"""Where a session's data came from: the real station, the embedded mock station, or a simulation.

A calibration of simulated data can look perfect; the report, the text summary and the JSON say so,
so that nobody takes it for a calibration of the robot in front of them.

- ``mock``: captured on a mock station: the embedded one (``handeye capture --mock``, ``handeye demo``)
  or a rehearsal against ``handeye mock controller`` (``camera.mock_arm``): ``session.yaml`` says
  ``capture: {station: mock}``. Sessions captured before that key existed are
  recognised by their recorded station configuration (``capture.config.camera.backend: mock``).
- ``real``: ``capture: {station: real}``, written by a capture on the real controller and camera
  (``station.config.station_kind``), and no mock part in the station configuration it recorded (a record
  that says ``real`` beside a mock camera or ``camera.mock_arm`` is ``mock``).
- ``simulated``: ``session.yaml`` says ``origin: simulated``, or ``truth.yaml`` lies beside it
  (``handeye simulate``), and the capture record does not say otherwise.
- ``unknown``: anything else (imported data sets, hand-written sessions).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["MOCK", "ORIGINS", "REAL", "SIMULATED", "UNKNOWN", "origin_banner", "origin_line", "session_origin"]

MOCK, REAL, SIMULATED, UNKNOWN = "mock", "real", "simulated", "unknown"
#: Every value :func:`session_origin` returns.
ORIGINS = (MOCK, REAL, SIMULATED, UNKNOWN)

_BANNERS = {
    "mock": ("MOCK SESSION", "captured on a mock station (embedded, or a rehearsal); not a calibration of a real "
                             "robot"),
    "simulated": ("SIMULATED SESSION", "synthetic data with a known truth (truth.yaml); not a calibration of a "
                                       "real robot"),
}


def _header(path) -> dict:
    """``session.yaml`` of a folder as a mapping ({} when missing or unreadable)."""
    from ..base import parse_yaml

    try:
        data = parse_yaml((Path(path) / "session.yaml").read_text(), Path(path) / "session.yaml", ValueError)
    except (OSError, UnicodeDecodeError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def session_origin(session=None, path=None) -> str:
    """``mock``, ``real``, ``simulated`` or ``unknown`` (see the module's description).

    Parameters
    ----------
    session : Session, optional
        A session read from disk; its ``extra['capture']`` holds the capture record. When omitted,
        ``session.yaml`` is read from ``path``.
    path : str or Path, optional
        The session folder (for ``truth.yaml``, and ``session.yaml`` when ``session`` is omitted);
        ``session.path`` when omitted.

    Returns
    -------
    str
        One of :data:`ORIGINS`.
    """
    if path is None and session is not None:
        path = getattr(session, "path", None)
    if session is not None:
        extra = getattr(session, "extra", None) or {}
    elif path is not None:
        extra = _header(path)
    else:
        return "unknown"
    capture = extra.get("capture")
    capture = capture if isinstance(capture, dict) else {}
    station = capture.get("station")
    if isinstance(station, str) and station.strip().lower() in ("mock", "real"):
        from .config.station_kind import recorded_mock_parts

        return MOCK if station.strip().lower() == MOCK or recorded_mock_parts(capture) else REAL
    if extra.get("origin") == SIMULATED or (path is not None and (Path(path) / "truth.yaml").is_file()):
        return "simulated"
    config = capture.get("config")
    camera = config.get("camera") if isinstance(config, dict) else None
    if isinstance(camera, dict) and camera.get("backend") == "mock":
        return "mock"
    return "unknown"


def origin_banner(origin: str) -> tuple[str, str] | None:
    """``(word, text)`` of the warning a report shows for ``mock`` and ``simulated`` sessions, else ``None``.

    ``word`` is ``MOCK SESSION`` or ``SIMULATED SESSION``; ``text`` says what the data are.
    """
    return _BANNERS.get(origin)


def origin_line(origin: str) -> str | None:
    """The banner of :func:`origin_banner` as one line (``MOCK SESSION: captured on ...``), else ``None``."""
    banner = origin_banner(origin)
    return None if banner is None else f"{banner[0]}: {banner[1]}"
