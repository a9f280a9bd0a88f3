"""Plain CSV or JSON of flange pose + board pose, one posture per row / item: the layout to write
from any tool (a RAPID log, a spreadsheet, a script around OpenCV or easy_handeye).

CSV (``.csv``): a header row naming the columns, then one row per posture::

    index,tool0_x,tool0_y,tool0_z,tool0_qw,tool0_qx,tool0_qy,tool0_qz,target_x,target_y,target_z,target_qw,target_qx,target_qy,target_qz
    0,812.4,-120.3,903.1,0.0123,0.7071,0.7069,0.0101,-35.2,12.8,904.5,0.9990,0.0100,-0.0400,0.0050

- ``tool0_*``: the flange in the robot base (``tool0_in_base``); ``target_*``: the board in the
  camera frame (``target_in_camera``).
- Quaternion columns named ``qw, qx, qy, qz`` fix their meaning by name; columns named
  ``q1 .. q4`` follow ``quaternion_order`` (default ``wxyz``, ABB's q1..q4).
- ``index`` is optional (kept as the posture's source label); other columns are ignored (listed).
- Lines starting with ``#`` are comments. Separator: comma (semicolon and tab are recognised).

JSON (``.json``)::

    {"setup": "eye_in_hand", "units": "mm", "quaternion_order": "wxyz",      all optional
     "target": {"corners": [13, 8], "square_mm": 30.0},                       optional
     "postures": [
       {"tool0_in_base": {"position": [x, y, z], "quaternion": [w, x, y, z]},
        "target_in_camera": {"matrix": [[r11, r12, r13, tx], ..., [0, 0, 0, 1]]}},
       ...]}

A pose is ``{"position", "quaternion"}`` or ``{"matrix"}`` (4x4, row-major). A top-level list is
read as the ``postures`` list. Units: ``units`` (option or JSON key) else detected from the values.
Set-up: option, else the JSON's ``setup``, else detected from the data, else ``eye_in_hand``.
"""

from __future__ import annotations

import csv

import numpy as np

from ...geometry import BoardGeometry
from ...base import SessionError, brief
from ...calibration import SETUPS
from ...calibration import MAX_CORNERS, MAX_LENGTH_MM, Session
from .head import check_log_head, read_head
from .common import (
    QUATERNION_ORDERS,
    quaternion_side,
    UNITS,
    Dropped,
    EntryErrors,
    build_session,
    check_quaternion_order,
    parse_json,
    read_text,
    rigid_transform,
    transform_from_quaternion,
)

__all__ = ["FORMAT", "DEFAULT_SETUP", "CSV_COLUMNS", "read_plain", "read_plain_csv", "read_plain_json",
           "looks_like_plain_csv", "looks_like_plain_json"]

FORMAT = "plain"
DEFAULT_SETUP = "eye_in_hand"
PARTS = ("tool0", "target")
#: The full column list of the CSV layout, quaternions named by component.
CSV_COLUMNS = ["index"] + [f"{part}_{c}" for part in PARTS for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]


