"""The calibration methods: one row each (name, kind, citation, solver, in the comparison or not).

``calibrate(problem, method)`` (:mod:`handeye.calibration.solve`) and the selection of the paper's
variants (:mod:`handeye.calibration.selection`) dispatch from this table, and everything that lists
methods (``method_names``, the command line's help, the benchmark, the report's comparison) reads
it. A new method is one solver file and one row here; another installed package adds one through an
entry point of the group ``handeye.methods`` naming a :class:`Method`, with no change to handeye::

    # pyproject.toml of the other package
    [project.entry-points."handeye.methods"]
    kabsch = "handeye_kabsch:METHOD"   # Method("kabsch", "classic", "Me (2025)", solver="handeye_kabsch:solve")

Kinds (how ``calibrate`` calls the row's ``solver``)
-----------------------------------------------------
``paper``
    A variant of Algorithm 1 of Deniz & Cakir: a candidate from every posture triplet and the one
    the row's selection criterion picks (``triplets``, ``selection``): ``solver(theta, inputs) ->
    Selection`` over candidates ``theta (12, c)`` (:func:`handeye.calibration.selection.select_candidate`).
    No solver: all postures at once, no selection (``mc``).
``estimator``
    A whole pipeline on the problem: ``solver(problem, progress=None)`` returns an object with
    ``x`` (4, 4), ``outliers`` (n,) bool, ``uncertainty`` (dict or None), ``details`` (dict) and
    ``cross_validation`` (dict or None). (The result's posture residuals are computed from ``x`` and
    ``outliers`` the same way for every kind: ``quality_words.posture_residuals``.) ``ml``, the recommended default (maximum likelihood with errors in variables,
    ``eiv``), and ``robust``, the default before it (``robust``).
``classic``
    An ``AX = XB`` solver, ``solver(hand, target2cam, pairs=None) -> X (4, 4)``; the published ones
    are :mod:`handeye.calibration.classic`, one file per method.

A ``solver`` may be given as ``"module:function"``: it is imported when the method first runs, so
reading the table (``handeye --help``) imports no numerics.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..base import Registry, load_target

__all__ = [
    "Method",
    "METHODS",
    "KINDS",
    "DEFAULT_METHOD",
    "method_names",
    "comparison_methods",
    "get_method",
    "register_method",
]

#: The kinds of method, in the order the table lists them.
KINDS = ("paper", "estimator", "classic")

_HERE = __package__  # handeye.calibration
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
        ``estimator``, ``paper`` or ``classic``: how ``calibrate`` calls ``solver`` (module docstring).
    citation : str
        Authors and year, as the result's ``details["reference"]`` names it (``Tsai & Lenz (1989)``).
    summary : str
        What it does, in one line.
    solver : callable, str or None
        What the kind calls (module docstring), or ``"module:function"`` naming it (imported when the
        method first runs). None only for a ``paper`` method that selects nothing (``mc``).
    source : str
        The full reference.
    in_comparison : bool
        Solved for the report's method comparison (``handeye calibrate --report``, the demo).
    needs_truth : bool
        Only solvable with the truth of a synthetic session (``mcy``).
    """

    name: str
    kind: str
    citation: str
    summary: str = ""
    solver: Callable | str | None = None
    source: str = ""
    in_comparison: bool = False
    needs_truth: bool = False

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"method {self.name!r}: kind {self.kind!r} is not one of {', '.join(KINDS)}")
        if self.solver is None and self.kind != "paper":
            raise ValueError(f"method {self.name!r} of kind {self.kind} needs a solver")

    def load(self) -> Callable | None:
        """The solver (imports its module now when it is named by a string)."""
        solver = load_target(self.solver)
        if solver is not None and not callable(solver):
            raise TypeError(f"method {self.name!r}: its solver {self.solver!r} names no function")
        return solver

    @property
    def reference(self) -> str:
        """``citation, summary.`` (what a classic result records as its reference)."""
        return f"{self.citation}, {self.summary}." if self.summary else f"{self.citation}."


#: Every method by name, in the order they are listed (the package's, then those of entry points).
METHODS: Registry[Method] = Registry("method", "handeye.methods", Method)


def register_method(method: Method) -> Method:
    """Add ``method`` to :data:`METHODS` (or replace the one of its name); returns it."""
    return METHODS.register(method)


def _paper(name: str, summary: str, criterion: str | None, **options) -> Method:
    solver = f"{_HERE}.selection:{criterion}" if criterion else None
    return Method(name, "paper", "Deniz & Cakir (2018)", summary, solver, _PAPER, **options)


def _classic(name: str, citation: str, summary: str, source: str, **options) -> Method:
    return Method(name, "classic", citation, summary, f"{_HERE}.classic.{name}:solve_{name}", source, **options)


