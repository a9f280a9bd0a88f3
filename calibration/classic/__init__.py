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

#: CLI name (conventions.md) -> solver.
CLASSIC_METHODS = {
    "tsai": solve_tsai,
    "park": solve_park,
    "horaud": solve_horaud,
    "andreff": solve_andreff,
    "daniilidis": solve_daniilidis,
    "chou": solve_chou,
    "lu": solve_lu,
    "liang": solve_liang,
}
