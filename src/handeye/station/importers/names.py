"""What names in a log say: which side a key or column belongs to, and which way a transform points.

Names are hints (declarations): they break ties the data leave, they never overrule the data.

- **Side.** A name whose words include ``robot``, ``tool0``, ``flange``, ``tcp``, ``ee``/``eef``,
  ``effector``, ``gripper``, ``hand``, ``arm``, ``wrist`` belongs to the robot; ``camera``/``cam``,
  ``target``, ``board``, ``marker``, ``tag``, ``object``, ``pattern``, ``chessboard``, ``tracking``
  to the camera (a name with both, like ``T_cam_target``, goes by its last word).
- **Direction.** ``a2b``, ``a_to_b`` and ``a_in_b`` name the pose of ``a`` in ``b``;
  ``T_a_b``, ``aMb`` and ``aPb`` (ROS's and ViSP's habit) the pose of ``b`` in ``a``. With ``a``
  and ``b`` among base / flange words (robot) or camera / target words (camera) this gives the
  direction of the poses: ``flange_in_base``, ``base_in_flange``, ``target_in_camera``,
  ``camera_in_target``.
"""

from __future__ import annotations

import re

__all__ = ["words_of", "side_of", "direction_of", "INDEX_NAMES", "STAMP_NAMES"]

BASE_WORDS = {"base", "world", "root", "robot_base", "baselink", "base_link", "b", "w", "r", "f"}
FLANGE_WORDS = {"tool0", "flange", "tcp", "ee", "eef", "effector", "endeffector", "end_effector", "gripper", "hand",
                "wrist", "tool", "e", "g", "h"}
CAMERA_WORDS = {"cam", "camera", "eye", "c", "sensor", "optical"}
TARGET_WORDS = {"target", "board", "marker", "tag", "object", "obj", "pattern", "chessboard", "checkerboard", "grid",
                "calib", "o", "t", "m"}
ROBOT_SIDE = {"robot", "tool0", "flange", "tcp", "ee", "eef", "effector", "endeffector", "gripper", "hand", "arm",
              "wrist", "fpe", "rpe", "bhe", "bme", "rme", "fme"}
CAMERA_SIDE = {"camera", "cam", "target", "board", "marker", "tag", "object", "pattern", "chessboard", "checkerboard",
               "tracking", "vision", "cpo", "cmo", "opc", "omc"}
#: Column names of a posture number and of a time stamp.
INDEX_NAMES = {"index", "idx", "id", "i", "n", "no", "nr", "num", "number", "#", "sample", "pose", "frame", "k",
               "posture", "step"}
STAMP_NAMES = {"t", "time", "stamp", "timestamp", "sec", "secs", "seconds", "time_s", "ts"}


def words_of(name) -> list:
    """Lower-case words of a key or column name (split at non-letters/digits and camelCase)."""
    text = re.sub(r"([a-z])([A-Z])", r"\1_\2", str(name))
    return [w for w in re.split(r"[^A-Za-z0-9]+", text.lower()) if w]


def side_of(names) -> str | None:
    """``robot``, ``camera`` or ``None`` from the words of one or more names (the last telling word wins)."""
    found = None
    for name in ([names] if isinstance(names, str) else names):
        for word in words_of(name):
            if word in ROBOT_SIDE:
                found = "robot"
            elif word in CAMERA_SIDE:
                found = "camera"
    return found


def _frame(word: str) -> str | None:
    if word in BASE_WORDS:
        return "base"
    if word in FLANGE_WORDS:
        return "flange"
    if word in CAMERA_WORDS:
        return "camera"
    if word in TARGET_WORDS:
        return "target"
    return None


#: ``(frame, in frame) -> direction``; a frame a name does not state (``None``) finds none.
_DIRECTIONS: dict[tuple[str | None, str | None], str] = {("flange", "base"): "flange_in_base", ("base", "flange"): "base_in_flange",
               ("target", "camera"): "target_in_camera", ("camera", "target"): "camera_in_target"}


def direction_of(name) -> str | None:
    """The pose direction a name states (module docstring), or ``None`` when it states none."""
    text = str(name)
    found = re.fullmatch(r"(?:pose_)?([a-z])([MP])([a-z])(?:_.*)?", text.split("/")[-1])  # ViSP: fPe, cMo
    if found:
        return _DIRECTIONS.get((_frame(found.group(3)), _frame(found.group(1))))
    words = words_of(text)
    for k, word in enumerate(words):
        if word in ("in", "to") and 0 < k < len(words) - 1:
            return _DIRECTIONS.get((_frame(words[k - 1]), _frame(words[k + 1])))
        pair = re.fullmatch(r"([a-z0-9]+?)2([a-z0-9]+)", word)
        if pair and _frame(pair.group(1)) and _frame(pair.group(2)):
            return _DIRECTIONS.get((_frame(pair.group(1)), _frame(pair.group(2))))
    if len(words) >= 3 and words[0] == "t":
        return _DIRECTIONS.get((_frame(words[2]), _frame(words[1])))
    return None
