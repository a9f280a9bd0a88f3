"""Any hand-eye log, read as it was written: the numbers found by content, their meaning by the data.

What is read (``FORMATS.md`` has examples):

- **Text tables** (CSV, TSV, semicolons, spaces; a header or none; ``#`` comments): one posture
  per row, the robot pose then the camera pose (a header naming the camera columns first swaps
  them), optionally after a posture number and/or a time stamp; or the robot poses and the camera
  poses in two blocks (separated by a text line, e.g. ``# camera``) or in two files (the file
  whose name says ``camera``/``target``/``marker`` holds the camera poses; else the order given);
  or 4x4 (3x4) matrices written over 4 (3) lines, in pairs or in two blocks.
- **JSON and YAML** of any nesting: the pose arrays are found wherever they are
  (``log_tree.find_poses``) and fall into two groups of the same postures, robot and camera.
- **A pose** is 16 or 12 numbers (matrix, row- or column-major), 7 (position + quaternion, wxyz or
  xyzw, either first) or 6 (position + rotation vector, or Euler angles in any of the 24
  conventions in degrees or radians, or OpenCV's rvec + tvec).

Nothing about the meaning is assumed: every reading the numbers allow (``conventions``) is scored
by ``inference``, which decides the rotation conventions, which pose sets are inverted, the set-up
and the units from the X-free invariants of ``AX = XB`` and plausibility, or refuses naming the
flag that decides. Names are hints that break ties: column names (``qw``, ``a b c``,
``roll pitch yaw``), keys (``T_base_eef``, ``target_in_camera``, ``fPe``), file names.
``euler`` (``--euler``) and ``quaternion_order`` restrict the readings, ``robot_pose``,
``camera_pose``, ``setup`` and ``units`` fix the rest.
"""

from __future__ import annotations

import itertools
from dataclasses import replace
from pathlib import Path

import numpy as np

from ...base import SessionError, SessionUsageError, brief
from ...calibration import Session
from ...base import parse_yaml
from .common import QUATERNION_ORDERS, Dropped, build_session, check_posture_count, parse_json, read_text
from .conventions import POSE_WIDTHS, PoseConvention, conventions_for_width, parse_rotation_spec, vendor_units
from .inference import Side, SideReading
from .readings import GAP_MAX_DEG, Constraints, screen, side_units
from .layout_choice import Candidate, choose_layout
from .layout_search import one_side_lists, propose
from .layout_text import tokenise
from .log_folder import FolderPlan, parse_document, plan_folder
from .log_group import Group
from .log_result import frame_hints, own_result
from .log_text import Table, matrices_from_rows, parse_table
from .log_tree import conventions_of, find_poses
from .names import INDEX_NAMES, STAMP_NAMES, direction_of, side_of, words_of

__all__ = ["FORMAT", "read_log", "looks_like_log"]

FORMAT = "log"
_TREE_SUFFIXES = (".json", ".yaml", ".yml")


# --------------------------------------------------------------------------- detection


def looks_like_log(path, head: str) -> bool:
    """A JSON/YAML document, or text with rows of pose numbers (6 to 38 numbers, or matrix rows of 4)."""
    start = head.lstrip()
    if Path(path).suffix.lower() in _TREE_SUFFIXES or start[:1] in ("{", "["):
        return True
    table = parse_table(head)
    if any(len(r.values) >= 6 for r in table.rows) or sum(len(r.values) == 4 for r in table.rows) >= 6:
        return True
    rows = tokenise(head)  # tagged rows (``hand: 1 2 3 ...``), count lines, image rows
    return sum(len(r.values) >= 6 for r in rows) >= 2 or sum(len(r.values) == 4 for r in rows) >= 6


# --------------------------------------------------------------------------- files -> groups


def _is_tree(path: Path, text: str) -> bool:
    start = text.lstrip()
    if start[:1] in ("{", "["):
        return True
    if path.suffix.lower() in _TREE_SUFFIXES:
        return True
    table = parse_table(text)
    return not table.rows and any(":" in line for line in text.splitlines()
                                  if not line.lstrip().startswith(_COMMENT_STARTS))


#: Lines starting so are comments (a header naming the columns, ``# P: X Y Z A B C``), never YAML keys.
_COMMENT_STARTS = ("#", "//", "%")


_document = parse_document


