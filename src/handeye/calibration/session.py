"""Capture sessions on disk, format ``handeye-session/1`` (see the conventions).

::

    SESSION/
      session.yaml
      postures/000.yaml, 001.yaml, ...     one file per posture, each written atomically
      images/000_left.png, ...             optional
      truth.yaml                           synthetic sessions only: the answer, for checks

Every write goes to a temporary file in the same folder, is flushed to disk and renamed over the
target, so an interrupted writer leaves either the old file or the new one, never half a file.
Reading validates every value and reports the first problem naming the posture and its file.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from ..geometry import BoardGeometry
from ..base import SessionError, brief
from ..base import make_folder, parse_yaml, read_text_file, write_failure, write_text_atomic, write_texts_atomic
from .problem import SETUPS
from ..geometry import pose_from_transform, transform_from_pose

if TYPE_CHECKING:
    from collections.abc import Iterable

__all__ = [
    "FORMAT",
    "Posture",
    "Session",
    "parse_yaml",
    "write_text_atomic",
    "write_yaml_atomic",
    "create_session",
    "write_posture",
    "write_postures",
    "read_session",
    "read_truth",
    "write_truth",
]

FORMAT = "handeye-session/1"
_POSTURE_KEYS = {"index", "tool0_in_base", "joints_deg", "points_mm", "corner_ids", "target_in_camera"}


@dataclass
class Posture:
    """One robot posture and what the camera measured there.

    Attributes
    ----------
    index : int
    tool0_in_base : ndarray, shape (4, 4) or None
        Authoritative flange pose (mm).
    joints_deg : ndarray, shape (6,) or None
        Controller axis angles.
    points_mm : ndarray, shape (m, 3) or None
        Board corners in the camera frame, target index order.
    target_in_camera : ndarray, shape (4, 4) or None
        Board pose ``target2cam``.
    corner_ids : ndarray of int, shape (m,) or None
        The target index of each row of ``points_mm`` when the view saw part of the board (a ChArUco
        board); ``None``: ``points_mm`` holds every corner in target index order.
    extra : dict
        Any other keys of the posture file (quality figures, image names), kept as they are.
    """

    index: int
    tool0_in_base: np.ndarray | None = None
    joints_deg: np.ndarray | None = None
    points_mm: np.ndarray | None = None
    target_in_camera: np.ndarray | None = None
    extra: dict = field(default_factory=dict)
    corner_ids: np.ndarray | None = None

    def to_dict(self) -> dict:
        out: dict = {"index": int(self.index)}
        if self.tool0_in_base is not None:
            out["tool0_in_base"] = _rounded_pose(self.tool0_in_base)
        if self.joints_deg is not None:
            out["joints_deg"] = [round(float(v), 9) for v in self.joints_deg]
        if self.points_mm is not None:
            out["points_mm"] = [[round(float(v), 6) for v in p] for p in np.asarray(self.points_mm)]
        if self.corner_ids is not None:
            out["corner_ids"] = [int(i) for i in self.corner_ids]
        if self.target_in_camera is not None:
            out["target_in_camera"] = _rounded_pose(self.target_in_camera)
        out.update(self.extra)
        return out


@dataclass
class Session:
    """A capture session: set-up, robot model, board and postures.

    Attributes
    ----------
    setup : str
        ``eye_in_hand`` or ``eye_to_hand``.
    robot : str or None
        Robot model name (joints -> tool0), e.g. ``IRB1400``.
    target : BoardGeometry or None
    postures : list of Posture
        Sorted by index.
    path : Path or None
    extra : dict
        Other keys of ``session.yaml``, kept as they are.
    """

    setup: str = "eye_in_hand"
    robot: str | None = None
    target: BoardGeometry | None = None
    postures: list = field(default_factory=list)
    path: Path | None = None
    extra: dict = field(default_factory=dict)

    def header(self) -> dict:
        out: dict = {"format": FORMAT, "setup": self.setup}
        if self.robot:
            out["robot"] = self.robot
        if self.target is not None:
            from ..geometry import target_to_dict  # noqa: PLC0415 (the target registry: checkerboard, charuco, circles)

            out["target"] = target_to_dict(self.target)
        out.update(self.extra)
        return out


def _rounded_pose(transform) -> dict:
    pose = pose_from_transform(transform)
    return {
        "position_mm": [round(v, 6) for v in pose["position_mm"]],
        "quaternion_wxyz": [round(v, 12) for v in pose["quaternion_wxyz"]],
    }


#: libyaml's emitter where it is installed: the same text as yaml.safe_dump, four times faster.
_SAFE_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def _yaml_text(data: dict) -> str:
    return yaml.dump(data, Dumper=_SAFE_DUMPER, sort_keys=False, default_flow_style=None, width=120)


def write_yaml_atomic(path: Path, data: dict) -> None:
    """Write ``data`` as YAML to ``path`` atomically (see :func:`write_text_atomic`)."""
    write_text_atomic(path, _yaml_text(data))


def create_session(path: str | Path, session: Session, overwrite: bool = False) -> Path:
    """Create ``path/session.yaml`` and ``path/postures/``.

    Raises
    ------
    SessionError
        If ``path`` already holds a session and ``overwrite`` is false (nothing is touched).
    OutputError
        The folder cannot be created or written (one line: the path, the reason, what to do).
    """
    path = Path(path)
    if (path / "session.yaml").exists() and not overwrite:
        raise SessionError(f"{path} already holds a session; choose another folder or pass --overwrite")
    if session.setup not in SETUPS:
        raise SessionError(f"setup must be one of {', '.join(SETUPS)}; got {brief(session.setup)}")
    if overwrite and (path / "postures").is_dir():
        for old in (path / "postures").glob("*.yaml"):
            try:
                old.unlink()
            except OSError as exc:
                raise write_failure(old, exc, "remove") from None
    make_folder(path / "postures")
    write_yaml_atomic(path / "session.yaml", session.header())
    session.path = path
    return path


def posture_file(path: str | Path, index: int) -> Path:
    return Path(path) / "postures" / f"{int(index):03d}.yaml"


def write_posture(path: str | Path, posture: Posture) -> Path:
    """Write one posture file atomically; returns its path."""
    target = posture_file(path, posture.index)
    write_yaml_atomic(target, posture.to_dict())
    return target


def write_postures(path: str | Path, postures: Iterable[Posture]) -> list:
    """Write many posture files, each atomically, with one flush to disk for all
    (``files.write_texts_atomic``); returns their paths."""
    return write_texts_atomic((posture_file(path, p.index), _yaml_text(p.to_dict())) for p in postures)


def _load_yaml(path: Path, what: str) -> dict:
    data = parse_yaml(read_text_file(path, what, SessionError), path)
    if not isinstance(data, dict):
        raise SessionError(f"{path} does not hold a YAML mapping")
    return data


#: Largest accepted length, mm (10 km): beyond it a value is a typing or unit error (or 1e300), not a
#: measurement; a metre file misread as mm still passes here and is left to the units checks.
MAX_LENGTH_MM = 1e7
#: The same limit in words, for messages.
MAX_LENGTH_WORDS = "±1e7 mm (10 km)"
#: Largest accepted joint angle, degrees (two turns: beyond any axis of an industrial robot).
MAX_JOINT_DEG = 720.0
#: Posture indices: the NNN of ``postures/NNN.yaml`` (three digits, four from 1000 on).
MAX_POSTURE_INDEX = 9999
#: Largest inner-corner count along one side of a board.
MAX_CORNERS = 1000


def _shape_of(value) -> str:
    if not isinstance(value, list):
        return "a string" if isinstance(value, str) else f"a {type(value).__name__}"
    shape = []
    while isinstance(value, list) and len(shape) < 8:
        shape.append(len(value))
        value = value[0] if value else None
    return " x ".join(map(str, shape))


def _nested_floats(value, shape_tail, what: str, want: str):
    """``value`` as nested lists of floats of the given shape, checked element by element (so that
    a shared YAML alias cannot make a huge array before the shape is refused)."""
    if not shape_tail:
        # PyYAML reads 1e-3 (no dot) as a string: numeric strings are numbers; bool, dates, None are not
        if type(value) not in (int, float, str):
            raise ValueError(f"{what} must have shape {want}; got a deeper nesting" if isinstance(value, (list, dict))
                             else f"{what} holds {brief(value)}, not a number")
        try:
            return float(value)
        except OverflowError:
            raise ValueError(f"{what} holds a number too large for a float") from None
        except ValueError:
            raise ValueError(f"{what} holds {brief(value)}, not a number") from None
    if not isinstance(value, list) or (shape_tail[0] is not None and len(value) != shape_tail[0]):
        raise ValueError(f"{what} must have shape {want}; got {_shape_of(value)}")
    return [_nested_floats(v, shape_tail[1:], what, want) for v in value]


def _array(value, shape_tail, what: str, limit: float | None = None, unit: str = "") -> np.ndarray:
    """A float array of shape ``shape_tail`` (``None`` = any length) from YAML lists of numbers.

    Raises
    ------
    ValueError
        Not numbers, a wrong shape, NaN or inf, or a value beyond ``limit`` (naming the key and index).
    """
    want = " x ".join("m" if s is None else str(s) for s in shape_tail)
    if not isinstance(value, list):
        raise ValueError(f"{what} must have shape {want}; got {_shape_of(value) if value is not None else 'nothing'}")
    arr = np.array(_nested_floats(value, tuple(shape_tail), what, want), dtype=float)
    if arr.ndim != len(shape_tail):  # an empty list of rows
        raise ValueError(f"{what} must have shape {want}; got {_shape_of(value)}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{what} holds {arr[tuple(bad)]} at {list(map(int, bad))}")
    if limit is not None and arr.size and np.max(np.abs(arr)) > limit:
        bad = np.unravel_index(np.argmax(np.abs(arr)), arr.shape)
        raise ValueError(f"{what} holds {arr[bad]:g} at {list(map(int, bad))}; {unit}")
    return arr


_LENGTH = f"lengths are millimetres within {MAX_LENGTH_WORDS}: is the unit right?"
_JOINT = f"joint angles are degrees within ±{MAX_JOINT_DEG:g}"


def _pose(value, what: str) -> np.ndarray:
    if not isinstance(value, dict) or "position_mm" not in value or "quaternion_wxyz" not in value:
        raise ValueError(f"{what} needs position_mm and quaternion_wxyz")
    position = _array(value["position_mm"], (3,), f"{what}.position_mm", MAX_LENGTH_MM, _LENGTH)
    quaternion = _array(value["quaternion_wxyz"], (4,), f"{what}.quaternion_wxyz")
    try:
        return transform_from_pose(position, quaternion)
    except ValueError as exc:
        raise ValueError(f"{what}: {exc}") from None


def _posture_index(data: dict, file_index: int | None) -> int:
    if "index" not in data and file_index is None:
        raise ValueError("no index, and the file name is not NNN.yaml; add 'index: N' (0..9999)")
    index = data.get("index", file_index)
    if not isinstance(index, int) or isinstance(index, bool):
        raise ValueError(f"index must be an integer; got {brief(index)}")
    if not 0 <= index <= MAX_POSTURE_INDEX:
        raise ValueError(f"index must be 0..{MAX_POSTURE_INDEX} (the NNN of postures/NNN.yaml); got {brief(index)}")
    return index


def _parse_posture(data: dict, file_index: int | None) -> Posture:
    index = _posture_index(data, file_index)
    posture = Posture(index=index, extra={k: v for k, v in data.items() if k not in _POSTURE_KEYS})
    if data.get("tool0_in_base") is not None:
        posture.tool0_in_base = _pose(data["tool0_in_base"], "tool0_in_base")
    if data.get("joints_deg") is not None:
        posture.joints_deg = _array(data["joints_deg"], (None,), "joints_deg", MAX_JOINT_DEG, _JOINT)
    if data.get("points_mm") is not None:
        posture.points_mm = _array(data["points_mm"], (None, 3), "points_mm", MAX_LENGTH_MM, _LENGTH)
    if data.get("corner_ids") is not None:
        posture.corner_ids = _corner_ids(data["corner_ids"], posture.points_mm)
    if data.get("target_in_camera") is not None:
        posture.target_in_camera = _pose(data["target_in_camera"], "target_in_camera")
    if posture.tool0_in_base is None and posture.joints_deg is None:
        raise ValueError("holds neither tool0_in_base nor joints_deg")
    if posture.points_mm is None and posture.target_in_camera is None:
        raise ValueError("holds neither points_mm nor target_in_camera")
    return posture


def _corner_ids(value, points) -> np.ndarray:
    """Corner ids of a partial view: distinct whole numbers >= 0, one per row of ``points_mm``."""
    if (not isinstance(value, list) or not all(type(i) is int and 0 <= i < MAX_CORNERS**2 for i in value)
            or len(set(value)) != len(value)):
        raise ValueError(f"corner_ids must be distinct whole numbers >= 0 (target indices); got {brief(value)}")
    if points is None or len(points) != len(value):
        raise ValueError(f"corner_ids has {len(value)} ids but points_mm {0 if points is None else len(points)} rows; "
                         "give one id per point")
    return np.array(value, dtype=int)


def _parse_target(value) -> BoardGeometry | None:
    if value is None:
        return None
    if isinstance(value, dict) and value.get("type", "checkerboard") != "checkerboard":
        from ..geometry import target_from_dict  # noqa: PLC0415 (a ChArUco board or a circle grid: issue 37)

        try:
            return target_from_dict(value)
        except ValueError as exc:
            raise SessionError(f"session.yaml: target: {exc}") from None
    if not isinstance(value, dict) or "corners" not in value:
        raise SessionError("session.yaml: target needs corners: [along x, along y]")
    corners = value["corners"]
    if (not isinstance(corners, (list, tuple)) or len(corners) != 2
            or not all(isinstance(c, int) and not isinstance(c, bool) and 2 <= c <= MAX_CORNERS for c in corners)):
        raise SessionError(f"session.yaml: target.corners must be two integers 2..{MAX_CORNERS}; got {brief(corners)}")
    square = value.get("square_mm")
    if square is not None:
        if not isinstance(square, (int, float)) or isinstance(square, bool) or not 0 < square <= MAX_LENGTH_MM:
            raise SessionError(f"session.yaml: target.square_mm must be a positive number of mm within "
                               f"{MAX_LENGTH_WORDS}; got {brief(square)}")
        square = float(square)
    return BoardGeometry((int(corners[0]), int(corners[1])), square)


def read_session(path: str | Path) -> Session:
    """Read and validate a session folder.

    Raises
    ------
    SessionError
        With a one-line message naming the file (and posture) at fault.
    """
    path = Path(path)
    if not path.is_dir():
        raise SessionError(f"no session folder at {path}")
    header = _load_yaml(path / "session.yaml", "session file")
    fmt = header.get("format")
    if fmt != FORMAT:
        raise SessionError(f"{path / 'session.yaml'}: format must be {FORMAT!r}; got {brief(fmt)}")
    setup = header.get("setup", "eye_in_hand")
    if setup not in SETUPS:
        raise SessionError(f"{path / 'session.yaml'}: setup must be one of {', '.join(SETUPS)}; got {brief(setup)}")
    robot = header.get("robot")
    if robot is not None and (not isinstance(robot, str) or not robot.strip()):
        raise SessionError(f"{path / 'session.yaml'}: robot must be a model name like IRB1400; got {brief(robot)}")
    target = _parse_target(header.get("target"))
    extra = {k: v for k, v in header.items() if k not in {"format", "setup", "robot", "target"}}
    folder = path / "postures"
    if folder.exists() and not folder.is_dir():
        raise SessionError(f"{folder} is a file; the postures belong in a folder of NNN.yaml files")
    postures = []
    seen: dict[int, Path] = {}
    for file in sorted(folder.glob("*.yaml")):
        stem = file.stem
        file_index = int(stem) if stem.isascii() and stem.isdigit() else None
        data = _load_yaml(file, "posture file")
        try:
            posture = _parse_posture(data, file_index)
        except ValueError as exc:
            index = data.get("index", file_index)
            where = file.relative_to(path)
            if type(index) is int and 0 <= index <= MAX_POSTURE_INDEX:
                where = f"posture {index} ({where})"
            raise SessionError(f"{where}: {exc}") from None
        if posture.index in seen:
            raise SessionError(f"posture {posture.index} appears twice: {seen[posture.index].name} and {file.name}")
        seen[posture.index] = file
        postures.append(posture)
    postures.sort(key=lambda p: p.index)
    return Session(setup=setup, robot=robot, target=target, postures=postures, path=path, extra=extra)


def write_truth(path: str | Path, truth: dict) -> None:
    """Write ``truth.yaml`` beside a synthetic session (the answer, for checks and ``mcy``)."""
    write_yaml_atomic(Path(path) / "truth.yaml", truth)


def read_truth(path: str | Path) -> dict | None:
    """The synthetic truth of a session, or ``None`` when the session has none."""
    file = Path(path) / "truth.yaml"
    if not file.exists():
        return None
    return _load_yaml(file, "truth file")
