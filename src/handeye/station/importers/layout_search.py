"""Readings of a text log's layout: which numbers form the robot poses and which the camera poses.

The text is tokenised (``layout_text``) into rows with tags and positions, and every grouping the
rows allow is proposed (:func:`propose`), each with its reading in words:

- **per tag**: rows grouped by their leading word or letter (``hand``/``eye``, ``robot:``/``camera:``,
  in any case, alternating or in blocks); a tag's rows of 4 numbers form matrices (three rows: 3x4,
  four ending ``0 0 0 1``: 4x4), so that ``P x y z a b c`` followed by three ``C`` rows reads as a
  6-number robot pose and a 3x4 camera matrix; two tags with as many poses make a pairing;
- **per block**: matrices written over 3-4 rows, with or without blank lines, in sections split by
  text or count lines: two sections of the same length, or 2-3 matrices per posture taken in every
  order (a decoy such as the tool's result matrix is one section, or one matrix more, left out);
- **per row**: a row holding a robot pose and a camera pose side by side after 0-3 leading columns,
  with extra columns after them (joints, errors) left out; the robot pose first, as the table
  format documents (a header naming the camera first is the table reader's to read);
- **per image row** (camera-calibration output: ``image7.png fx 0 cx 0 fy cy 0 0 1 r11 .. r33 tx ty tz
  k1 ..``): the nine columns that are a rotation in every row (orthonormal, det +1) and the three
  beside them as the translation (:func:`rotation_windows`, one side only; the other comes from
  another file).

A proposal only says which numbers go together; ``log.read_log`` scores every proposal that yields
two equally long lists of valid poses by the convention inference (its X-free invariants) and keeps
the best, or refuses when two differ and fit within the noise.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .conventions import POSE_WIDTHS, PoseConvention
from .layout_text import tokenise
from .log_group import Group
from .names import direction_of, side_of

__all__ = ["Proposal", "propose", "one_side_lists", "rotation_windows", "MAX_PROPOSALS"]

#: At most this many pairings are scored (the cheapest readings, fewest columns left out, first).
MAX_PROPOSALS = 24
_ORTHO_TOL = 5e-3
_MATRIX_ROWS = (3, 4)


@dataclass
class Proposal:
    """A pairing of two lists: ``first`` and ``second`` in file order, with names when the text has them."""

    words: str
    first: Group
    second: Group
    first_name: str = ""
    second_name: str = ""
    cost: int = 0
    robot_first: bool = False

    def sides(self) -> list:
        """``[(robot, camera, robot name)]``: the order the names say, else both orders."""
        a, b = side_of(self.first_name) if self.first_name else None, side_of(self.second_name) if self.second_name else None
        if a == "camera" or b == "robot":
            return [(self.second, self.first, self.second_name)]
        if a == "robot" or b == "camera" or self.robot_first:
            return [(self.first, self.second, self.first_name)]
        return [(self.first, self.second, self.first_name), (self.second, self.first, self.second_name)]


def _group(rows: list, values, path_name: str, name: str = "", conventions=None, words: str = "") -> Group:
    keys = [r.key for r in rows]
    keys = keys if all(k is not None for k in keys) and len(set(keys)) == len(keys) else None
    names = [name] if name else []
    return Group(np.asarray(values, float), [f"{path_name}: line {r.line}" for r in rows], names, conventions, [],
                 direction_of(name) if name else None, keys)


def _clumps(rows: list, position: dict) -> list:
    """Rows split where another row (or a blank line) comes between them in the file."""
    out = []
    for r in rows:
        if out and position[r.line] == position[out[-1][-1].line] + 1 and r.run == out[-1][-1].run:
            out[-1].append(r)
        else:
            out.append([r])
    return out


def _matrices(rows: list, position: dict) -> list | None:
    """``[(first row, 12 or 16 values)]`` from rows of 4 numbers, or ``None`` when they do not group."""
    out = []
    for clump in _clumps(rows, position):
        k = 0
        while k < len(clump):
            four = clump[k:k + 4]
            if len(four) == 4 and np.allclose(four[3].values, (0, 0, 0, 1), atol=1e-6):
                out.append((four[0], sum((r.values for r in four[:3]), ())))
                k += 4
            elif len(clump) - k >= 3:
                out.append((clump[k], sum((r.values for r in clump[k:k + 3]), ())))
                k += 3
            else:
                return None
    return out


def is_rotation(blocks: np.ndarray, tol: float = _ORTHO_TOL) -> np.ndarray:
    """Which ``(n, 3, 3)`` blocks are rotations (orthonormal within ``tol``, det +1)."""
    gram = np.einsum("nij,nkj->nik", blocks, blocks)
    ortho = np.max(np.abs(gram - np.eye(3)), axis=(1, 2)) < tol
    return ortho & (np.linalg.det(blocks) > 0.5)


def rotation_windows(values: np.ndarray) -> list:
    """Readings of wide rows holding a rotation matrix and a translation among other numbers.

    Parameters
    ----------
    values : ndarray, shape (n, w)

    Returns
    -------
    list of (poses (n, 16) row-major 4x4, words)
        For every offset where nine columns are a rotation in every row (row-major as written, and
        its transpose), with the three columns after (or else before) them as the translation.
    """
    n, w = values.shape
    out = []
    for o in range(0, w - 8):
        block = values[:, o:o + 9].reshape(n, 3, 3)
        if not np.all(is_rotation(block)) or np.allclose(block, np.eye(3), atol=1e-9):
            continue
        for lo in (o + 9, o - 3):
            if lo < 0 or lo + 3 > w:
                continue
            t = values[:, lo:lo + 3]
            if np.all(np.abs(t) < 1e-9):
                continue
            for transposed in (False, True):
                r = np.transpose(block, (0, 2, 1)) if transposed else block
                m = np.tile(np.eye(4), (n, 1, 1))
                m[:, :3, :3], m[:, :3, 3] = r, t
                words = (f"columns {o + 1}-{o + 9} read as a rotation matrix ({'column' if transposed else 'row'}-major), "
                         f"{lo + 1}-{lo + 3} as the translation; the other {w - 12} columns skipped")
                out.append((m.reshape(n, 16), words))
            break
    return out


def _lists_of_rows(rows: list, position: dict, path_name: str, name: str) -> list:
    """Every one-side list a set of rows can be: ``[(Group, words, cost)]``."""
    widths = {len(r.values) for r in rows}
    if len(widths) != 1 or len(rows) < 3:
        return []
    w = widths.pop()
    values = np.array([r.values for r in rows], float)
    out = []
    if w in POSE_WIDTHS:
        out.append((_group(rows, values, path_name, name), f"one {w}-number pose per row", 0))
    if w - 1 in POSE_WIDTHS and np.all(np.diff(values[:, 0]) > 0):
        g = _group(rows, values[:, 1:], path_name, name)
        g.keys = g.keys or [float(v) for v in values[:, 0]]
        out.append((g, f"a posture number then one {w - 1}-number pose per row", 1))
    if w == 4:
        mats = _matrices(rows, position)
        if mats:
            out.append((_group([m[0] for m in mats], [m[1] for m in mats], path_name, name),
                        "a matrix over 3-4 rows", 0))
    if w > 12 and w not in POSE_WIDTHS:
        for poses, words in rotation_windows(values):
            out.append((_group(rows, poses, path_name, name, [PoseConvention("matrix", "row", width=16)]), words, 2))
    return out


def _per_tag(rows: list, position: dict, path_name: str) -> list:
    tags = list(dict.fromkeys(r.tag for r in rows))
    if len(tags) < 2:
        return []
    lists = []
    for tag in tags:
        for key, name, members in _under_headers([r for r in rows if r.tag == tag], tag):
            for group, words, cost in _lists_of_rows(members, position, path_name, name):
                lists.append((key, name, group, words, cost))
    out = []
    for (ka, ta, a, wa, ca), (kb, tb, b, wb, cb) in itertools.combinations(lists, 2):
        if ka != kb and len(a.values) == len(b.values):
            out.append(Proposal(f"rows tagged '{ta}' ({wa}) and rows tagged '{tb}' ({wb})", a, b, ta, tb, ca + cb))
    return out


def _under_headers(rows: list, tag: str) -> list:
    """``[(key, name, rows)]``: a tag's rows, and when they fall under several section headers (``Robot TCP
    Position:`` / ``Camera Position in Marker Coordinate Space:`` above untagged matrix rows), the rows under
    each header, named by it."""
    out = [((tag, None), tag, rows)]
    labels = list(dict.fromkeys(r.label for r in rows))
    if len(labels) > 1:
        for label in labels:
            name = label.strip("#%/ :<>")
            out.append(((tag, label), f"{tag} {name}".strip() if tag else name,
                        [r for r in rows if r.label == label]))
    return out


def _sections(rows: list, position: dict, path_name: str) -> list:
    """Matrices over rows, per section (text and count lines split them) and per posture (2-3 in turn)."""
    rows4 = [r for r in rows if len(r.values) == 4]
    if len(rows4) < 6 or len(rows4) < 0.8 * len(rows):
        return []
    out = []
    by_section: dict = {}
    for r in rows4:
        by_section.setdefault(r.section, []).append(r)
    sections = []
    for members in by_section.values():
        mats = _matrices(members, position)
        if mats:
            label = members[0].label.strip("#%/ :")
            sections.append((label, _group([m[0] for m in mats], [m[1] for m in mats], path_name, label)))
    for (la, a), (lb, b) in itertools.combinations(sections, 2):
        if len(a.values) == len(b.values) and len(a.values) >= 3:
            out.append(Proposal(f"matrices over 3-4 rows in two sections ({la or 'unlabelled'}, {lb or 'unlabelled'})",
                                a, b, la, lb, 0))
    mats = _matrices(rows4, position)
    if not mats:
        return out
    for k in (2, 3):
        for trim in ((0, 0), (1, 0), (0, 1)):
            chosen = mats[trim[0]:len(mats) - trim[1]]
            if len(chosen) % k or len(chosen) // k < 3:
                continue
            for i, j in itertools.permutations(range(k), 2):
                if i > j and k == 2:
                    continue  # the order of the two sides is the pairing's to decide
                first, second = chosen[i::k], chosen[j::k]
                left = f"; {sum(trim)} matrix left out ({'first' if trim[0] else 'last'})" if sum(trim) else ""
                out.append(Proposal(f"{k} matrices over 3-4 rows per posture, the {_nth(i)} and the {_nth(j)}{left}",
                                    _group([m[0] for m in first], [m[1] for m in first], path_name),
                                    _group([m[0] for m in second], [m[1] for m in second], path_name),
                                    cost=sum(trim) + (k - 2)))
    return out


def _nth(i: int) -> str:
    return ("first", "second", "third")[i]


def _index_columns(values: np.ndarray) -> int:
    """How many leading columns are posture numbers or stamps (increasing in every row), at most 2."""
    k = 0
    while k < min(2, values.shape[1]) and len(values) > 1 and np.all(np.diff(values[:, k]) > 0):
        k += 1
    return k


def _per_row(rows: list, path_name: str) -> list:
    """A robot and a camera pose side by side in each row, after 0-3 leading and before trailing columns.

    Leading posture numbers or stamps are skipped for free and never read as part of a pose; every
    other column left out costs one (the cheapest readings are scored first).
    """
    widths = {len(r.values) for r in rows}
    if len(widths) != 1:
        return []
    w = widths.pop()
    values = np.array([r.values for r in rows], float)
    index = _index_columns(values)
    out = []
    for skip in range(index, index + 3):
        for wa, wb in itertools.product(POSE_WIDTHS, POSE_WIDTHS):
            extra = w - skip - wa - wb
            if extra < 0:
                continue
            a = _group(rows, values[:, skip:skip + wa], path_name)
            b = _group(rows, values[:, skip + wa:skip + wa + wb], path_name)
            if index:
                a.keys = b.keys = [tuple(v) for v in values[:, :index]]
            words = (f"each row: {wa} numbers then {wb} numbers" + (f" after {skip} leading column(s)" if skip else "")
                     + (f", {extra} trailing column(s) left out" if extra else ""))
            out.append(Proposal(words, a, b, cost=skip - index + extra, robot_first=True))
    return out


def propose(text: str, path_name: str) -> list:
    """Every pairing the text's rows allow (module docstring), cheapest first, at most :data:`MAX_PROPOSALS`."""
    rows = tokenise(text)
    if not rows:
        return []
    position = {r.line: k for k, r in enumerate(rows)}
    proposals = _per_tag(rows, position, path_name) + _sections(rows, position, path_name)
    if len({r.tag for r in rows}) == 1:
        proposals += _per_row(rows, path_name)
    proposals.sort(key=lambda p: p.cost)
    return proposals[:MAX_PROPOSALS]


def one_side_lists(text: str, path_name: str) -> list:
    """The one-side lists a file can be (for one file per side): ``[(Group, words)]``."""
    rows = tokenise(text)
    if not rows:
        return []
    position = {r.line: k for k, r in enumerate(rows)}
    tags = {r.tag for r in rows}
    found = [(g, w) for g, w, _ in _lists_of_rows(rows, position, path_name, "")] if len(tags) == 1 else []
    return found