def _tree_groups(path: Path, text: str) -> list:
    """``[(robot group, camera group)]`` or ``[group]`` (one side) from a JSON/YAML document."""
    document = _document(path, text)
    try:
        leaves = find_poses(document)
    except ValueError as exc:
        raise SessionError(f"{path}: {exc}") from None
    if not leaves:
        raise SessionError(f"{path}: no pose found (a pose is 6, 7, 12 or 16 numbers, a 4x4 matrix, or a position "
                           f"with a rotation)")
    groups: dict = {}
    for leaf in leaves:
        groups.setdefault(leaf.signature, []).append(leaf)
    widths = {}
    for signature, members in groups.items():
        widths[signature] = {len(m.values) for m in members}
        if len(widths[signature]) != 1:
            raise SessionError(f"{path}: the poses at {members[0].path} and their like hold different numbers of values "
                               f"({', '.join(map(str, sorted(widths[signature])))})")
    ordered = sorted(groups.values(), key=len, reverse=True)
    if len(ordered) == 1:
        return [_group_of(path, ordered[0])]
    if len(ordered) > 2 and len(ordered[1]) == len(ordered[2]):
        where = ", ".join(g[0].path for g in ordered[:3])
        raise SessionError(f"{path}: poses in more than two places ({where}, ...): cannot tell which are the robot's and "
                           f"the camera's; keep the two pose lists only")
    a, b = _group_of(path, ordered[0]), _group_of(path, ordered[1])
    first = min((ordered[0][0], ordered[1][0]), key=leaves.index)
    if first is not ordered[0][0]:
        a, b = b, a
    return [_assign(a, b, [ordered[0][0].names, ordered[1][0].names] if first is ordered[0][0]
                    else [ordered[1][0].names, ordered[0][0].names])]


def _group_of(path: Path, leaves: list) -> Group:
    names = [n for n in leaves[0].names]
    direction = next((d for d in (direction_of(n) for n in reversed(names)) if d), None)
    conventions = conventions_of(leaves)
    keys = [leaf.index for leaf in leaves] if all(leaf.index for leaf in leaves) else None
    if keys is not None and len(set(keys)) != len(keys):
        keys = None
    return Group(np.array([leaf.values for leaf in leaves], dtype=float), [f"{path.name}: {leaf.path}" for leaf in leaves],
                 names, conventions, [], direction, keys)


def _assign(first: Group, second: Group, names: list) -> tuple:
    """(robot, camera) of two groups: by their names when they say, else in order."""
    sides = [side_of(n) if n else None for n in names]
    sides = [s or _side_from_direction(g.direction) for s, g in zip(sides, (first, second))]
    if sides[0] == "camera" or sides[1] == "robot":
        return second, first
    return first, second


def _side_from_direction(direction: str | None) -> str | None:
    if direction in ("flange_in_base", "base_in_flange"):
        return "robot"
    if direction in ("target_in_camera", "camera_in_target"):
        return "camera"
    return None


def _header_hints(names: list, width: int) -> tuple[list | None, list]:
    """``(fixed conventions or None, declared conventions)`` from a side's column names."""
    last = [words_of(n)[-1] if words_of(n) else "" for n in names]
    tail = lambda k: [w[-1:] if len(w) <= 2 or w.startswith("q") else w for w in last[-k:]]  # noqa: E731
    if width == 7:
        letters = "".join(w[-1] for w in last[-4:] if w)
        head = "".join(w[-1] for w in last[:4] if w)
        for order in QUATERNION_ORDERS:
            if letters == order and all(len(w) <= 2 for w in last[-4:]):
                return [PoseConvention("quaternion", order, width=7)], []
            if head == order and all(len(w) <= 2 for w in last[:4]):
                return [PoseConvention("quaternion", order, rotation_first=True, width=7)], []
        if [w[-1:] for w in last[-4:]] == list("1234"):
            return None, [PoseConvention("quaternion", "wxyz", width=7)]
    if width == 6:
        rotation = tail(3)
        if rotation == ["a", "b", "c"]:
            return None, [PoseConvention("euler", sequence="ZYX", degrees=True)]
        if rotation == ["w", "p", "r"]:
            return None, [PoseConvention("euler", sequence="xyz", degrees=True)]
        if rotation == ["roll", "pitch", "yaw"]:
            return None, [PoseConvention("euler", sequence="xyz", degrees=d) for d in (True, False)]
    return None, []


def _index_like(column: np.ndarray) -> bool:
    """Posture numbers or time stamps: finite and increasing (numbers: whole)."""
    return len(column) >= 2 and bool(np.all(np.isfinite(column))) and bool(np.all(np.diff(column) > 0))


