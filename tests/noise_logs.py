"""Stations whose logs only the noise can decide: flange orientations close to the base's axes.

Euler orders differ only at second order in the angles, so when the flange's Euler angles stay
small (a base frame aligned with the working posture, as a user frame often is), a wrong order fits
the X-free invariants almost as well as the right one: a degree or two of misfit instead of the
noise's few tenths. :func:`aligned_station` draws such a station at a chosen noise level and
rotation spread; ``axis`` makes every posture turn about one axis (a log that nothing decides).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.geometry.transforms import invert_transforms
from layout_logs import Station, _pose


def _board_views(rng, n: int, spread_deg: float, axis) -> np.ndarray:
    """Camera poses in the board's frame (board z into the board, the camera on its -z side, 700-1000 mm
    away), turned by up to ``spread_deg`` about random axes (or about ``axis`` only, a unit 3-vector)."""
    nominal = _pose(np.eye(3), [0.0, 0.0, -850.0])
    out = []
    for _ in range(n):
        if axis is None:
            turn = Rotation.from_rotvec(rng.uniform(-1, 1, 3) * np.radians(spread_deg))
        else:
            turn = Rotation.from_rotvec(np.asarray(axis, float) * rng.uniform(-1, 1) * np.radians(spread_deg))
        about_board = _pose(turn.as_matrix(), [0.0, 0.0, 0.0])
        view = about_board @ nominal
        view[:3, 3] += rng.normal(0, 60, 3)
        out.append(view)
    return np.array(out)


def aligned_station(seed: int, n: int = 15, setup: str = "eye_in_hand", spread_deg: float = 12.0,
                    sigma_deg: float = 0.1, sigma_mm: float = 0.5, axis=None) -> Station:
    """A station whose flange orientations stay within about ``spread_deg`` of the base's axes.

    Parameters
    ----------
    seed, n : int
        Random seed, postures.
    setup : str
        ``eye_in_hand`` (camera on the flange) or ``eye_to_hand`` (board on the flange).
    spread_deg : float
        How far the views turn about the board (and the flange about its nominal, identity, orientation).
    sigma_deg, sigma_mm : float
        Noise of the board poses (rotation about a random axis, translation per coordinate).
    axis : array-like of 3, optional
        Every view turns about this axis only (degenerate: the invariants cannot tell the readings apart).

    Returns
    -------
    Station
        ``tool0`` flange in base and ``target`` board in camera (mm), the true ``x``.
    """
    rng = np.random.default_rng(seed)
    cam_in_board = _board_views(rng, n, spread_deg, axis)
    mount = _pose(Rotation.from_rotvec(rng.normal(0, 0.3, 3)).as_matrix(), rng.uniform(-120, 120, 3))
    if setup == "eye_in_hand":  # x: camera in flange; the flange's nominal orientation is the base's
        x = mount
        flange_in_board = cam_in_board @ invert_transforms(x)
        base_in_board = flange_in_board[0] @ invert_transforms(_pose(np.eye(3), [750.0, 50.0, 600.0]))
        tool0 = invert_transforms(base_in_board) @ flange_in_board
    else:  # the board on the flange (``mount``: board in flange); x: camera in base
        flange_in_camera = invert_transforms(cam_in_board) @ invert_transforms(mount)
        x = _pose(np.eye(3), [750.0, 50.0, 600.0]) @ invert_transforms(flange_in_camera[0])
        tool0 = x @ flange_in_camera
    target = invert_transforms(cam_in_board)
    noise = np.array([_pose(Rotation.from_rotvec(rng.normal(0, np.radians(sigma_deg), 3)).as_matrix(),
                            rng.normal(0, sigma_mm, 3)) for _ in range(n)])
    return Station(setup, tool0, target @ noise, x, rng.uniform(-120, 120, (n, 6)))
