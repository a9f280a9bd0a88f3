"""Where a session's data came from: a real station, the embedded mock station, or a simulation.

A calibration from the mock station or from a simulation is a test of the software, never a camera
pose of a real robot; every output names the origin so that nobody takes one for the other, and
write-back refuses to put such a pose into a real controller.

The origin is read from the session itself: ``capture`` records ``capture.station`` (``real`` or
``mock``) in ``session.yaml``; ``simulate`` records ``origin: simulated`` and writes ``truth.yaml``
beside the postures; ``import`` records an ``import`` section.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["IMPORTED", "MOCK", "ORIGINS", "REAL", "SIMULATED", "UNKNOWN", "origin_banner", "session_origin"]

REAL, MOCK, SIMULATED, IMPORTED, UNKNOWN = "real", "mock", "simulated", "imported", "unknown"
ORIGINS = (REAL, MOCK, SIMULATED, IMPORTED, UNKNOWN)

_BANNERS = {
    MOCK: "MOCK SESSION: captured on the embedded mock station; not a calibration of a real robot",
    SIMULATED: "SIMULATED SESSION: synthetic data; not a calibration of a real robot",
}


def session_origin(session, path=None) -> str:
    """``real``, ``mock``, ``simulated``, ``imported`` or ``unknown``.

    Parameters
    ----------
    session : calibration.session.Session
    path : path, optional
        The session folder (default ``session.path``): a ``truth.yaml`` there marks a simulation.
    """
    extra = getattr(session, "extra", None) or {}
    capture = extra.get("capture")
    if isinstance(capture, dict) and capture.get("station") in (REAL, MOCK):
        return capture["station"]
    folder = path if path is not None else getattr(session, "path", None)
    if extra.get("origin") == SIMULATED or (folder is not None and (Path(folder) / "truth.yaml").is_file()):
        return SIMULATED
    if isinstance(extra.get("import"), dict):
        return IMPORTED
    if isinstance(capture, dict):
        return MOCK if _old_mock_capture(capture) else REAL
    return UNKNOWN


def _old_mock_capture(capture: dict) -> bool:
    """Captures recorded before ``capture.station`` existed: the stored config tells (camera backend)."""
    config = capture.get("config")
    camera = config.get("camera") if isinstance(config, dict) else None
    return isinstance(camera, dict) and camera.get("backend") == MOCK


def origin_banner(origin: str) -> str | None:
    """The one-line warning every output carries for a mock or simulated session (None otherwise)."""
    return _BANNERS.get(origin)