def _skips(table_values: np.ndarray, header: list | None) -> list:
    """How many leading columns are posture numbers / stamps (0, 1 or 2), most likely first."""
    named = 0
    if header:
        for name in header[:2]:
            words = words_of(name)
            if words and (words[0] in INDEX_NAMES or words[0] in STAMP_NAMES or name.strip() in INDEX_NAMES):
                named += 1
            else:
                break
        return [named]
    out = [0]
    for k in (1, 2):
        if table_values.shape[1] > k and all(_index_like(table_values[:, j]) for j in range(k)):
            out.insert(0 if k == 1 else 1, k)
    return out


def _table_groups(path: Path, text: str) -> list:
    """Alternatives: ``[(robot, camera), ...]`` pairings, or ``[group, ...]`` one-side readings."""
    table = parse_table(text)
    if not table.rows:
        raise SessionError(f"{path}: no rows of numbers found (a pose is 6, 7, 12 or 16 numbers)")
    rows = table.rows
    if table.widths == {4}:
        return _matrix_groups(path, table)
    two = _two_blocks(path, table)
    if two is not None:
        return [two]
    widths = sorted(table.widths, key=lambda w: -sum(len(r.values) == w for r in rows))
    width = widths[0]
    main = [r for r in rows if len(r.values) == width]
    values = np.array([r.values for r in main], dtype=float)
    header = table.header if table.header and len(table.header) == width else None
    blocks = [[r for r in b if len(r.values) == width] for b in table.blocks()]
    blocks = [b for b in blocks if b]
    out = []
    for skip in _skips(values, header):
        rest = width - skip
        if len(blocks) == 2 and rest in POSE_WIDTHS and len(blocks[0]) == len(blocks[1]):
            a = _rows_group(path, blocks[0], skip, header, table.labels.get(blocks[0][0].block))
            b = _rows_group(path, blocks[1], skip, header, table.labels.get(blocks[1][0].block))
            out.append(_assign(a, b, [table.labels.get(blocks[0][0].block), table.labels.get(blocks[1][0].block)]))
            continue
        for wr in POSE_WIDTHS:
            if rest - wr in POSE_WIDTHS:
                out.append(_split_rows(path, main, skip, wr, header))
        if rest in POSE_WIDTHS and len(blocks) != 2:
            out.append(_rows_group(path, main, skip, header, table.labels.get(main[0].block)))
    if not out:
        raise SessionError(
            f"{path}: rows of {width} numbers are neither one pose (6, 7, 12 or 16 numbers, after a posture number or "
            f"time stamp) nor a robot pose and a camera pose side by side")
    return out


def _two_blocks(path: Path, table: Table):
    """``(robot, camera)`` when the rows form two blocks of one pose per row and the same length, else ``None``."""
    blocks = table.blocks()
    if len(blocks) != 2 or len(blocks[0]) != len(blocks[1]) or len(blocks[0]) < 2:
        return None
    groups, labels = [], []
    for block in blocks:
        width = len(block[0].values)
        label = table.labels.get(block[0].block)
        names = _names_for(label, width)
        values = np.array([r.values for r in block], dtype=float)
        skips = [k for k in _skips(values, names) if width - k in POSE_WIDTHS]
        if not skips:
            return None
        groups.append(_rows_group(path, block, skips[0], names, label))
        labels.append(label)
    return _assign(groups[0], groups[1], labels)


def _names_for(label: str | None, width: int) -> list | None:
    """The column names a text line gives a block of ``width`` numbers (``None`` when it gives none)."""
    if not label:
        return None
    names = [n for n in label.strip().lstrip("#%/").replace(",", " ").replace(";", " ").replace("\t", " ").split()]
    return names if len(names) == width else None


def _rows_group(path: Path, rows: list, skip: int, header, label) -> Group:
    values = np.array([r.values[skip:] for r in rows], dtype=float)
    names = list(header[skip:]) if header else []
    fixed, declared = _header_hints(names, values.shape[1]) if names else (None, [])
    keys = [tuple(r.values[:1]) for r in rows] if skip else None
    direction = direction_of(label.strip("# :")) if label else None
    return Group(values, [f"{path.name}: line {r.line}" for r in rows], [label] if label else names, fixed, declared,
                 direction, keys if keys and len(set(keys)) == len(keys) else None)


