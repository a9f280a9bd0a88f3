"""Importers: other tools' hand-eye samples -> a ``handeye-session/1`` session (mm, quaternions wxyz).

One module per format, each with ``read_<format>(path(s), **options) -> Session``; this package
holds the registry and the format detection used by ``handeye import``.

==============  =======================================================  ==================  ======
format          files                                                     what the file says  units
==============  =======================================================  ==================  ======
moveit          MoveIt Calibration ``pose_samples.json``                  T_base_eef,         m
                                                                          T_cam_target
visp            folder of ViSP ``pose_fPe_<i>.yaml`` + ``pose_cPo_<i>``   fPe/rPe, cPo        m
opencv          OpenCV FileStorage ``T1_<i>``/``T2_<i>`` (camodocal)       T_base_ee,          m
                                                                          T_cam_marker
stream          two time-stamped CSV streams (ETH layout)                 hand in base,       m
                                                                          camera in target
plain           CSV / JSON of flange pose + board pose (documented here)  tool0 in base,      m|mm
                                                                          target in camera;
                                                                          eye_in_hand default
easy_handeye    easy_handeye2 ``.samples`` (YAML)                         calibration_type    m
log             any table, JSON or YAML of pose numbers                   (names, if any)     m|mm
==============  =======================================================  ==================  ======

Every reader hands the poses as the file holds them, with what the format says they are, to
``common.build_session``, where ``inference.infer`` decides the reading (rotation convention,
directions, set-up, units) from the data; what the file says breaks the ties the data leave.
Every reader records how it decided in ``session.extra["import"]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ...base import SessionError, SessionUsageError
from ...calibration import Session
from .easy_handeye import looks_like_easy_handeye, read_easy_handeye
from .head import head_text as _head
from .log_folder import plan_folder
from .log import looks_like_log, read_log
from .moveit import looks_like_moveit, read_moveit
from .opencv_storage import looks_like_opencv, pairs_files, read_opencv
from .plain import looks_like_plain_csv, looks_like_plain_json, read_plain
from .stream import looks_like_stream, read_stream
from .visp import looks_like_visp, read_visp

__all__ = [
    "Importer",
    "IMPORTERS",
    "FORMAT_NAMES",
    "detect_format",
    "read_any",
    "read_moveit",
    "read_visp",
    "read_opencv",
    "read_stream",
    "read_plain",
    "read_easy_handeye",
    "read_log",
]


@dataclass(frozen=True)
class Importer:
    """A format: its reader, what it reads, the options it accepts beyond the common ones."""

    name: str
    reader: Callable[..., Session]
    description: str
    default_setup: str | None
    options: tuple = ()
    several_paths: bool = False


#: Options every reader takes.
COMMON_OPTIONS = ("setup", "units", "board", "skip_invalid", "robot_pose", "camera_pose")

IMPORTERS = {
    "moveit": Importer("moveit", read_moveit, "MoveIt Calibration pose_samples.json ([T_base_eef, T_cam_target] pairs)",
                       None),
    "visp": Importer("visp", read_visp, "ViSP pose vectors: folder of pose_fPe_<i>.yaml (or *_pose_rPe_<i>.yaml) + pose_cPo_<i>.yaml",
                     None, ("tag_mm",), several_paths=True),
    "opencv": Importer("opencv", read_opencv, "OpenCV FileStorage pose pairs T1_<i> (robot) / T2_<i> (camera), camodocal layout",
                       None, ("robot_prefix", "camera_prefix"), several_paths=True),
    "stream": Importer("stream", read_stream, "two time-stamped CSV pose streams (t,x,y,z,qx,qy,qz,qw), robot then camera",
                       None, ("quaternion_order", "tolerance_s", "max_postures", "rest_mm_s",
                                       "rest_deg_s"), several_paths=True),
    "plain": Importer("plain", read_plain, "plain CSV/JSON, one posture per row: tool0 in base + target in camera",
                      "eye_in_hand", ("quaternion_order",)),
    "easy_handeye": Importer("easy_handeye", read_easy_handeye, "easy_handeye2 .samples (YAML robot/tracking transforms)",
                             None),
    "log": Importer("log", read_log, "any log of pose numbers (CSV/TSV/text table, JSON, YAML; one or two files): "
                    "conventions inferred from the data", None, ("euler", "quaternion_order", "robot_rows"), several_paths=True),
}
FORMAT_NAMES = tuple(IMPORTERS)


def _formats_hint() -> str:
    return f"pass --format ({', '.join(FORMAT_NAMES)})"


def detect_format(paths) -> str:
    """The format name of a path or paths, from the files' content (and names).

    Raises
    ------
    SessionError
        Missing path, or a content no importer recognises.
    """
    if isinstance(paths, (str, Path)):
        paths = [paths]
    paths = [Path(p) for p in paths]
    if not paths:
        raise SessionError("no input given")
    for p in paths:
        if not p.exists():
            raise SessionError(f"{p}: no such file or folder")
    if len(paths) == 2 and all(p.is_file() for p in paths):
        if all(looks_like_stream(_head(p)) for p in paths):
            return "stream"
    if len(paths) > 1:
        if all(p.is_file() for p in paths) and pairs_files(paths):
            return "opencv"  # camodocal's pairs and its result file
        if all(p.is_file() and looks_like_visp(p) for p in paths):
            return "visp"
        if len(paths) == 2 and all(p.is_file() and looks_like_log(p, _head(p)) for p in paths):
            return "log"
        raise SessionError(f"several inputs are read as two CSV streams, two log files (robot, camera) or ViSP pose "
                           f"files; {_formats_hint()}")
    path = paths[0]
    if path.is_dir():
        if looks_like_visp(path):
            return "visp"
        if pairs_files(path):
            return "opencv"  # a camodocal folder: its pairs, its result beside them
        csvs = [p for p in path.iterdir() if p.suffix.lower() == ".csv"]
        if len(csvs) == 2 and all(looks_like_stream(_head(p, strict=False)) for p in csvs):
            return "stream"
        files = [p for p in path.iterdir() if p.is_file() and not p.name.startswith(".")]
        if len(files) in (1, 2) and all(looks_like_log(p, _head(p, strict=False)) for p in files):
            return "log"
        if plan_folder(path) is not None:  # side files or per-posture files, results and settings beside
            return "log"
        raise SessionError(f"{path}: a folder without ViSP pose files, two CSV streams or one or two logs; "
                           f"{_formats_hint()}")
    head = _head(path)
    suffix = path.suffix.lower()
    if looks_like_visp(path):
        return "visp"
    if looks_like_opencv(path, head):
        return "opencv"
    if suffix == ".json" or head.lstrip()[:1] in ("[", "{"):
        if looks_like_moveit(path, head):
            return "moveit"
        if looks_like_plain_json(head):
            return "plain"
    if suffix == ".samples" or looks_like_easy_handeye(head):
        if looks_like_easy_handeye(head):
            return "easy_handeye"
    if looks_like_plain_csv(head):
        return "plain"
    if looks_like_stream(head):
        raise SessionError(f"{path} looks like a time-stamped pose stream: give the robot stream and the camera stream "
                           f"(two files, or their folder)")
    if looks_like_log(path, head):
        return "log"
    raise SessionError(f"{path}: cannot tell the format from its content; {_formats_hint()}")


def read_any(paths, format: str | None = None, **options) -> Session:
    """Read ``paths`` with the named (or detected) importer; options not applicable are refused.

    Parameters
    ----------
    paths : path or list of paths
    format : str, optional
        One of :data:`FORMAT_NAMES`; detected when ``None``.
    **options
        ``setup``, ``units``, ``board``, ``skip_invalid`` and the format's own (``IMPORTERS[name].options``);
        options whose value is ``None`` count as not given.

    Returns
    -------
    Session
        With ``session.extra["import"]`` recording the format and how set-up and units were decided.

    Raises
    ------
    SessionError
    """
    if format is None:
        format = detect_format(paths)
        how = "detected"
    else:
        how = "given"
    if format not in IMPORTERS:
        raise SessionError(f"unknown format {format!r}; choose one of {', '.join(FORMAT_NAMES)}")
    importer = IMPORTERS[format]
    given = {k: v for k, v in options.items() if v is not None}
    unknown = [k for k in given if k not in COMMON_OPTIONS + importer.options]
    if unknown:
        flag = "--" + unknown[0].replace("_", "-")
        raise SessionUsageError(f"{flag} does not apply to {format} files (it applies to: "
                           f"{', '.join(n for n, i in IMPORTERS.items() if unknown[0] in i.options) or 'none'})")
    if isinstance(paths, (list, tuple)) and not importer.several_paths:
        if len(paths) != 1:
            raise SessionUsageError(f"{format} reads one file; got {len(paths)}")
        paths = paths[0]
    if isinstance(paths, (list, tuple)) and len(paths) == 1 and format in ("visp", "log", "opencv"):
        paths = paths[0]
    session = importer.reader(paths, **given)
    session.extra["import"]["format_how"] = how
    return session
