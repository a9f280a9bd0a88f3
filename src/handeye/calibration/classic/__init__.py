"""Classic ``AX = XB`` hand-eye solvers, one module per published method, implemented here.

Every solver has the signature ``solve_<name>(hand, target2cam, pairs=None) -> ndarray (4, 4)``:
``hand`` (n, 4, 4) are the hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0``
eye-to-hand), ``target2cam`` (n, 4, 4) the board poses ``B_i``, and the returned ``X``
(``cam2tool0`` or ``cam2base``, in the input's length unit) satisfies
``hand_i @ X @ target2cam_i = constant``. See README.md in this folder for what each minimises.
"""

from .andreff import solve_andreff
from .chou import solve_chou
from .daniilidis import solve_daniilidis
from .horaud import solve_horaud
from .liang import solve_liang
from .lu import solve_lu
from .park import solve_park
from .tsai import solve_tsai

__all__ = [
    "CLASSIC_METHODS",
    "solve_tsai",
    "solve_park",
    "solve_horaud",
    "solve_andreff",
    "solve_daniilidis",
    "solve_chou",
    "solve_lu",
    "solve_liang",
]


def __getattr__(name: str):
    """``CLASSIC_METHODS``: ``{name: solver}`` of the methods table's ``classic`` rows (read now, so
    it holds a plug-in's AX = XB solver too); the table (``calibration.methods``) is the one list."""
    if name == "CLASSIC_METHODS":
        from ..methods import METHODS, method_names

        return {method: METHODS[method].load() for method in method_names("classic")}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