def _split_rows(path: Path, rows: list, skip: int, robot_width: int, header) -> tuple:
    values = np.array([r.values for r in rows], dtype=float)
    labels = [f"{path.name}: line {r.line}" for r in rows]
    parts = []
    for lo, hi in ((skip, skip + robot_width), (skip + robot_width, values.shape[1])):
        names = list(header[lo:hi]) if header else []
        fixed, declared = _header_hints(names, hi - lo) if names else (None, [])
        parts.append(Group(values[:, lo:hi], labels, names, fixed, declared, None, None))
    if header:
        return _assign(parts[0], parts[1], [parts[0].names, parts[1].names])
    return parts[0], parts[1]


def _matrix_groups(path: Path, table: Table) -> list:
    matrices = matrices_from_rows(table.rows)
    if not matrices:
        raise SessionError(f"{path}: rows of 4 numbers that do not group into 4x4 (or 3x4) matrices")
    by_key: dict = {}
    for m in matrices:
        by_key.setdefault(m[2], []).append(m)
    blocks = list(by_key.values())

    def group(items, label=None):
        return Group(np.array([m[1] for m in items], dtype=float), [f"{path.name}: line {m[0]}" for m in items],
                     [label] if label else [], None, [], direction_of(label.strip("# :")) if label else None, None)

    if len(blocks) == 2 and len(blocks[0]) == len(blocks[1]) and len(blocks[0]) > 1:
        labels = [table.labels.get(b[0][2]) for b in blocks]
        return [_assign(group(blocks[0], labels[0]), group(blocks[1], labels[1]), labels)]
    if all(len(b) == 2 for b in blocks) or (len(blocks) == 1 and len(matrices) % 2 == 0):
        return [(group(matrices[0::2]), group(matrices[1::2]))]
    if len(blocks) == 1:
        return [group(matrices, table.labels.get(blocks[0][0][2]))]
    raise SessionError(f"{path}: {len(matrices)} matrices in {len(blocks)} blocks: expected pairs (robot, camera), two "
                       f"blocks of the same length, or one block per file")


def _file_alternatives(path: Path) -> list:
    text = read_text(path)
    if _is_tree(path, text):
        return _tree_groups(path, text)
    return _table_groups(path, text)


# --------------------------------------------------------------------------- groups -> sides


def _rotation_flags(euler) -> dict:
    """``{"robot": {width: [conventions]}, "camera": {...}}`` from ``--euler`` values."""
    specs = [euler] if isinstance(euler, str) else list(euler or [])
    out: dict = {"robot": {}, "camera": {}}
    for spec in specs:
        for part in str(spec).split(","):
            part = part.strip()
            if not part:
                continue
            side, _, value = part.partition("=") if "=" in part else part.partition(":") if part.split(":")[0].lower() in (
                "robot", "camera") else ("", "", part)
            sides = [side.strip().lower()] if side else ["robot", "camera"]
            try:
                allowed = parse_rotation_spec(value.strip())
            except ValueError as exc:
                raise SessionUsageError(str(exc)) from None
            for s in sides:
                for width, conventions in allowed.items():
                    out[s].setdefault(width, []).extend(conventions)
    return out


def _invalid_reason(values: np.ndarray) -> str:
    width = len(values)
    if not np.all(np.isfinite(values)):
        return "holds NaN or inf"
    if width == 7:
        return (f"no unit quaternion among its numbers (norms {np.linalg.norm(values[3:]):.4g} after the position, "
                f"{np.linalg.norm(values[:4]):.4g} before it)")
    if width in (12, 16):
        return "no rotation matrix (not orthonormal, a reflection, or a bottom row other than 0 0 0 1)"
    return "rotation numbers beyond two full turns"


def _readings_of(group: Group) -> tuple[list, np.ndarray]:
    """Every reading the group's width (or structure) allows, with its poses and valid rows, and the
    rows at least one reading can read."""
    conventions = group.conventions or conventions_for_width(group.width)
    results = [(c, *c.transforms(group.values)) for c in conventions]
    readable = np.zeros(len(group.values), bool)
    for _, _, valid in results:
        readable |= valid
    return results, readable