def looks_like_plain_csv(head: str) -> bool:
    lines = [ln for ln in head.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    return bool(lines) and "tool0_x" in lines[0].replace(" ", "").lower() and "target_x" in lines[0].replace(" ", "").lower()


def looks_like_plain_json(head: str) -> bool:
    start = head.lstrip()
    return (start.startswith("{") and '"postures"' in head) or (start.startswith("[") and '"tool0_in_base"' in head)


def _quaternion_columns(names: set, part: str, order: str):
    named = [f"{part}_q{c}" for c in "wxyz"]
    numbered = [f"{part}_q{k}" for k in "1234"]
    if all(n in names for n in named):
        return named, "wxyz", True
    if all(n in names for n in numbered):
        return numbered, order, False
    missing = [n for n in named if n not in names]
    raise SessionError(f"header lacks {', '.join(missing)} (or {part}_q1..{part}_q4)")


def _csv_columns(names: list, quaternion_order: str | None, where: str) -> dict:
    """``{part: (position columns, quaternion columns, order, named)}`` of a header, or a one-line error."""
    name_set = set(names)
    try:
        columns = {}
        for part in PARTS:
            position = [f"{part}_{c}" for c in "xyz"]
            missing = [n for n in position if n not in name_set]
            if missing:
                raise SessionError(f"header lacks {', '.join(missing)}")
            quaternion, order, named = _quaternion_columns(name_set, part, quaternion_order or "wxyz")
            columns[part] = ([names.index(n) for n in position], [names.index(n) for n in quaternion], order, named)
    except SessionError as exc:
        raise SessionError(f"{where}: {exc} (columns: {','.join(CSV_COLUMNS)})") from None
    return columns


#: A plain CSV row (header or posture) is far shorter than this; a longer line is not a table row.
MAX_LINE_BYTES = 64 * 1024


def _check_header_from_head(path) -> None:
    """Refuse, from the file's first :data:`MAX_LINE_BYTES` only, a file whose first row is longer than
    a row can be or holds no column name (issue 42.8: a 60 MB single line took 14 s and 2 GB to refuse)."""
    head = read_head(path, MAX_LINE_BYTES)
    check_log_head(path, head, MAX_LINE_BYTES)
    number = 0
    for number, raw in enumerate(head.split(b"\n"), start=1):
        line = raw.decode("utf-8", errors="replace")
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if len(head) >= MAX_LINE_BYTES and number == len(head.split(b"\n")):
            raise SessionError(f"{path}: line {number} is longer than {MAX_LINE_BYTES // 1024} KB: not a row of a "
                               f"table; give the plain CSV (a header row, then one row per posture)")
        names = line.replace(";", ",").replace("\t", ",").split(",")
        if all(_number(n.strip()) is not None for n in names):
            raise SessionError(f"{path}: line {number}: expected a header row naming the columns, e.g. "
                               f"{','.join(CSV_COLUMNS)}")
        return


def read_plain_csv(path, *, setup=None, units=None, board=None, skip_invalid: bool = False,
                   quaternion_order: str | None = None, robot_pose=None, camera_pose=None) -> Session:
    """Read the plain CSV layout (module docstring) into a session (mm).

    Raises
    ------
    SessionError
        Naming the file and line at fault.
    """
    if quaternion_order is not None:
        check_quaternion_order(quaternion_order)
    _check_header_from_head(path)
    text = read_text(path)
    lines = [(k, ln) for k, ln in enumerate(text.splitlines(), start=1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise SessionError(f"{path}: empty (expected a header row and one row per posture)")
    header_line, header = lines[0]
    try:
        dialect = csv.Sniffer().sniff(header, delimiters=",;\t")
        delimiter = dialect.delimiter
    except csv.Error:
        delimiter = ","
    names = [n.strip().lower() for n in next(csv.reader([header], delimiter=delimiter))]
    if all(_number(n) is not None for n in names):
        raise SessionError(f"{path}: line {header_line}: expected a header row naming the columns, e.g. {','.join(CSV_COLUMNS)}")
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise SessionError(f"{path}: line {header_line}: column {duplicates[0]!r} appears twice")
    name_set = set(names)
    columns = _csv_columns(names, quaternion_order, f"{path}: line {header_line}")
    used = {i for part in columns.values() for group in part[:2] for i in group}
    raw = {part: ([], []) for part in PARTS}
    index_col = names.index("index") if "index" in name_set else None
    ignored = [n for i, n in enumerate(names) if i not in used and i != index_col]
    dropped = Dropped()
    errors = EntryErrors(path, skip_invalid, dropped)
    labels = []
    rows = 0
    for number, line in lines[1:]:
        rows += 1
        fields = next(csv.reader([line], delimiter=delimiter))
        label = f"line {number}"
        if len(fields) != len(names):
            errors.bad(label, f"{len(fields)} values for {len(names)} columns")
            continue
        values = [_number(f) for f in fields]
        bad = [names[i] for i in used if values[i] is None]
        if bad:
            errors.bad(label, f"{bad[0]} is not a number ({fields[names.index(bad[0])].strip()!r})")
            continue
        poses = []
        for part in PARTS:
            pos_cols, quat_cols, order, _ = columns[part]
            try:
                transform_from_quaternion([values[i] for i in pos_cols], [values[i] for i in quat_cols], order)
            except ValueError as exc:
                errors.bad(label, f"{part} pose: {exc}")
                break
            poses.append(([values[i] for i in pos_cols], [values[i] for i in quat_cols]))
        if len(poses) != 2:
            continue
        for part, (position, quaternion) in zip(PARTS, poses):
            raw[part][0].append(position)
            raw[part][1].append(quaternion)
        labels.append(label + (f" (index {fields[index_col].strip()})" if index_col is not None else ""))
    notes = [f"columns ignored: {', '.join(ignored)}"] if ignored else []
    sides = [quaternion_side(name, raw[part][0], raw[part][1], "wxyz" if not columns[part][3] else columns[part][2],
                             quaternion_order, direction, named=columns[part][3])
             for name, part, direction in (("robot", "tool0", "flange_in_base"), ("camera", "target", "target_in_camera"))]
    return build_session(FORMAT, path, sides[0], sides[1], labels,
                         setup=setup, default_setup=DEFAULT_SETUP, units=units, documented_units=None, board=board,
                         dropped=dropped, entries_read=rows, notes=notes, robot_pose=robot_pose,
                         camera_pose=camera_pose,
                         conventions_given=f"--quaternion-order {quaternion_order}" if quaternion_order else None)


def _number(text: str):
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value


def _json_pose(value, order: str) -> np.ndarray:
    if not isinstance(value, dict):
        raise ValueError("must be an object with position + quaternion, or matrix")
    if "matrix" in value:
        return rigid_transform(value["matrix"])
    if "position" in value and "quaternion" in value:
        try:
            p = np.asarray(value["position"], dtype=float)
            q = np.asarray(value["quaternion"], dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise ValueError("position and quaternion must be lists of numbers") from None
        return transform_from_quaternion(p, q, order)
    raise ValueError(f"needs position + quaternion, or matrix; has {', '.join(map(brief, sorted(value))) or 'nothing'}")


def _json_board(value, path) -> BoardGeometry | None:
    if value is None:
        return None
    corners = value.get("corners") if isinstance(value, dict) else None
    square = value.get("square_mm") if isinstance(value, dict) else None
    if (not isinstance(corners, list) or len(corners) != 2
            or not all(isinstance(c, int) and not isinstance(c, bool) and 2 <= c <= MAX_CORNERS for c in corners)):
        raise SessionError(f"{path}: target.corners must be two integers 2..{MAX_CORNERS}, e.g. [13, 8]")
    if square is not None and (not isinstance(square, (int, float)) or isinstance(square, bool)
                               or not 0 < square <= MAX_LENGTH_MM):
        raise SessionError(f"{path}: target.square_mm must be a positive number of mm (within 10 km)")
    return BoardGeometry((int(corners[0]), int(corners[1])), None if square is None else float(square))


def read_plain_json(path, *, setup=None, units=None, board=None, skip_invalid: bool = False,
                    quaternion_order: str | None = None, robot_pose=None, camera_pose=None) -> Session:
    """Read the plain JSON layout (module docstring) into a session (mm).

    Options given here win over the file's own ``setup``, ``units`` and ``quaternion_order``.

    Raises
    ------
    SessionError
    """
    text = read_text(path)
    data = parse_json(text, path)
    if isinstance(data, list):
        data = {"postures": data}
    if not isinstance(data, dict) or not isinstance(data.get("postures"), list):
        raise SessionError(f"{path}: expected an object with a 'postures' list (or a list of postures)")
    declared_setup = data.get("setup")
    if declared_setup is not None and declared_setup not in SETUPS:
        raise SessionError(f"{path}: setup must be one of {', '.join(SETUPS)}; got {brief(declared_setup)}")
    file_units = data.get("units")
    if file_units is not None and file_units not in UNITS:
        raise SessionError(f"{path}: units must be 'm' or 'mm'; got {brief(file_units)}")
    order = quaternion_order or data.get("quaternion_order", "wxyz")
    if order not in QUATERNION_ORDERS:
        raise SessionError(f"{path}: quaternion_order must be 'wxyz' or 'xyzw'; got {brief(order)}")
    if board is None:
        board = _json_board(data.get("target"), path)
    dropped = Dropped()
    errors = EntryErrors(path, skip_invalid, dropped)
    robot, camera, labels = [], [], []
    for k, item in enumerate(data["postures"]):
        label = f"postures[{k}]"
        if not isinstance(item, dict):
            errors.bad(label, "must be an object with tool0_in_base and target_in_camera")
            continue
        poses = []
        for key in ("tool0_in_base", "target_in_camera"):
            if key not in item:
                errors.bad(label, f"lacks {key}")
                break
            try:
                poses.append(_json_pose(item[key], order))
            except ValueError as exc:
                errors.bad(label, f"{key} {exc}")
                break
        if len(poses) != 2:
            continue
        robot.append(poses[0])
        camera.append(poses[1])
        labels.append(label + (f" (index {item['index']})" if "index" in item else ""))
    return build_session(FORMAT, path, np.array(robot).reshape(-1, 4, 4), np.array(camera).reshape(-1, 4, 4), labels,
                         setup=setup, declared_setup=declared_setup, default_setup=DEFAULT_SETUP,
                         units=units or file_units, documented_units=None, board=board, dropped=dropped,
                         entries_read=len(data["postures"]), robot_pose=robot_pose, camera_pose=camera_pose,
                         robot_words=f"position + quaternion ({', '.join(order)}) or 4x4 matrix",
                         camera_words=f"position + quaternion ({', '.join(order)}) or 4x4 matrix")


def read_plain(path, **options) -> Session:
    """:func:`read_plain_json` for ``.json`` files, :func:`read_plain_csv` otherwise."""
    from pathlib import Path

    if Path(path).suffix.lower() == ".json":
        return read_plain_json(path, **options)
    if options.get("quaternion_order") is None:
        options.pop("quaternion_order", None)
    return read_plain_csv(path, **options)
