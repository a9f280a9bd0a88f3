"""Write a synthetic session to disk (the library side of ``handeye simulate``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..geometry import STATION_CORNERS, STATION_SQUARE_MM
from ..base import HandEyeError, UsageError
from .origin import SIMULATED

#: Most postures a synthetic session may have (sampling takes about 0.05 s a posture; the triplet
#: methods grow with the cube of the count; a calibration uses 15-60).
MAX_POSTURES = 1000


@dataclass(frozen=True)
class SimulateOptions:
    output: str
    postures: int = 30
    sigma_rob_deg: float = 0.0
    sigma_cam_mm: float = 0.0
    camera_noise: str = "paper"
    joint_offset_deg: tuple | None = None  # one value per robot axis; None: no offset
    setup: str = "eye_in_hand"
    corners: tuple = STATION_CORNERS
    square_mm: float = STATION_SQUARE_MM
    seed: int = 0
    scene_seed: int = 0
    overwrite: bool = False


def simulate_session(options: SimulateOptions, progress=lambda message: None) -> Path:
    """Sample a scene, draw noise and write the session with ``truth.yaml``; returns the folder."""
    from ..robot import load_robot
    from ..calibration import create_session, write_posture, write_truth
    from ..calibration import NoiseConfig, SceneConfig, make_scene, sample_session, truth_dict

    if not 3 <= options.postures <= MAX_POSTURES:
        raise UsageError(f"postures must be between 3 and {MAX_POSTURES}; got {options.postures}")
    robot = load_robot(SceneConfig.robot)
    offset = (0.0,) * robot.dof if options.joint_offset_deg is None else tuple(options.joint_offset_deg)
    if len(offset) != robot.dof:
        raise UsageError(f"--joint-offset needs {robot.dof} values, one per axis of the {robot.name}; got {len(offset)}")
    if options.square_mm <= 0:
        raise UsageError(f"--square-mm must be positive; got {options.square_mm}")
    path = Path(options.output)
    if (path / "session.yaml").exists() and not options.overwrite:
        raise HandEyeError(f"{path} already holds a session; choose another folder or pass --overwrite")
    progress(f"planning {options.postures} reachable postures with the board in view (about "
             f"{max(1, round(0.05 * options.postures))} s) ...")
    try:
        scene = make_scene(SceneConfig(postures=options.postures, corners=tuple(options.corners),
                                       square_mm=options.square_mm, setup=options.setup, seed=options.scene_seed))
    except RuntimeError as exc:
        raise HandEyeError(str(exc)) from None
    noise = NoiseConfig(options.sigma_rob_deg, options.sigma_cam_mm, options.camera_noise,
                        offset, options.seed)
    session = sample_session(scene, noise)
    session.extra["origin"] = SIMULATED
    create_session(path, session, overwrite=options.overwrite)
    write_truth(path, truth_dict(scene, noise))
    for posture in session.postures:
        write_posture(path, posture)
    return path