def _build_sides(groups: tuple, options: dict, dropped: Dropped, skip_invalid: bool, path) -> tuple:
    """(robot Side, camera Side, labels) of a pairing; rows no reading can read are refused or dropped."""
    robot, camera = groups
    flags = _rotation_flags(options.get("euler"))
    order = options.get("quaternion_order")
    per_side, readable = {}, np.ones(len(robot.values), bool)
    for name, group in (("robot", robot), ("camera", camera)):
        per_side[name], ok = _readings_of(group)
        for k in np.flatnonzero(readable & ~ok):
            reason = f"the {name} pose {_invalid_reason(group.values[k])}"
            if not skip_invalid:
                raise SessionError(f"{path}: {group.labels[k].split(': ', 1)[-1]}: {reason} (fix it, or pass "
                                   f"--skip-invalid to drop such entries)")
            dropped.add(f"invalid: {reason.split(' (')[0]}", group.labels[k])
        readable &= ok
    if readable.sum() == 0:
        raise SessionError(f"{path}: no readable pose pair")
    sides = []
    for name, group in (("robot", robot), ("camera", camera)):
        readings = []
        for convention, poses, valid in per_side[name]:
            if not np.all(valid[readable]):
                continue
            allowed = convention in flags[name].get(group.width, [convention])
            if group.width == 7 and order is not None:
                allowed = allowed and convention.layout == order
            readings.append(SideReading(convention.key, convention.describe(), convention.short(), poses[readable],
                                        declared=convention in group.declared, allowed=allowed))
        if not readings:
            raise SessionError(f"{path}: the {name} poses have no reading valid for every posture")
        unit = next((vendor_units(v) for v in _flag_values(options.get("euler"), name) if vendor_units(v)), None)
        sides.append(Side(name, readings, group.direction, unit))
    labels = [label for label, ok in zip(robot.labels, readable) if ok]
    return sides[0], sides[1], labels


def _flag_values(euler, side: str) -> list:
    specs = [euler] if isinstance(euler, str) else list(euler or [])
    out = []
    for spec in specs:
        for part in str(spec).split(","):
            head, sep, value = part.partition(":") if ":" in part and part.split(":")[0].lower() in ("robot", "camera") \
                else part.partition("=")
            if sep and head.strip().lower() in ("robot", "camera"):
                if head.strip().lower() == side:
                    out.append(value.strip())
            else:
                out.append(part.strip())
    return out


def _paired(robot: Group, camera: Group, path) -> tuple:
    """The two groups restricted to the postures they share (by posture number when both have one)."""
    if robot.keys is not None and camera.keys is not None:
        robot_at, camera_at = _first_places(robot.keys), _first_places(camera.keys)  # as list.index, in O(n)
        common = [k for k in robot.keys if k in camera_at]
        if len(common) < len(robot.keys) or len(common) < len(camera.keys):
            ri = [robot_at[k] for k in common]
            ci = [camera_at[k] for k in common]
            return _take(robot, ri), _take(camera, ci), len(robot.keys) + len(camera.keys) - 2 * len(common)
        ci = [camera_at[k] for k in robot.keys]
        return robot, _take(camera, ci), 0
    if len(robot.values) != len(camera.values):
        raise SessionError(f"{path}: {len(robot.values)} robot poses but {len(camera.values)} camera poses: pair them "
                           f"posture by posture (time-stamped streams: --format stream)")
    return robot, camera, 0


def _first_places(keys: list) -> dict:
    """``{key: index of its first occurrence}``."""
    places = {}
    for k, key in enumerate(keys):
        places.setdefault(key, k)
    return places


def _take(group: Group, index: list) -> Group:
    return replace(group, values=group.values[index], labels=[group.labels[k] for k in index],
                   keys=[group.keys[k] for k in index] if group.keys is not None else None)


# --------------------------------------------------------------------------- the reader


def _sources(paths) -> tuple[list, FolderPlan | None]:
    """``(files, folder plan or None)``: the one or two files to read (a folder's side files), or the folder
    itself when it holds one file per posture (``log_folder.plan_folder``)."""
    if isinstance(paths, (str, Path)):
        paths = [paths]
    paths = [Path(p) for p in paths]
    plan = None
    if len(paths) == 1 and paths[0].is_dir():
        plan = plan_folder(paths[0])
        if plan is None:
            files = [p for p in paths[0].iterdir() if p.is_file() and not p.name.startswith(".")]
            raise SessionError(f"{paths[0]}: a folder of {len(files)} files, none (or more than two) holding a list of "
                               f"poses and no set of per-posture files; give the log file (or the robot and the "
                               f"camera file)")
        if plan.posture_files:
            return [paths[0]], plan
        paths = plan.side_files
    if len(paths) not in (1, 2):
        raise SessionError(f"a log is one file (robot and camera poses) or two (robot poses, camera poses); got {len(paths)}")
    for p in paths:
        if not p.exists():
            raise SessionError(f"{p}: no such file")
    return paths, plan


