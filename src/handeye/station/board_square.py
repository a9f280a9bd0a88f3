"""The square size of a station's board, where the code needs it known."""

from __future__ import annotations

from ..base import ConfigError
from ..geometry import BoardGeometry

__all__ = ["known_square_mm"]


def known_square_mm(board: BoardGeometry) -> float:
    """``board.square_mm`` (mm), refused in one line when the board's size is unknown (``None``: a board
    read from data without its size); the station's own boards (``target`` in the configuration) always
    have one."""
    if board.square_mm is None:
        raise ConfigError(f"the {board.corners[0]}x{board.corners[1]} board has no square size: give target.square_mm "
                          "(mm) in the station configuration")
    return board.square_mm
