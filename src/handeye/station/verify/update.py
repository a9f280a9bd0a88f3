"""A check's quick update as a result ``handeye writeback`` writes like a calibration's.

The check's folder (``SESSION-verify-<time>``, written by ``handeye verify``) holds ``verify.json``;
when its diagnosis is a camera move, its ``quick_update`` (the new camera pose and its uncertainty) is
the result; its verdict is whether that uncertainty is within the quality thresholds.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...base import OutputError
from ...base import read_text_file
from ...calibration import EYE_IN_HAND
from ...calibration import CalibrationResult
from ...geometry import transform_from_pose
from .plan import VerifyError

__all__ = ["UPDATE_METHOD", "verify_check"]

#: The method name of a quick update (``writeback.yaml``, the history).
UPDATE_METHOD = "verify-quick-update"


def verify_check(folder) -> tuple[CalibrationResult, bool, str] | None:
    """``(result, passed, reason)`` of a check's folder, or None when ``folder`` is not a check.

    Raises
    ------
    VerifyError
        A check without a quick update (nothing to write: its diagnosis says why).
    """
    path = Path(folder) / "verify.json"
    if not path.is_file():
        return None
    try:
        data = json.loads(read_text_file(path, "check outcome", OutputError))
        update = data.get("quick_update")
        cause = data["diagnosis"]["cause"]
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise VerifyError(f"{path} is not a readable check outcome ({exc}); run handeye verify again") from None
    if update is None:
        raise VerifyError(f"{folder} is a check whose diagnosis is {cause!r} (verdict {data.get('verdict')}), not a camera "
                          "move: it has no quick update to write")
    pose = update["camera_pose"]
    x = transform_from_pose(pose["position_mm"], pose["quaternion_wxyz"])
    sigma = update["uncertainty"]
    result = CalibrationResult(UPDATE_METHOD, EYE_IN_HAND, x, {}, {}, [], 0.0,
                               details={"verify_of": data.get("session")}, uncertainty=sigma)
    reason = (f"one sigma {np.max(sigma['translation_mm']):.3f} mm / {np.max(sigma['rotation_deg']):.4f} deg: "
              + ("within the quality thresholds" if update["within_thresholds"] else
                 "above the quality thresholds: recapture (handeye capture) and calibrate"))
    return result, bool(update["within_thresholds"]), reason

