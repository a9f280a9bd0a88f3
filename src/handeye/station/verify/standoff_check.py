"""``verify`` against the stand-off prediction of ``calibrate --kinematics`` (``SESSION/standoff.json``).

At every revisited posture the check sees the board: the camera in the board's frame is ``B^-1``
(``B`` the board in the camera, from the corners). The result the check compares against puts the
stand-off point ``p_c = (0, 0, L)`` of the camera at ``T^-1 A X p_c`` in the board's frame (``A`` the
flange the controller reports, ``X``, ``T`` the camera and board poses), the measurement at
``B^-1 p_c``. Their distance is the error of that point as the station runs (the camera-only result,
the controller's arm model: what the prediction calls "without correction"), plus the check's own
measurement noise (not in the prediction: small at the board's distances). Its RMS over the measured
postures is stated next to the prediction's RMS over the same postures, and called within it when it
is at most :data:`WITHIN_FACTOR` times the prediction (the band issue 36 holds a prediction to).
"""

from __future__ import annotations

import numpy as np

from ...geometry import invert_transforms
from ..standoff_file import predicted_at, read_prediction

__all__ = ["WITHIN_FACTOR", "measured_standoff_mm", "standoff_comparison", "standoff_line"]

#: A measured stand-off error up to this many times the predicted one is within the prediction.
WITHIN_FACTOR = 1.5


def measured_standoff_mm(x, target, flange, board_in_camera, standoff_mm: float) -> np.ndarray:
    """Distance (mm) per posture between where the result puts the stand-off point and where the check
    measured it, in the board's frame.

    Parameters
    ----------
    x, target : ndarray, shape (4, 4)
        Camera in tool0, board in base (the result compared against).
    flange : ndarray, shape (n, 4, 4)
        tool0 in base as the controller reported it.
    board_in_camera : ndarray, shape (n, 4, 4)
        The board as the check's camera saw it.
    """
    from ...calibration import flange_standoff_points

    seen = invert_transforms(np.asarray(board_in_camera, float))  # the camera in the board's frame
    measured = seen[:, :3, :3] @ np.array([0.0, 0.0, float(standoff_mm)]) + seen[:, :3, 3]
    return np.linalg.norm(flange_standoff_points(flange, x, target, standoff_mm) - measured, axis=1)


def standoff_comparison(session_dir, check_problem, baseline, numbers) -> dict | None:
    """The ``standoff`` entry of the check (None: SESSION has no current prediction, or the check is not
    eye-in-hand).

    ``check_problem``: the check's own session solved as a problem (its posture ``i`` is SESSION's
    ``numbers[i]``); ``baseline``: what the check compares against (``x``, ``target``).
    """
    from ...calibration import EYE_IN_HAND

    data = read_prediction(session_dir)
    if data is None or check_problem.setup != EYE_IN_HAND:
        return None
    ids = [int(i) for i in check_problem.posture_ids]
    revisited = [int(numbers[i]) for i in ids if 0 <= i < len(numbers)]
    predicted = predicted_at(data, revisited)
    if predicted is None or len(revisited) != len(ids):
        return None
    errors = measured_standoff_mm(baseline.x, baseline.target, check_problem.hand, check_problem.target2cam,
                                  data["standoff_mm"])
    measured = float(np.sqrt(np.mean(errors ** 2)))
    without, with_ = predicted
    return {"standoff_mm": float(data["standoff_mm"]), "postures": revisited,
            "measured_rms_mm": measured, "predicted_rms_mm": without, "predicted_with_correction_rms_mm": with_,
            "within_prediction": bool(measured <= WITHIN_FACTOR * without), "factor": WITHIN_FACTOR,
            "meaning": "error of a point at the stand-off along the camera axis, in the board's frame, at the "
                       "revisited postures: measured by the check against the result (camera-only, the "
                       "controller's arm model) and as calibrate --kinematics predicted it there without the "
                       "correction; within_prediction: measured at most factor times the prediction"}


def standoff_line(entry: dict | None) -> str | None:
    """The text line of the check's stand-off comparison."""
    if entry is None:
        return None
    words = "within the prediction" if entry["within_prediction"] else (
        f"beyond {entry['factor']:g} times the prediction: the station is further off at the stand-off than its "
        "calibration said")
    return (f"stand-off {entry['standoff_mm']:g} mm: measured {entry['measured_rms_mm']:.3f} mm RMS at the "
            f"{len(entry['postures'])} postures, predicted {entry['predicted_rms_mm']:.3f} mm "
            f"({entry['predicted_with_correction_rms_mm']:.3f} mm with the identified offsets entered): {words}")