def read_log(paths, *, setup=None, units=None, board=None, skip_invalid: bool = False, robot_pose=None,
             camera_pose=None, euler=None, quaternion_order=None, robot_rows=None) -> Session:
    """Read a hand-eye log of unknown convention and layout into a session (mm); the module docstring says how.

    Parameters
    ----------
    paths : path, folder or list of one or two paths
        One file holding both sides, or the robot file and the camera file (in either order).
    setup, units, robot_pose, camera_pose : str, optional
        Force the set-up, the unit (``m``/``mm``), what the robot poses are (``flange_in_base``,
        ``base_in_flange``) and what the camera poses are (``target_in_camera``, ``camera_in_target``).
    board : BoardGeometry, optional
    skip_invalid : bool
        Drop postures whose numbers no reading can read (reported) instead of stopping at the first.
    euler : str or list of str, optional
        Rotation convention of 6-number poses: an Euler sequence (``ZYX`` rotating, ``xyz`` static,
        ``:deg``/``:rad``), ``rotvec``, ``rvec-tvec`` or a vendor (``kuka``, ``fanuc``, ``ur``, ``ros``,
        ``abb``, ``visp``, ``opencv``); ``robot:SPEC`` / ``camera:SPEC`` for one side.
    quaternion_order : str, optional
        ``wxyz`` or ``xyzw`` for 7-number poses.
    robot_rows : str, optional
        Which list holds the robot poses: a tag (``hand``), a key or file name, or ``first`` /
        ``second`` (in the file's order); the layout search keeps only the readings that agree.

    Raises
    ------
    SessionError
        One line: unreadable file, no poses, unpaired poses, or data that do not decide the reading
        or the layout (naming the flag that does).
    """
    if quaternion_order is not None and quaternion_order not in QUATERNION_ORDERS:
        raise SessionError(f"quaternion order must be wxyz or xyzw; got {brief(quaternion_order)}")
    files, plan = _sources(paths)
    if plan is not None and plan.posture_files:
        pairings = _tree_candidates(files[0], plan.document())
    else:
        pairings = _one_file_pairings(files[0]) if len(files) == 1 else _two_file_pairings(files)
    session = _read_pairings(pairings, files, options_of(euler, quaternion_order), skip_invalid, robot_rows,
                             dict(setup=setup, units=units, board=board, robot_pose=robot_pose,
                                  camera_pose=camera_pose))
    note = plan.note() if plan is not None else None
    if note:
        session.extra["import"].setdefault("notes", []).append(note)
    return session


def options_of(euler, quaternion_order) -> tuple[dict, str | None]:
    """``({euler, quaternion_order}, the flags in words or None)``."""
    given = " ".join([f"--euler {e}" for e in ([euler] if isinstance(euler, str) else euler or [])]
                     + ([f"--quaternion-order {quaternion_order}"] if quaternion_order else [])) or None
    return {"euler": euler, "quaternion_order": quaternion_order}, given


def _read_pairings(pairings: list, files: list, options_given: tuple, skip_invalid: bool, robot_rows, flags: dict):
    """The session of the best pairing (the table reader's layouts first, the search's where they read nothing)."""
    options, given = options_given
    flags = dict(flags, given=given)
    if not pairings:
        raise SessionError(f"{files[0]}: no two lists of poses of the same postures found (a robot list and a camera "
                           f"list); give the log file (or the robot and the camera file)")
    if robot_rows is not None:
        pairings = [c for c in pairings if c.matches(robot_rows)]
        if not pairings:
            raise SessionUsageError(f"--robot-rows {robot_rows}: no list of poses in {files[0]} is named or placed so")
    source = str(files[0]) if len(files) == 1 else [str(f) for f in files]
    results, errors = [], []
    documented = [c for c in pairings if c.documented]
    if documented and len(files) == 1:  # the table reader's layouts first: the search only where they read nothing
        partners = {c.swap for c in documented if c.swap is not None}
        first = documented + [c for c in pairings if not c.documented and c.swap in partners]
        results, errors = _read_candidates(first, files[0], source, options, skip_invalid, flags, len(pairings) > 1)
        if results or any(stage == 1 for stage, _ in errors):
            if not results:
                raise max(errors, key=lambda e: e[0])[1]
            return choose_layout(results, files[0])
        pairings = [c for c in pairings if all(c is not f for f in first)]
    more, errors_more = _read_candidates(pairings, files[0], source, options, skip_invalid, flags, len(pairings) > 1)
    results, errors = results + more, errors + errors_more
    if not results:  # the error of the layout that got furthest (read, then refused by the inference)
        raise max(errors, key=lambda e: e[0])[1]
    return choose_layout(results, files[0])


