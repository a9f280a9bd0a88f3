"""The calibration methods: one row each (name, kind, solver, citation, what it does).

``calibrate(problem, method)`` (:mod:`handeye.calibration.solve`) and everything that lists methods
(``ALL_METHODS``, ``PAPER_METHODS``, the command line, the benchmarks) read this table. A new
method is one solver file and one row here.

Kinds
-----
``paper``
    The variants of Algorithm 1 of Deniz & Cakir: a candidate from every posture triplet (or all
    postures at once for ``mc``) and one selection criterion (``triplets``, ``selection``).
``ml``
    The recommended default: maximum likelihood with errors in variables (``eiv``), started by mcb,
    noise levels estimated from the data, cross-validated accuracy (solved in ``solve``).
``robust``
    The default before ``ml``: the paper's mcb start, outlier postures out, robust refinement of
    the point consistency, one-sigma uncertainty (solved in ``solve``).
``classic``
    A published ``AX = XB`` solver, ``solver(hand, target2cam, pairs=None) -> X (4, 4)``
    (:mod:`handeye.calibration.classic`, one file per method).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .classic import (
    solve_andreff,
    solve_chou,
    solve_daniilidis,
    solve_horaud,
    solve_liang,
    solve_lu,
    solve_park,
    solve_tsai,
)

__all__ = ["Method", "METHODS", "KINDS", "DEFAULT_METHOD", "method_names", "get_method"]

#: The kinds of method, in the order the table lists them.
KINDS = ("paper", "ml", "robust", "classic")

_PAPER = ('C. Deniz and M. Cakir, "Solution to the hand-eye calibration in the manner of absolute orientation '
          'problem", Industrial Robot, 2018')


@dataclass(frozen=True)
class Method:
    """One calibration method.

    Attributes
    ----------
    name : str
        The ``--method`` word.
    kind : str
        ``ml``, ``robust``, ``paper`` or ``classic`` (see the module docstring).
    citation : str
        Authors and year, as the result's ``details["reference"]`` names it (``Tsai & Lenz (1989)``).
    summary : str
        What it does, in one line.
    solver : callable or None
        For ``classic``: ``solver(hand, target2cam, pairs=None) -> ndarray (4, 4)``; the other kinds
        are solved by ``solve`` from their name.
    source : str
        The full reference.
    """

    name: str
    kind: str
    citation: str
    summary: str
    solver: Callable | None = None
    source: str = ""

    @property
    def reference(self) -> str:
        """``citation, summary.`` (what a classic result records as its reference)."""
        return f"{self.citation}, {self.summary}." if self.summary else f"{self.citation}."


def _paper(name: str, summary: str) -> Method:
    return Method(name, "paper", "Deniz & Cakir (2018)", summary, source=_PAPER)


#: Every method by name, in the order they are listed.
METHODS: dict[str, Method] = {m.name: m for m in (
    _paper("mc", "all postures at once (Horn least squares over every pair; no selection)"),
    _paper("mcr", "best triplet by the rotation residual of AX = XB (eq. 16)"),
    _paper("mct", "best triplet by the translation residual of AX = XB (eq. 16)"),
    _paper("mcb", "best triplet by back-projection d_back (eq. 23)"),
    _paper("mco", "best triplet by d_org (eq. 22)"),
    _paper("mcy", "best triplet by the distance to the true board points (synthetic sessions only)"),
    Method("ml", "ml", "handeye, after Deniz & Cakir (2018)", "maximum likelihood with errors in variables: X, "
           "the board and per-posture robot and camera corrections weighted by noise levels estimated from the "
           "data, kinematic deviations when a likelihood-ratio test finds them, outliers out, covariance and "
           "cross-validated accuracy", source=_PAPER),
    Method("robust", "robust", "handeye, after Deniz & Cakir (2018)", "mcb, then outlier postures out, robust refinement "
           "of the point consistency and a one-sigma uncertainty", source=_PAPER),
    Method("tsai", "classic", "Tsai & Lenz (1989)", "", solve_tsai,
           'R. Y. Tsai and R. K. Lenz, "A new technique for fully autonomous and efficient 3D robotics hand/eye '
           'calibration", IEEE Transactions on Robotics and Automation 5(3):345-358, 1989'),
    Method("park", "classic", "Park & Martin (1994)", "", solve_park,
           'F. C. Park and B. J. Martin, "Robot sensor calibration: solving AX = XB on the Euclidean group", '
           'IEEE Transactions on Robotics and Automation 10(5):717-721, 1994'),
    Method("horaud", "classic", "Horaud & Dornaika (1995)", "linear rotation then translation", solve_horaud,
           'R. Horaud and F. Dornaika, "Hand-eye calibration", The International Journal of Robotics Research '
           '14(3):195-210, 1995'),
    Method("andreff", "classic", "Andreff, Horaud & Espiau (1999)", "linear in (vec R_X, t_X)", solve_andreff,
           'N. Andreff, R. Horaud and B. Espiau, "On-line hand-eye calibration", Second International Conference '
           "on 3-D Digital Imaging and Modeling (3DIM'99), pp. 430-436, 1999"),
    Method("daniilidis", "classic", "Daniilidis (1999)", "simultaneous rotation and translation", solve_daniilidis,
           'K. Daniilidis, "Hand-eye calibration using dual quaternions", The International Journal of Robotics '
           'Research 18(3):286-298, 1999'),
    Method("chou", "classic", "Chou & Kamel (1991)", "quaternion SVD then translation", solve_chou,
           'J. C. K. Chou and M. Kamel, "Finding the position and orientation of a sensor on a robot manipulator '
           'using quaternions", The International Journal of Robotics Research 10(3):240-254, 1991'),
    Method("lu", "classic", "Lu & Chou (1995)", "simultaneous, eight-space quaternions", solve_lu,
           'Y.-C. Lu and J. C. K. Chou, "Eight-space quaternion approach for robotic hand-eye calibration", '
           'IEEE International Conference on Systems, Man and Cybernetics, vol. 4, pp. 3316-3321, 1995'),
    Method("liang", "classic", "Liang & Mao (2008)", "Kronecker null space then translation", solve_liang,
           'R.-H. Liang and J.-F. Mao, "Hand-eye calibration with a new linear decomposition algorithm", '
           'Journal of Zhejiang University SCIENCE A 9(10):1363-1368, 2008'),
)}

#: The method ``calibrate`` runs when none is named.
DEFAULT_METHOD = "ml"


def method_names(kind: str | None = None) -> tuple[str, ...]:
    """The method names, in table order; only those of ``kind`` when given."""
    return tuple(name for name, m in METHODS.items() if kind is None or m.kind == kind)


def get_method(name: str) -> Method | None:
    """The table row of ``name`` (any case), or None."""
    return METHODS.get(str(name).lower())
