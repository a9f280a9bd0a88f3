"""What a calibration tool's own JSON/YAML log says beside its inputs: frame names and its own result.

- **Frame names** (string values and keys: ``"T camera to tool0"``, ``"base"``, ``"tool0"``,
  ``"attached on robot"``, ``eye_on_hand: true``) are hints for the set-up: a camera named with
  the flange (``tool0``, ``flange``, ``ee``, ``gripper``, ``hand``, "on robot", "in hand") says
  eye-in-hand, a camera named with the base or the world ("on base", "fixed", "to hand") says
  eye-to-hand. A hint is a declaration: it breaks ties the data leave, never overrules them.
- **The tool's own result**: a single pose (a 4x4 or 3x4 matrix, or a position with a rotation)
  outside the per-posture lists, preferably under a name such as ``result``, ``calibration``,
  ``hand_eye`` or ``camera to tool0``. It is never an input: ``handeye import`` solves the session
  and prints how far the log's own answer is from its own (``compare_result``).
"""

from __future__ import annotations

import re

import numpy as np

from ...geometry import invert_transforms

__all__ = ["frame_hints", "own_result", "compare_result"]

_FLANGE = {"tool0", "flange", "ee", "eef", "effector", "gripper", "hand", "tcp", "wrist", "tool"}
_FIXED = {"base", "world", "root", "fixed", "stand", "tripod"}
_CAMERA = {"camera", "cam", "eye", "sensor", "optical"}
_RESULT = {"result", "results", "calibration", "calibrated", "handeye", "hand", "x", "extrinsic", "extrinsics",
           "transform", "estimate", "estimated", "solution", "output", "t"}


def _words(text) -> list:
    text = re.sub(r"([a-z])([A-Z])", r"\1_\2", str(text))
    return [w for w in re.split(r"[^A-Za-z0-9]+", text.lower()) if w]


def _strings(document, depth: int = 0):
    """Every key and string value of a document, with the key it sits under."""
    if depth > 40:
        return
    if isinstance(document, dict):
        for key, value in document.items():
            yield str(key), value if isinstance(value, (str, bool)) else None
            yield from _strings(value, depth + 1)
    elif isinstance(document, list):
        for value in document[:2000]:
            yield from _strings(value, depth + 1)
    elif isinstance(document, str):
        yield "", document


def _setup_of_text(key: str, value) -> str | None:
    words = _words(key) + (_words(value) if isinstance(value, str) else [])
    text = " ".join(words)
    generic = re.sub(r"\bhand eye\b|\bhandeye\b", " ", text)  # "hand-eye" names the problem, not a frame
    words = generic.split()
    if isinstance(value, bool) and "eye" in _words(key):
        hand = "hand" in _words(key) or "robot" in _words(key)
        base = "base" in _words(key) or "world" in _words(key)
        if hand != base:
            return "eye_in_hand" if hand == value else "eye_to_hand"
    if re.search(r"\b(attached on robot|on robot|in hand|on hand|eye in hand|eye on hand)\b", text):
        return "eye_in_hand"
    if re.search(r"\b(eye to hand|eye on base|on base|fixed camera|static camera|on a tripod)\b", text):
        return "eye_to_hand"
    if any(w in _CAMERA for w in words):
        if any(w in _FLANGE for w in words):
            return "eye_in_hand"
        if any(w in _FIXED for w in words):
            return "eye_to_hand"
    return None


def frame_hints(document) -> tuple[str | None, list]:
    """``(set-up the names say or None, the names that said it)``; ``None`` when they disagree."""
    found = {}
    for key, value in _strings(document):
        setup = _setup_of_text(key, value)
        if setup:
            found.setdefault(setup, []).append(f"{key}: {value}" if isinstance(value, (str, bool)) and key else
                                               str(value if value is not None else key))
    if len(found) != 1:
        return None, []
    setup, names = next(iter(found.items()))
    return setup, names[:3]


def _direction_of_name(path: str) -> bool | None:
    """``True``: the matrix maps camera coordinates to the mount frame (camera in flange/base); ``False``:
    the inverse; ``None``: the name does not say."""
    words = _words(path)
    for k, w in enumerate(words):
        if w in ("to", "in") and 0 < k < len(words) - 1:
            a, b = words[k - 1], words[k + 1]
            if a in _CAMERA and (b in _FLANGE or b in _FIXED):
                return True
            if b in _CAMERA and (a in _FLANGE or a in _FIXED):
                return False
        pair = re.fullmatch(r"([a-z0-9]+?)2([a-z0-9]+)", w)
        if pair:
            a, b = pair.groups()
            if a in _CAMERA:
                return True
            if b in _CAMERA:
                return False
    return None


def own_result(leaves: list, lists: set) -> dict | None:
    """The tool's own result among the leaves outside the pose lists (module docstring), or ``None``.

    Parameters
    ----------
    leaves : list of log_tree.Leaf
    lists : set of signatures
        The signatures of the per-posture lists (not results).
    """
    singles = {}
    for leaf in leaves:
        singles.setdefault(leaf.signature, []).append(leaf)
    found = [g[0] for s, g in singles.items() if len(g) == 1 and s not in lists and len(g[0].values) in (12, 16)]
    named = [leaf for leaf in found if set(_words(leaf.path)) & _RESULT]
    pick = named if named else found
    if len(pick) != 1:
        return None
    leaf = pick[0]
    m = np.eye(4)
    m[:3, :] = np.asarray(leaf.values[:12], float).reshape(3, 4)
    gram = m[:3, :3] @ m[:3, :3].T
    if not np.allclose(gram, np.eye(3), atol=1e-3) or np.linalg.det(m[:3, :3]) < 0:
        return None
    return {"path": leaf.path, "matrix": m.tolist(), "camera_to_mount": _direction_of_name(leaf.path)}


def compare_result(result: dict, x_mm: np.ndarray, unit_factor: float) -> str:
    """One line: how far the log's own answer is from ours (mm, deg), in the direction its name says
    (or, when it says none, the closer of the two, said so)."""
    theirs = np.array(result["matrix"], float)
    theirs[:3, 3] *= unit_factor
    options = {True: theirs, False: invert_transforms(theirs)}
    direction = result.get("camera_to_mount")
    gaps = {}
    for key, m in options.items():
        turn = np.clip((np.trace(m[:3, :3].T @ x_mm[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)
        gaps[key] = (float(np.linalg.norm(m[:3, 3] - x_mm[:3, 3])), float(np.degrees(np.arccos(turn))))
    key = direction if direction is not None else min(gaps, key=lambda k: gaps[k][0] + 10.0 * gaps[k][1])
    how = "as its name says" if direction is not None else "read in the closer of its two directions"
    mm, deg = gaps[key]
    return (f"the log's own answer ({result['path']}, {how}) differs from ours by {mm:.1f} mm, {deg:.2f} deg "
            f"(a comparison only: it is not used as input)")