for _row in (
    _paper("mc", "all postures at once (Horn least squares over every pair; no selection)", None, in_comparison=True),
    _paper("mcr", "best triplet by the rotation residual of AX = XB (eq. 16)", "least_rotation_residual"),
    _paper("mct", "best triplet by the translation residual of AX = XB (eq. 16)", "least_translation_residual"),
    _paper("mcb", "best triplet by back-projection d_back, eq. 23 (mean distance between the same board point "
           "seen from two postures)", "least_d_back", in_comparison=True),
    _paper("mco", "best triplet by d_org, eq. 22 (mean distance to the mean point)", "least_d_org"),
    _paper("mcy", "best triplet by the distance to the true board points (synthetic sessions only)",
           "least_truth_distance", needs_truth=True),
    Method("ml", "estimator", "handeye, after Deniz & Cakir (2018)", "maximum likelihood with errors in variables: "
           "camera corners weighted by their stereo covariance, robot poses corrected with a prior from the joint "
           "noise (and the arm's kinematic deviations when a likelihood-ratio test finds them), noise levels "
           "estimated from the data, outlier postures excluded, a one-sigma uncertainty and a 5-fold "
           "cross-validation of the held-out board points (calibration/eiv/)", f"{_HERE}.eiv:solve_eiv", _PAPER),
    Method("robust", "estimator", "handeye, after Deniz & Cakir (2018)", "mcb, then outlier postures detected and "
           "excluded, a robust refinement of the point consistency over the inliers, and a one-sigma uncertainty "
           "(the default before ml)", f"{_HERE}.robust:solve_robust", _PAPER, in_comparison=True),
    _classic("tsai", "Tsai & Lenz (1989)", "",
             'R. Y. Tsai and R. K. Lenz, "A new technique for fully autonomous and efficient 3D robotics hand/eye '
             'calibration", IEEE Transactions on Robotics and Automation 5(3):345-358, 1989', in_comparison=True),
    _classic("park", "Park & Martin (1994)", "",
             'F. C. Park and B. J. Martin, "Robot sensor calibration: solving AX = XB on the Euclidean group", '
             'IEEE Transactions on Robotics and Automation 10(5):717-721, 1994', in_comparison=True),
    _classic("horaud", "Horaud & Dornaika (1995)", "linear rotation then translation",
             'R. Horaud and F. Dornaika, "Hand-eye calibration", The International Journal of Robotics Research '
             '14(3):195-210, 1995'),
    _classic("andreff", "Andreff, Horaud & Espiau (1999)", "linear in (vec R_X, t_X)",
             'N. Andreff, R. Horaud and B. Espiau, "On-line hand-eye calibration", Second International Conference '
             "on 3-D Digital Imaging and Modeling (3DIM'99), pp. 430-436, 1999"),
    _classic("daniilidis", "Daniilidis (1999)", "simultaneous rotation and translation",
             'K. Daniilidis, "Hand-eye calibration using dual quaternions", The International Journal of Robotics '
             'Research 18(3):286-298, 1999', in_comparison=True),
    _classic("chou", "Chou & Kamel (1991)", "quaternion SVD then translation",
             'J. C. K. Chou and M. Kamel, "Finding the position and orientation of a sensor on a robot manipulator '
             'using quaternions", The International Journal of Robotics Research 10(3):240-254, 1991'),
    _classic("lu", "Lu & Chou (1995)", "simultaneous, eight-space quaternions",
             'Y.-C. Lu and J. C. K. Chou, "Eight-space quaternion approach for robotic hand-eye calibration", '
             'IEEE International Conference on Systems, Man and Cybernetics, vol. 4, pp. 3316-3321, 1995'),
    _classic("liang", "Liang & Mao (2008)", "Kronecker null space then translation",
             'R.-H. Liang and J.-F. Mao, "Hand-eye calibration with a new linear decomposition algorithm", '
             'Journal of Zhejiang University SCIENCE A 9(10):1363-1368, 2008'),
):
    METHODS.register(_row)
del _row

#: The method ``calibrate`` runs when none is named (the one place it is defined).
DEFAULT_METHOD = "ml"


def method_names(kind: str | None = None, where: Callable[[Method], bool] | None = None) -> tuple[str, ...]:
    """The method names, in table order (plug-ins last); only those of ``kind`` and satisfying
    ``where`` when given."""
    return METHODS.names(lambda m: (kind is None or m.kind == kind) and (where is None or where(m)))


def comparison_methods() -> tuple[str, ...]:
    """The methods the report's comparison solves (``in_comparison``), in table order."""
    return method_names(where=lambda m: m.in_comparison)


def get_method(name: str) -> Method | None:
    """The table row of ``name`` (any case), or None."""
    return METHODS.get(str(name).lower())
