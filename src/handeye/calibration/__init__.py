"""The numeric core: sessions on disk, the calibration methods, kinematics, rotations and metrics.

It runs on numpy and scipy alone. The names below load on first use (importing the package is cheap)::

    from handeye.calibration import calibrate_session, read_session
    result = calibrate_session(read_session("cal_01"))            # the default method (ml)
    print(result.x, result.metrics["d_org_mm"])

Methods are the rows of :data:`METHODS` (``handeye.calibration.methods``; another package adds one
through the entry-point group ``handeye.methods``, :func:`method_names` lists them all); robots are
the YAML files of ``robot/robots`` (:func:`load_robot`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base.lazy import lazy_exports

_EXPORTS = {
    "calibrate": "solve",
    "calibrate_session": "solve",
    "problem_from_session": "solve",
    "CalibrationResult": "solve",
    "ALL_METHODS": "solve",
    "DEFAULT_METHOD": "methods",
    "METHODS": "methods",
    "Method": "methods",
    "method_names": "methods",
    "register_method": "methods",
    "read_session": "session",
    "create_session": "session",
    "write_posture": "session",
    "Session": "session",
    "Posture": "session",
    "HandEyeProblem": "problem",
    "EYE_IN_HAND": "problem",
    "EYE_TO_HAND": "problem",
    "BoardGeometry": "handeye.geometry.board",
    "RobotModel": "handeye.robot.kinematics",
    "load_robot": "handeye.robot.kinematics",
    "known_robots": "handeye.robot.kinematics",
    "transform_from_pose": "handeye.geometry.transforms",
    "pose_from_transform": "handeye.geometry.transforms",
    "d_org": "metrics",
    "d_back": "metrics",
    "HandEyeError": "handeye.base.errors",
    "ConfigError": "handeye.base.errors",
    "SessionError": "handeye.base.errors",
    "CalibrationError": "handeye.base.errors",
    "OutputError": "handeye.base.errors",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from ..geometry.board import BoardGeometry  # noqa: F401
    from ..base.errors import CalibrationError, ConfigError, HandEyeError, OutputError, SessionError  # noqa: F401
    from ..robot.kinematics import RobotModel, known_robots, load_robot  # noqa: F401
    from .methods import DEFAULT_METHOD, METHODS, Method, method_names, register_method  # noqa: F401
    from .metrics import d_back, d_org  # noqa: F401
    from .problem import EYE_IN_HAND, EYE_TO_HAND, HandEyeProblem  # noqa: F401
    from .session import Posture, Session, create_session, read_session, write_posture  # noqa: F401
    from .solve import ALL_METHODS, CalibrationResult, calibrate, calibrate_session, problem_from_session  # noqa: F401
    from ..geometry.transforms import pose_from_transform, transform_from_pose  # noqa: F401
