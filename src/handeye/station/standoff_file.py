"""``SESSION/standoff.json``: the predicted stand-off error of a ``calibrate --kinematics``, for ``verify``.

``handeye calibrate SESSION --kinematics`` writes it (atomically) beside ``result.yaml``: the stand-off,
the predicted error of the stand-off point (board frame, mm) at every posture of the session, with and
without the kinematic correction, and the SHA-256 of the posture files it was computed from
(``result_file.postures_hash``). ``handeye verify --against SESSION`` reads it and states, next to the
prediction at the postures it revisited, the error of that point it measured; a file older than the
postures (hash changed) is not used.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..base import write_text_atomic

__all__ = ["STANDOFF_FILE", "STANDOFF_FORMAT", "save_prediction", "read_prediction", "predicted_at"]

STANDOFF_FILE = "standoff.json"
STANDOFF_FORMAT = "handeye-standoff/1"


def save_prediction(session_dir, posture_ids, standoff) -> Path:
    """Write ``SESSION/standoff.json`` of a ``calibration.standoff.StandoffError`` over the session's
    postures (``posture_ids``: their numbers, in the prediction's order)."""
    from .result_file import postures_hash

    path = Path(session_dir) / STANDOFF_FILE
    data = {"format": STANDOFF_FORMAT, "postures_sha256": postures_hash(session_dir),
            "standoff_mm": float(standoff.standoff_mm), "frame": "board (the work's frame)",
            "postures": [int(i) for i in posture_ids],
            "with_correction_mm": [float(v) for v in standoff.corrected_mm],
            "without_correction_mm": [float(v) for v in standoff.uncorrected_mm],
            "meaning": "predicted error (root of the expected squared error, mm) of a point at the stand-off along "
                       "the camera axis, in the board's frame, per posture: with the identified arm, and without "
                       "(the camera-only result with the controller's nominal arm, as the station runs)"}
    write_text_atomic(path, json.dumps(data, indent=1) + "\n")
    return path


def read_prediction(session_dir) -> dict | None:
    """The prediction of SESSION when it has a current one (None: no file, unreadable, or older than the
    postures)."""
    from .result_file import postures_hash

    path = Path(session_dir) / STANDOFF_FILE
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != STANDOFF_FORMAT:
        return None
    if data.get("postures_sha256") != postures_hash(session_dir) or not _well_formed(data):
        return None
    return data


def _well_formed(data: dict) -> bool:
    """True when the prediction holds what :func:`predicted_at` reads: a positive stand-off and, per posture,
    an integer number and two finite errors (a file edited by hand, or damaged, is not used)."""
    def numbers(key: str) -> list | None:
        values = data.get(key)
        ok = isinstance(values, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
        return values if ok else None

    postures, with_, without = numbers("postures"), numbers("with_correction_mm"), numbers("without_correction_mm")
    standoff = data.get("standoff_mm")
    if postures is None or with_ is None or without is None or not len(postures) == len(with_) == len(without):
        return False
    return (isinstance(standoff, (int, float)) and not isinstance(standoff, bool) and standoff > 0
            and all(float(n).is_integer() for n in postures) and bool(np.all(np.isfinite(with_ + without))))


def predicted_at(data: dict, numbers) -> tuple[float, float] | None:
    """RMS of the predicted error (without, with the correction; mm) over SESSION's posture ``numbers``;
    None when one of them is not in the prediction."""
    index = {int(n): i for i, n in enumerate(data["postures"])}
    if not numbers or any(int(n) not in index for n in numbers):
        return None
    rows = [index[int(n)] for n in numbers]
    without = np.asarray(data["without_correction_mm"], float)[rows]
    with_ = np.asarray(data["with_correction_mm"], float)[rows]
    return float(np.sqrt(np.mean(without ** 2))), float(np.sqrt(np.mean(with_ ** 2)))