def _read_candidates(pairings: list, path: Path, source, options: dict, skip_invalid: bool, flags: dict,
                     screen_out: bool) -> tuple[list, list]:
    """``(candidates read, [(stage, error)])``, cheapest first; once one reads, only readings as cheap follow."""
    results, errors = [], []
    for candidate in pairings:  # cheapest first; once one reads, only readings as cheap follow
        if results and candidate.cost > min(c.cost for c in results):
            break
        try:
            candidate.session = _session_of(candidate, path, source, options, skip_invalid, flags, screen_out=screen_out)
            results.append(candidate)
        except SessionError as exc:
            errors.append((candidate.stage, exc))
    return results, errors


def _one_file_pairings(path: Path) -> list:
    """Every (robot, camera) pairing one file allows: the table and tree readers', then the layout search's."""
    text = read_text(path)
    found, first_error = [], None
    try:
        alternatives = _file_alternatives(path)
    except SessionError as exc:
        alternatives, first_error = [], exc
    tree = _is_tree(path, text)
    if tree:
        try:
            found = _tree_candidates(path, text)
        except SessionError:  # ``robot: 1, 2, ...`` lines look like YAML but are a tagged table
            if _declared_tree(path, text) or not tokenise(text):
                raise
            tree = False
        if not found and not _declared_tree(path, text):  # a text YAML reads as strings: read it as text
            tree = False
    for a in alternatives if not found else []:
        if isinstance(a, tuple):
            found.append(Candidate(a[0], a[1], "one posture per row or block (the table reader's layout)", "", "", 0,
                                   documented=True))
    if not tree:
        for p in propose(text, path.name):
            for k, (robot, camera, name) in enumerate(p.sides()):
                other = p.second_name if robot is p.first else p.first_name
                found.append(Candidate(robot, camera, p.words, name, other, p.cost, robot is p.first,
                                       swap=id(p) if len(p.sides()) == 2 else None))
    found = _distinct(found)
    if not found:
        if first_error is not None and "one list" not in str(first_error):
            raise first_error
        raise SessionError(f"{path}: one list of poses only; give the robot poses and the camera poses (two "
                           f"blocks, two lists, two tags, or two files)")
    return found


def _declared_tree(path: Path, text: str) -> bool:
    """The file says it is JSON/YAML: by its suffix, or a first character opening a list or a mapping."""
    return path.suffix.lower() in _TREE_SUFFIXES or text.lstrip()[:1] in ("{", "[")


def _tree_candidates(path: Path, text) -> list:
    """Every pair of equally long pose lists of a JSON/YAML document (its text, or the parsed document), the
    names deciding the sides when they say (else both orders), each carrying the document's frame-name
    hints and the tool's own result."""
    document = _document(path, text) if isinstance(text, str) else text
    try:
        leaves = find_poses(document)
    except ValueError as exc:
        raise SessionError(f"{path}: {exc}") from None
    groups: dict = {}
    for leaf in leaves:
        groups.setdefault(leaf.signature, []).append(leaf)
    lists = [g for g in groups.values() if len(g) >= 3 and len({len(m.values) for m in g}) == 1]
    setup, said = frame_hints(document)
    result = own_result(leaves, {g[0].signature for g in lists})
    extra = {"declared_setup": setup, "setup_names": said, "log_result": result}
    out = []
    for ga, gb in itertools.combinations(lists, 2):
        if len(ga) != len(gb):
            continue
        a, b = _group_of(path, ga), _group_of(path, gb)
        names = [side_of(list(ga[0].names)) or _side_from_direction(a.direction),
                 side_of(list(gb[0].names)) or _side_from_direction(b.direction)]
        words = f"the lists at {ga[0].path} and {gb[0].path} (and their like)"
        na, nb = ".".join(ga[0].names), ".".join(gb[0].names)
        if names[0] == "camera" or names[1] == "robot":
            out.append(Candidate(b, a, words, nb, na, 0, False, extra=extra))
        elif names[0] == "robot" or names[1] == "camera":
            out.append(Candidate(a, b, words, na, nb, 0, True, extra=extra))
        else:
            swap = len(out) + 1
            out.append(Candidate(a, b, words, na, nb, 0, True, swap=swap, documented=True, extra=extra))
            out.append(Candidate(b, a, words, nb, na, 0, False, swap=swap, extra=extra))
    return out


