"""Pose conventions: how a row of numbers becomes a 4x4 transform, and the names vendors give them.

A pose in a log is 16 or 12 numbers (a matrix, row- or column-major), 7 (a position and a unit
quaternion, ``w x y z`` or ``x y z w``, either first) or 6 (a position and three rotation numbers:
a rotation vector, or Euler angles in one of the 24 conventions - 12 axis orders, about static or
rotating axes - in degrees or radians). :class:`PoseConvention` is one such reading;
:func:`conventions_for_width` lists every reading of a width, :func:`parse_rotation_spec` turns what
the user writes after ``--euler`` (``ZYX``, ``xyz:deg``, ``rotvec``, ``kuka``) into the readings it
allows.

Euler sequences are written as scipy writes them: UPPERCASE letters for rotating (intrinsic) axes,
lowercase for static (extrinsic, fixed) axes; the three angles are read in the order of the letters.
``ZYX`` rotating = ``R = Rz(a) Ry(b) Rx(c)`` for the angles ``(a, b, c)``; ``xyz`` static =
``R = Rz(c) Ry(b) Rx(a)`` for ``(a, b, c)``.

Vendors (``VENDORS``; position units are what the vendor writes, a prior that the data may overrule):

========  ============================================================  ========
name      rotation                                                      position
========  ============================================================  ========
abb       quaternion q1..q4 = (w, x, y, z); 6 numbers: Euler ZYX        mm
          rotating axes, degrees (RobotStudio's display)
kuka      A B C: Euler ZYX rotating axes (Rz(A) Ry(B) Rx(C)), degrees   mm
fanuc     W P R: Euler XYZ static axes (Rz(R) Ry(P) Rx(W)), degrees     mm
ur        rotation vector (rx, ry, rz), radians                         m
ros       quaternion (x, y, z, w); 6 numbers: RPY = Euler XYZ static    m
          axes, radians
visp      theta-u = rotation vector, radians                            m
opencv    rvec then tvec (rotation vector first), radians               board's
========  ============================================================  ========
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    "POSE_WIDTHS",
    "EULER_SEQUENCES",
    "VENDORS",
    "ROTATION_TOLERANCE",
    "PoseConvention",
    "conventions_for_width",
    "parse_rotation_spec",
    "vendor_units",
    "SPEC_HELP",
]

#: Numbers per pose this module reads.
POSE_WIDTHS = (6, 7, 12, 16)
#: The 12 axis orders; uppercase = rotating (intrinsic) axes, lowercase = static (extrinsic) axes.
_ORDERS = ["".join(p) for p in itertools.permutations("xyz")] + [a + b + a for a in "xyz" for b in "xyz" if b != a]
EULER_SEQUENCES = tuple(o.upper() for o in _ORDERS) + tuple(_ORDERS)
#: Largest deviation of a quaternion's norm from 1, and of a rotation matrix from orthonormal.
ROTATION_TOLERANCE = 1e-3
#: Largest deviation of a matrix's bottom row from (0, 0, 0, 1).
BOTTOM_ROW_TOLERANCE = 1e-4
#: Largest rotation numbers a reading accepts: a rotation vector or Euler angle in radians beyond a
#: full turn (with a margin for rounding) is no angle a tool writes; in degrees, two full turns.
_FULL_TURN_RAD = 2.0 * np.pi * 1.001
_FULL_TURN_DEG = 720.0


@dataclass(frozen=True)
class PoseConvention:
    """One way to read ``width`` numbers as a pose.

    Attributes
    ----------
    kind : str
        ``matrix``, ``quaternion``, ``rotvec`` or ``euler``.
    layout : str
        ``matrix``: ``row`` or ``column`` (major); ``quaternion``: ``wxyz`` or ``xyzw``; else empty.
    sequence : str
        ``euler``: the scipy sequence (``ZYX`` rotating, ``xyz`` static).
    degrees : bool
        ``euler``: angles in degrees (else radians).
    rotation_first : bool
        The rotation numbers come before the position (quaternion first; OpenCV's rvec, tvec).
    width : int
        Numbers per pose: 16 or 12 (matrix), 7 (quaternion), 6 (rotvec, euler).
    """

    kind: str
    layout: str = ""
    sequence: str = ""
    degrees: bool = False
    rotation_first: bool = False
    width: int = 6

    @property
    def key(self) -> str:
        """A short stable name: ``euler:ZYX:deg``, ``quaternion:wxyz``, ``matrix16:row``, ``rotvec``."""
        if self.kind == "euler":
            return f"euler:{self.sequence}:{'deg' if self.degrees else 'rad'}"
        if self.kind == "quaternion":
            return f"quaternion:{self.layout}" + (":first" if self.rotation_first else "")
        if self.kind == "matrix":
            return f"matrix{self.width}:{self.layout}"
        return "rotvec" + (":first" if self.rotation_first else "")

    def short(self) -> str:
        """A few words for the candidates table."""
        if self.kind == "euler":
            axes = "rotating" if self.sequence.isupper() else "static"
            return f"Euler {self.sequence} {axes} {'deg' if self.degrees else 'rad'}"
        if self.kind == "quaternion":
            return f"quaternion {self.layout}" + (" first" if self.rotation_first else "")
        if self.kind == "matrix":
            return f"{'4x4' if self.width == 16 else '3x4'} {self.layout}-major"
        return "rotation vector" + (" first" if self.rotation_first else "")

    def describe(self) -> str:
        """The reading in words, for the import summary and the session record."""
        if self.kind == "euler":
            axes = "rotating axes" if self.sequence.isupper() else "static axes"
            return f"Euler {self.sequence.upper()} {axes} in {'degrees' if self.degrees else 'radians'}"
        if self.kind == "quaternion":
            where = "quaternion then position" if self.rotation_first else "position then quaternion"
            return f"{where}, quaternion ({', '.join(self.layout)})"
        if self.kind == "matrix":
            shape = "4x4" if self.width == 16 else "3x4 [R|t]"
            return f"{shape} matrix, {self.layout}-major"
        if self.rotation_first:
            return "rotation vector (axis x angle, radians) then position"
        return "rotation vector (axis x angle, radians)"

    def transforms(self, values) -> tuple[np.ndarray, np.ndarray]:
        """Poses ``(n, 4, 4)`` in the numbers' own length unit, and which rows are valid.

        Parameters
        ----------
        values : array-like, shape (n, width)

        Returns
        -------
        poses : ndarray, shape (n, 4, 4)
            Identity for invalid rows.
        valid : ndarray of bool, shape (n,)
            Finite numbers, and (quaternion) a unit norm within 1e-3, (matrix) an orthonormal
            rotation part with determinant +1 and, for 16 numbers, the row or column (0, 0, 0, 1).
        """
        v = np.asarray(values, dtype=float).reshape(-1, self.width)
        n = len(v)
        poses = np.tile(np.eye(4), (n, 1, 1))
        valid = np.all(np.isfinite(v), axis=1) & np.all(np.abs(v) < 1e12, axis=1)
        safe = np.where(valid[:, None], v, 0.0)
        if self.kind == "matrix":
            rot, pos, bottom_ok = _matrix_parts(safe, self.width, self.layout)
            valid &= bottom_ok
        elif self.kind == "quaternion":
            if self.rotation_first:
                q, pos = safe[:, :4], safe[:, 4:7]
            else:
                pos, q = safe[:, :3], safe[:, 3:7]
            norm = np.linalg.norm(q, axis=1)
            valid &= np.abs(norm - 1.0) <= ROTATION_TOLERANCE
            q = np.where(valid[:, None], q / np.maximum(norm, 1e-12)[:, None], [1.0, 0.0, 0.0, 0.0])
            rot = Rotation.from_quat(q, scalar_first=(self.layout == "wxyz")).as_matrix()
        elif self.kind == "rotvec":
            if self.rotation_first:
                r, pos = safe[:, :3], safe[:, 3:6]
            else:
                pos, r = safe[:, :3], safe[:, 3:6]
            valid &= np.linalg.norm(r, axis=1) <= _FULL_TURN_RAD
            rot = Rotation.from_rotvec(r).as_matrix()
        else:
            pos, angles = safe[:, :3], safe[:, 3:6]
            valid &= np.max(np.abs(angles), axis=1) <= (_FULL_TURN_DEG if self.degrees else _FULL_TURN_RAD)
            rot = Rotation.from_euler(self.sequence, angles, degrees=self.degrees).as_matrix()
        if self.kind == "matrix":
            error = np.max(np.abs(np.einsum("nji,njk->nik", rot, rot) - np.eye(3)), axis=(1, 2))
            valid &= (error <= ROTATION_TOLERANCE) & (np.linalg.det(rot) > 0)
            u, _, vt = np.linalg.svd(np.where(valid[:, None, None], rot, np.eye(3)))
            rot = u @ vt
        poses[:, :3, :3] = np.where(valid[:, None, None], rot, np.eye(3))
        poses[:, :3, 3] = np.where(valid[:, None], pos, 0.0)
        return poses, valid


def _matrix_parts(v, width: int, layout: str):
    n = len(v)
    if width == 16:
        m = v.reshape(n, 4, 4)
        if layout == "column":
            m = np.transpose(m, (0, 2, 1))
        bottom = np.max(np.abs(m[:, 3] - [0.0, 0.0, 0.0, 1.0]), axis=1) <= BOTTOM_ROW_TOLERANCE
        return m[:, :3, :3], m[:, :3, 3], bottom
    if layout == "row":
        m = v.reshape(n, 3, 4)
        return m[:, :, :3], m[:, :, 3], np.ones(n, bool)
    m = np.transpose(v.reshape(n, 4, 3), (0, 2, 1))  # column-major 3x4: four columns of three
    return m[:, :, :3], m[:, :, 3], np.ones(n, bool)


def _euler(sequence: str, degrees: bool) -> PoseConvention:
    return PoseConvention("euler", sequence=sequence, degrees=degrees, width=6)


ROTVEC = PoseConvention("rotvec", width=6)
RVEC_TVEC = PoseConvention("rotvec", rotation_first=True, width=6)


def conventions_for_width(width: int) -> list:
    """Every reading of ``width`` numbers (6, 7, 12 or 16), most common first; empty for another width."""
    if width == 16:
        return [PoseConvention("matrix", "row", width=16), PoseConvention("matrix", "column", width=16)]
    if width == 12:
        return [PoseConvention("matrix", "row", width=12), PoseConvention("matrix", "column", width=12)]
    if width == 7:
        return [PoseConvention("quaternion", order, rotation_first=first, width=7)
                for first in (False, True) for order in ("wxyz", "xyzw")]
    if width == 6:
        return ([ROTVEC] + [_euler(s, d) for d in (True, False) for s in EULER_SEQUENCES] + [RVEC_TVEC])
    return []


#: Vendor name -> (conventions by width, position unit). Only the widths a vendor writes are listed.
VENDORS = {
    "abb": ({7: [PoseConvention("quaternion", "wxyz", width=7)], 6: [_euler("ZYX", True)]}, "mm"),
    "kuka": ({6: [_euler("ZYX", True)]}, "mm"),
    "fanuc": ({6: [_euler("xyz", True)]}, "mm"),
    "ur": ({6: [ROTVEC]}, "m"),
    "ros": ({7: [PoseConvention("quaternion", "xyzw", width=7)], 6: [_euler("xyz", False)]}, "m"),
    "visp": ({6: [ROTVEC]}, "m"),
    "opencv": ({6: [RVEC_TVEC]}, None),
}

SPEC_HELP = ("an Euler sequence (ZYX = rotating axes, xyz = static axes; add :deg or :rad), rotvec, "
             "rvec-tvec, or a vendor: " + ", ".join(VENDORS))


def vendor_units(spec: str | None) -> str | None:
    """The position unit a vendor name implies (``None`` for other specs)."""
    if spec is None:
        return None
    entry = VENDORS.get(spec.strip().lower())
    return entry[1] if entry else None


def parse_rotation_spec(spec: str) -> dict:
    """The conventions a ``--euler`` value allows, by width.

    Parameters
    ----------
    spec : str
        ``ZYX`` / ``xyz`` (both angle units), ``ZYX:deg``, ``xyz:rad``, ``rotvec``, ``rvec-tvec``,
        or a vendor name (:data:`VENDORS`).

    Returns
    -------
    dict
        ``{width: [PoseConvention, ...]}``; widths not listed are not constrained.

    Raises
    ------
    ValueError
        With what is accepted.
    """
    text = str(spec).strip()
    lower = text.lower()
    if lower in VENDORS:
        return dict(VENDORS[lower][0])
    if lower in ("rotvec", "rotation-vector", "thetau", "theta-u", "axis-angle"):
        return {6: [ROTVEC]}
    if lower in ("rvec-tvec", "rvec,tvec", "rvec_tvec"):
        return {6: [RVEC_TVEC]}
    sequence, _, unit = text.partition(":")
    if sequence not in EULER_SEQUENCES:
        raise ValueError(f"--euler {text!r} is not understood; give {SPEC_HELP}")
    unit = unit.strip().lower()
    if unit not in ("", "deg", "rad", "degrees", "radians"):
        raise ValueError(f"--euler {text!r}: the angle unit must be deg or rad")
    units = [True, False] if not unit else [unit.startswith("deg")]
    return {6: [_euler(sequence, d) for d in units]}