def _two_file_pairings(files: list) -> list:
    """Pairings of a robot file and a camera file: the names decide the order, else both orders are scored."""
    lists = []
    for f in files:
        found = [(a, "one pose per row") for a in _file_alternatives_safe(f) if not isinstance(a, tuple)]
        if not _is_tree(f, read_text(f)):
            found += one_side_lists(read_text(f), f.name)
        if not found:
            raise SessionError(f"{f}: holds robot and camera poses both, or none; give it alone")
        lists.append([(replace(g, direction=g.direction or direction_of(f.stem)), words) for g, words in found])
    names = [side_of(words_of(f.stem)) or _side_from_direction(direction_of(f.stem)) for f in files]
    out = []
    for (a, wa), (b, wb) in itertools.product(*lists):
        words = f"one file per side: {files[0].name} ({wa}), {files[1].name} ({wb})"
        if names[0] == "camera" or names[1] == "robot":
            out.append(Candidate(b, a, words, files[1].stem, files[0].stem, 0, False))
        elif names[0] == "robot" or names[1] == "camera":
            out.append(Candidate(a, b, words, files[0].stem, files[1].stem, 0, True))
        else:
            swap = object()
            out.append(Candidate(a, b, words, files[0].stem, files[1].stem, 0, True, swap=id(swap)))
            out.append(Candidate(b, a, words, files[1].stem, files[0].stem, 0, False, swap=id(swap)))
    return _distinct(out)


def _file_alternatives_safe(path: Path) -> list:
    try:
        return _file_alternatives(path)
    except SessionError:
        return []


def _distinct(candidates: list) -> list:
    """The candidates without repeats (the same numbers on the same sides), cheapest first."""
    seen, out = {}, []
    for c in sorted(candidates, key=lambda c: c.cost):
        key = (c.robot.values.shape, c.robot.values.tobytes(), c.camera.values.shape, c.camera.values.tobytes())
        if key not in seen:
            seen[key] = c
            out.append(c)
        elif c.swap is not None and seen[key].swap is None:
            seen[key].swap = c.swap  # the documented reading joins the pair the content decides between
    return out


def _hopeless(robot: Side, camera: Side, n: int) -> bool:
    """No pair of readings passes the inference's first screen (the X-free angle gap): a decoy pairing
    (joint angles, a result matrix) is dropped before the full fit, which would refuse it anyway."""
    units = side_units(robot, camera, Constraints(), [])
    gaps, _ = screen(robot, camera, units, n)
    return bool(gaps.size) and bool(np.nanmin(gaps) > GAP_MAX_DEG) if np.any(np.isfinite(gaps)) else False


def _session_of(candidate: Candidate, path: Path, source, options: dict, skip_invalid: bool, flags: dict,
                screen_out: bool = False) -> Session:
    """The session one pairing gives (``build_session`` with every reading of its numbers); ``screen_out``
    drops a pairing no reading can fit before the full inference (when other pairings compete)."""
    candidate.stage = 0
    robot, camera, unpaired = _paired(candidate.robot, candidate.camera, path)
    check_posture_count(path, len(robot.values), FORMAT)  # before the readings multiply the poses
    dropped = Dropped()
    for _ in range(unpaired):
        dropped.add("pose without a partner of the same posture number", "")
    robot_side, camera_side, labels = _build_sides((robot, camera), options, dropped, skip_invalid, path)
    if screen_out and _hopeless(robot_side, camera_side, len(robot.values)):
        raise SessionError(f"{path}: {candidate.words}: no reading of these lists fits AX = XB (angle gap over "
                           f"{GAP_MAX_DEG:g} deg)")
    candidate.stage = 1
    details = {"layout": {"robot_numbers": robot.width, "camera_numbers": camera.width, "reading": candidate.words}}
    extra = candidate.extra or {}
    if extra.get("log_result"):
        details["log_result"] = extra["log_result"]
    notes = [f"the frame names say {extra['declared_setup']} ({'; '.join(extra['setup_names'])}): a hint for "
             f"ties"] if extra.get("declared_setup") else []
    return build_session(FORMAT, source, robot_side, camera_side, labels, setup=flags["setup"], default_setup=None,
                         declared_setup=extra.get("declared_setup"), notes=notes,
                         units=flags["units"], documented_units=None, board=flags["board"], dropped=dropped,
                         entries_read=len(robot.values), details=details, robot_pose=flags["robot_pose"],
                         camera_pose=flags["camera_pose"], robot_declared=robot.direction,
                         camera_declared=camera.direction, conventions_given=flags["given"])
