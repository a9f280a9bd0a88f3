"""Library entry of ``handeye stereo calibrate``: image pairs (files or live) in, ``STEREO.yaml`` out.

Sources of pairs:

- **files**: a folder (pairs named ``*left*`` / ``*right*`` with the rest of the name equal, e.g.
  ``000_left.png`` + ``000_right.png`` or ``left/01.png`` + ``right/01.png``; a session folder's
  ``images/``), or two glob patterns (paired by the part of the name that is not left/right, else
  in sorted order);
- **live**: a camera back end (``drivers.camera.open_camera``: ``xb3``, ``mock``) and a guided loop
  that says after each accepted pair where to hold the board next (the empty cells of each image
  and the board tilts still missing, :class:`~handeye.drivers.camera.coverage.Coverage`), until
  the coverage is complete and enough pairs are in.

Each image is searched with the full detector (:func:`~handeye.drivers.camera.checkerboard.detect_board`;
the live loop uses its quick stage to keep up with the camera); images whose board has corners off
its grid (glare) are left out with the reason. Then
:func:`~handeye.drivers.camera.stereo_fit.calibrate_stereo`, and the files: the stereo
model (OpenCV FileStorage YAML that ``handeye triangulate --stereo`` and the station's
``camera.stereo_model`` read), a JSON report (figures, every pair's use and reasons) and a coverage
map (PNG). A Triclops factory file (``--factory``) is compared with the result.
"""

from __future__ import annotations

import glob as globlib
import json
import os
import re
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..geometry import BoardGeometry
from ..base import HandEyeError, OutputError, UsageError
from ..base import make_folder, write_failure, write_text_atomic

__all__ = ["StereoCalibrationConfig", "StereoCalibrationRun", "find_pairs", "detect_pairs", "capture_live",
           "run_stereo_calibration", "write_stereo_file", "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm")
_SIDE = re.compile(r"left|right", re.IGNORECASE)
#: Live loop: a view is new when its corners moved this fraction of the image diagonal (mean) since the last one.
NOVELTY_FRACTION = 0.04


class StereoInputError(HandEyeError):
    """The pairs cannot be read or matched (no images, unmatched names, different sizes)."""


class StereoUsageError(UsageError, StereoInputError):
    """The sources of pairs are given wrongly (a folder and patterns together, or none)."""


@dataclass(frozen=True)
class StereoCalibrationConfig:
    """What ``handeye stereo calibrate`` was asked to do.

    Attributes
    ----------
    output : Path
        The stereo model to write (OpenCV FileStorage YAML).
    board : BoardGeometry
        Inner corners and square size (mm).
    images : Path, optional
        A folder of pairs.
    left, right : str, optional
        Glob patterns of the left and right images.
    camera : str, optional
        A camera back end for live capture (``xb3``, ``mock``).
    pairs : int
        Live: pairs to collect at least (the loop also waits for a complete coverage).
    max_grabs : int
        Live: frames to grab at most.
    save_images : Path, optional
        Live: folder for the accepted pairs (``NNN_left.png``, ``NNN_right.png``).
    swap : bool
        The images given as left are the right camera's.
    distortion : str
        Distortion model (``k1k2p1p2k3``, ``k1k2p1p2``, ``rational``).
    refine : bool
        Try the joint refinement of intrinsics and extrinsics.
    factory : Path, optional
        A Triclops file (``.cal`` or YAML/INI values) to compare with.
    report : Path, optional
        JSON report (default: the output with ``.json``).
    coverage_map : Path, optional
        Coverage map PNG (default: ``<output stem>_coverage.png``).
    """

    output: Path
    board: BoardGeometry
    images: Path | None = None
    left: str | None = None
    right: str | None = None
    camera: str | None = None
    pairs: int = 20
    max_grabs: int = 600
    save_images: Path | None = None
    swap: bool = False
    distortion: str = "k1k2p1p2k3"
    refine: bool = True
    factory: Path | None = None
    report: Path | None = None
    coverage_map: Path | None = None

    @property
    def report_path(self) -> Path:
        return Path(self.report) if self.report else Path(self.output).with_suffix(".json")

    @property
    def coverage_path(self) -> Path:
        out = Path(self.output)
        return Path(self.coverage_map) if self.coverage_map else out.with_name(out.stem + "_coverage.png")


@dataclass
class StereoCalibrationRun:
    """What a run produced: the calibration, its coverage, the files written, the factory comparison."""

    calibration: object
    coverage: object
    files: dict
    source: str
    pairs_given: int
    factory: dict | None = None
    seconds: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------- pairs from files

def _key(path: Path, root: Path | None = None) -> str | None:
    text = str(path.relative_to(root)) if root is not None else path.name
    return _SIDE.sub("*", text, count=1) if _SIDE.search(text) else None


def _pair_name(key: str) -> str:
    stem = Path(key).with_suffix("").as_posix().replace("*", "")
    stem = re.sub(r"[_\-. /]+", "_", stem).strip("_")
    return stem or "pair"


def _images_in(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)


def find_pairs(images=None, left=None, right=None, swap: bool = False) -> list[tuple[str, Path, Path]]:
    """``(name, left_path, right_path)`` of every pair in a folder or two glob patterns (module docstring).

    Raises
    ------
    StereoInputError
        Nothing found, unmatched images, or both a folder and globs given.
    """
    if images is not None and (left or right):
        raise StereoUsageError("give either a folder (--images) or --left and --right patterns, not both")
    if images is not None:
        folder = Path(images)
        if not folder.is_dir():
            raise StereoInputError(f"{folder} is not a folder of image pairs")
        if (folder / "images").is_dir() and not any(_key(p, folder) for p in _images_in(folder) if p.parent == folder):
            folder = folder / "images"
        files = _images_in(folder)
        # a name with left (right) in it always has a key (_SIDE finds it)
        lefts = {k: p for p in files if re.search("left", str(p.relative_to(folder)), re.I) and (k := _key(p, folder))}
        rights = {k: p for p in files if re.search("right", str(p.relative_to(folder)), re.I) and (k := _key(p, folder))}
        where = str(folder)
    elif left and right:
        lfiles = sorted(Path(p) for p in globlib.glob(os.path.expanduser(left), recursive=True) if Path(p).is_file())
        rfiles = sorted(Path(p) for p in globlib.glob(os.path.expanduser(right), recursive=True) if Path(p).is_file())
        if not lfiles or not rfiles:
            raise StereoInputError(f"no file matches {left if not lfiles else right!r}: check the pattern (quote it so "
                                   "the shell does not expand it)")
        lkeys, rkeys = [_key(p) for p in lfiles], [_key(p) for p in rfiles]
        lefts = {k: p for k, p in zip(lkeys, lfiles) if k is not None}
        rights = {k: p for k, p in zip(rkeys, rfiles) if k is not None}
        if None in lkeys or None in rkeys or not set(lefts) & set(rights):
            # the names do not say left/right alike: pair in sorted order
            if len(lfiles) != len(rfiles):
                raise StereoInputError(f"{len(lfiles)} left and {len(rfiles)} right images, and their names do not pair "
                                       "them: give as many of each, or name them *left* / *right*")
            lefts = {f"#{k:03d}": p for k, p in enumerate(lfiles)}
            rights = {f"#{k:03d}": p for k, p in enumerate(rfiles)}
        where = f"{left} / {right}"
    else:
        raise StereoUsageError("give image pairs: --images FOLDER, or --left 'L*.png' --right 'R*.png', or --camera")
    unmatched = sorted(set(lefts) ^ set(rights))
    if unmatched:
        k = unmatched[0]
        missing, have = ("right", lefts[k]) if k in lefts else ("left", rights[k])
        raise StereoInputError(f"{have} has no {missing} image beside it ({len(unmatched)} unmatched in {where}): "
                               f"name pairs alike, e.g. 000_left.png and 000_right.png")
    if not lefts:
        raise StereoInputError(f"no image pairs in {where}: name them *left* / *right* ({', '.join(IMAGE_SUFFIXES)})")
    out = []
    for k in sorted(lefts):
        if k.startswith("#"):  # paired by order: the common file stem, else the number
            name = lefts[k].stem if lefts[k].stem == rights[k].stem else k[1:]
        else:
            name = _pair_name(k)
        l_path, r_path = (rights[k], lefts[k]) if swap else (lefts[k], rights[k])
        out.append((name, l_path, r_path))
    names = [n for n, _, _ in out]
    if len(set(names)) != len(names):
        out = [(f"{i:03d}_{n}", a, b) for i, (n, a, b) in enumerate(out)]
    return out


def _detect(image, board, what: str):
    """``(corners or None, note, ids or None)`` of one image for calibration (corners off the grid leave it
    out; ids of a ChArUco board's corners, which may be part of it)."""
    from ..drivers import detect_board
    from ..drivers import BoardNotFound

    if getattr(board, "kind", "checkerboard") == "charuco":
        return _detect_charuco(image, board, what)
    try:
        det = detect_board(image, board, what=what)
    except BoardNotFound as exc:
        return None, str(exc), None
    if det.off_grid:
        return None, det.off_grid_message(what), None
    return det.corners_px, "", None


def _detect_charuco(image, board, what: str):
    """``(corners or None, note, ids or None)`` of a ChArUco board for calibration: OpenCV's corners by id, the
    whole board or part of it; a view whose corners cannot fix the board's pose (``geometry.view_refusal``:
    too few, too little of the board) is left out saying why."""
    from ..drivers import detect_charuco
    from ..drivers import BoardNotFound
    from ..geometry import view_refusal

    try:
        det = detect_charuco(image, board, what)
    except BoardNotFound as exc:
        return None, str(exc), None
    ids = np.asarray(det.ids, int)
    why = view_refusal(ids, board)
    if why:
        return None, f"{what}: {why}", None
    return det.corners_px, "", ids


#: Pairs searched before a board size found in none of their images is refused (a wrong ``--board``).
EARLY_PAIRS = 3
_OTHER_SIZE = re.compile(r"has (\d+)x(\d+) inner corners, not")


def _no_board_message(board: BoardGeometry, views) -> str:
    """The refusal when no image of the first pairs shows a board of ``board``'s size: the size the
    detector saw instead, when it saw one."""
    nx, ny = board.corners
    seen = Counter(found.groups() for v in views for note in (v.left_note, v.right_note)
                   for found in [_OTHER_SIZE.search(note or "")] if found)
    if seen:
        (a, b), count = seen.most_common(1)[0]
        hint = f" (they show a board of {a}x{b} inner corners, in {count} images: give --board {a}x{b})"
    else:
        hint = " (inner corners, long side first: 9x6 for a board of 10x7 squares) and that the whole board is in view"
    return f"no checkerboard of {nx}x{ny} inner corners found in the first {len(views)} pairs: check --board{hint}"


def detect_pairs(pairs, board: BoardGeometry, update: Callable | None = None) -> tuple[list, tuple]:
    """Detect the board in every pair of files; returns ``(views, image_size)``.

    Raises
    ------
    StereoInputError
        An image cannot be read, the images differ in size, or none of the first :data:`EARLY_PAIRS`
        pairs shows a board of ``board``'s size (a wrong ``--board``: refused before the other pairs
        are searched, which takes seconds an image when the board is not found).
    """
    from ..drivers import ViewCorners
    from ..drivers import decode_image, read_image_bytes

    views, size = [], None
    for k, (name, lpath, rpath) in enumerate(pairs):
        images = []
        for path in (lpath, rpath):
            image = decode_image(read_image_bytes(path), str(path))
            this = (image.shape[1], image.shape[0])
            if size is None:
                size = this
            elif this != size:
                raise StereoInputError(f"{path} is {this[0]}x{this[1]} but the first image is {size[0]}x{size[1]}: "
                                       "every image of a calibration must have the same size")
            images.append(image)
        left, lnote, lids = _detect(images[0], board, "left image")
        right, rnote, rids = _detect(images[1], board, "right image")
        views.append(ViewCorners(name, left, right, lnote, rnote, lids, rids))
        if update:
            update(k + 1, len(pairs), f"pair {name}")
        if k + 1 == min(EARLY_PAIRS, len(pairs)) and all(v.left is None and v.right is None for v in views):
            raise StereoInputError(_no_board_message(board, views))
    if size is None:  # find_pairs gives at least one pair
        raise StereoInputError("no image pairs to find the board in")
    return views, size


# ----------------------------------------------------------------------------------- live


def _pose_guess(corners, board, model):
    from ..drivers import board_pose_from_corners

    try:
        return board_pose_from_corners(corners, board, model.K1)[0]
    except HandEyeError:
        return None


def _detect_both(left, right, board) -> dict:
    """``{"left": corners or None, "right": corners or None}`` with the live loop's quick search
    (a board with corners off its grid counts as not found)."""
    from ..drivers import detect_board
    from ..drivers import BoardNotFound

    found = {}
    for side, image in (("left", left), ("right", right)):
        try:
            det = detect_board(image, board, search="fast", what=f"{side} image")
            found[side] = None if det.off_grid else det.corners_px
        except BoardNotFound:
            found[side] = None
    return found


def _save_pair(save, name: str, left, right) -> None:
    import cv2

    for side, image in (("left", left), ("right", right)):
        ok, data = cv2.imencode(".png", image)
        _write_bytes(save / f"{name}_{side}.png", data.tobytes())


def _view_line(name: str, found: dict, pairs: int, coverage, hint, wanted: int) -> str:
    both = found["left"] is not None and found["right"] is not None
    state = "pair" if both else f"{'left' if found['left'] is not None else 'right'} image only"
    return (f"view {name} ({state}): {pairs} pair{'' if pairs == 1 else 's'}; {coverage.summary()}"
            + (f"; next: {hint.text}" if hint else "" if pairs >= wanted else "; next: any new place and tilt"))


def capture_live(camera, config: StereoCalibrationConfig, say: Callable = print,
                 follow: Callable | None = None, update: Callable | None = None) -> tuple[list, tuple, object]:
    """The guided loop: grab, detect, keep new views, say where to hold the board next.

    Parameters
    ----------
    camera : Camera
        A connected back end of ``drivers.camera``.
    config : StereoCalibrationConfig
        ``pairs``, ``max_grabs``, ``save_images``, ``board``, ``swap``.
    say : callable
        Prints one line for the operator.
    follow : callable, optional
        Called with each hint (a simulated operator moves the mock board with it).
    update : callable, optional
        Progress: ``update(done, total, label)``.

    Returns
    -------
    views : list of ViewCorners
    image_size : (width, height)
    coverage : Coverage
        The live coverage (board poses from the nominal XB3 model: enough for the tilt classes).
    """
    from ..drivers import Coverage
    from ..drivers import nominal_xb3_model
    from ..drivers import ViewCorners

    follow = follow or (lambda hint: None)
    views, coverage, model, last, size, hint = [], None, None, None, None, None
    pairs, missing_said = 0, False
    save = make_folder(config.save_images) if config.save_images else None
    for _ in range(config.max_grabs):
        if coverage is not None and pairs >= config.pairs and coverage.complete:
            break
        frame = camera.grab()
        left, right = (frame.right, frame.left) if config.swap else (frame.left, frame.right)
        if coverage is None:
            size = (left.shape[1], left.shape[0])
            coverage, model = Coverage(size), nominal_xb3_model(*size)
            hint = coverage.next_hint()
            if hint is not None:  # an empty coverage always has a next place
                say(f"next: {hint.text}")
            follow(hint)
            continue
        found = _detect_both(left, right, config.board)
        if found["left"] is None and found["right"] is None:
            if not missing_said:
                say("no board in view: hold the whole board, with its white margin, in front of the cameras")
                missing_said = True
            follow(hint)
            continue
        missing_said = False
        ref = found["left"] if found["left"] is not None else found["right"]
        if (last is not None and size is not None and last.shape == ref.shape
                and float(np.mean(np.linalg.norm(ref - last, axis=1))) < NOVELTY_FRACTION * float(np.hypot(*size))):
            follow(hint)
            continue  # the same view again: wait for the board to move
        last, name = ref, f"{len(views):03d}"
        alone = "board not in this image (a view for the other camera alone)"
        views.append(ViewCorners(name, found["left"], found["right"], "" if found["left"] is not None else alone,
                                 "" if found["right"] is not None else alone))
        coverage.add(found["left"], found["right"],
                     _pose_guess(ref, config.board, model) if found["left"] is not None else None)
        pairs += found["left"] is not None and found["right"] is not None
        if save is not None:
            _save_pair(save, name, left, right)
        hint = coverage.next_hint()
        say(_view_line(name, found, pairs, coverage, hint, config.pairs))
        if update:
            update(min(pairs, config.pairs), config.pairs, f"{pairs} pairs")
        follow(hint)
    if coverage is None or size is None:  # the first frame sets both
        raise StereoInputError("the camera gave no frame")
    if pairs < config.pairs or not coverage.complete:
        say(f"stopped after {config.max_grabs} frames with {pairs} pair{'' if pairs == 1 else 's'}; {coverage.summary()}")
    return views, size, coverage


# ----------------------------------------------------------------------------------- files


def _write_bytes(path: Path, data: bytes) -> Path:
    """Write ``data`` atomically (temporary file in the same folder, then rename)."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a folder; give a file name")
    folder = make_folder(path.parent)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        raise write_failure(path, exc) from None
    return path


def write_stereo_file(path, model, extra: dict | None = None) -> Path:
    """Write the stereo model as OpenCV FileStorage YAML (the keys of ``load_stereo_model``, plus
    ``extra`` numbers and strings after them), atomically."""
    from ..drivers import save_stereo_model

    path = Path(path)
    folder = make_folder(path.parent)
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        temp = Path(tmp) / "stereo.yaml"
        save_stereo_model(temp, model, extra=extra)
        return _write_bytes(path, temp.read_bytes())


def _check_factory(path) -> None:
    """Read the factory file before any work: a bad file is refused at once (a file without the image
    size is read again with the images' size after the capture)."""
    from ..drivers import StereoModelError
    from ..drivers import read_triclops_model

    try:
        read_triclops_model(path)
    except StereoModelError as exc:
        if "no SensorResolution" not in str(exc) and "give image_width" not in str(exc):
            raise


def _factory_comparison(path, calibration) -> dict:
    from ..drivers import read_triclops_model

    factory = read_triclops_model(path, size=calibration.model.image_size)
    m = calibration.model
    out = {
        "file": str(path),
        "factory": {"f_px": float(factory.K1[0, 0]), "cx": float(factory.K1[0, 2]), "cy": float(factory.K1[1, 2]),
                    "baseline_mm": factory.baseline_mm},
        "calibrated": {"f_px": [float(m.K1[0, 0]), float(m.K2[0, 0])], "baseline_mm": m.baseline_mm},
        "baseline_difference_percent": 100.0 * (m.baseline_mm / factory.baseline_mm - 1.0),
        "note": "the factory model is Triclops' rectified pinhole model; raw-image focal lengths differ by the "
                "rectification's scaling, the baseline should agree within about 1 %",
    }
    return out


def _coverage(views, result, size):
    """The coverage map's data: where the corners of each view were used (and, drawn in red, where the
    board was found but the view left out)."""
    from ..drivers import Coverage

    coverage = Coverage(size)
    for v, report in zip(views, result.views):
        pose = result.left.poses.get(v.name, result.right.poses.get(v.name))
        coverage.add(v.left if report.used_left else None, v.right if report.used_right else None, pose)
        for side in ("left", "right"):  # found but left out: drawn in red on the map
            if getattr(v, side) is not None and not getattr(report, f"used_{side}"):
                coverage.add(**{side: getattr(v, side)}, used=False)
    return coverage


def run_stereo_calibration(config: StereoCalibrationConfig, *, say: Callable = print, camera=None,
                           follow: Callable | None = None, progress=None) -> StereoCalibrationRun:
    """Collect the pairs (files or live), calibrate, write the model, the report and the coverage map.

    Parameters
    ----------
    config : StereoCalibrationConfig
    say : callable
        One line for the operator at a time.
    camera : Camera, optional
        A connected camera for live capture (else ``config.camera`` is opened with ``open_camera``).
    follow : callable, optional
        Live: called with each hint (the mock's simulated operator).
    progress : context manager factory, optional
        ``progress(title)`` yielding ``update(done, total, label)`` (``station.progress.progress_bar``).

    Raises
    ------
    HandEyeError
        One line: bad input, a calibration that cannot be made, a file that cannot be written.
    """
    from ..drivers import coverage_map
    from ..drivers import calibrate_stereo

    progress = progress or _no_progress
    for target in (config.output, config.report_path, config.coverage_path):
        if Path(target).is_dir():
            raise OutputError(f"cannot write {target}: it is a folder; give a file name")
    if config.factory:
        _check_factory(config.factory)
    seconds = {}
    start = time.perf_counter()
    if config.camera or camera is not None:
        from ..drivers import open_camera

        own = camera is None
        if camera is not None:
            cam = camera
        elif config.camera:
            cam = open_camera(config.camera)
        else:  # the branch is taken with a camera or config.camera
            raise StereoUsageError("give the camera back end (--camera)")
        try:
            with progress("stereo capture") as update:
                views, size, _ = capture_live(cam, config, say, follow, update)
        finally:
            if own:
                cam.close()
        source = f"live from the {config.camera or getattr(camera, 'name', 'camera')} camera"
    else:
        pairs = find_pairs(config.images, config.left, config.right, config.swap)
        say(f"{len(pairs)} pairs; finding the board in each image")
        with progress("detect") as update:
            views, size = detect_pairs(pairs, config.board, update)
        source = str(config.images) if config.images else f"{config.left} + {config.right}"
    seconds["collect"] = time.perf_counter() - start
    found = sum(v.left is not None and v.right is not None for v in views)
    say(f"board in both images of {found} of {len(views)} pairs; calibrating")
    t0 = time.perf_counter()
    result = calibrate_stereo(views, config.board, size, distortion=config.distortion, refine=config.refine,
                              name=f"stereo calibration of {source}")
    seconds["calibrate"] = time.perf_counter() - t0
    coverage = _coverage(views, result, size)
    factory = _factory_comparison(config.factory, result) if config.factory else None
    extra = {"rms_px": result.rms_px, "epipolar_rms_px": result.epipolar_rms_px, "baseline_mm": result.baseline_mm,
             "pairs_used": result.pairs_used, "calibrated_with": "handeye stereo calibrate",
             "calibrated_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    files = {"stereo": str(write_stereo_file(config.output, result.model, extra))}
    report = {"format": "handeye-stereo-calibration/1", "source": source, "pairs_given": len(views),
              "board": {"corners": list(config.board.corners), "square_mm": config.board.square_mm},
              "distortion_model": config.distortion, **result.to_json(), "coverage": coverage.to_json(),
              "factory": factory, "seconds": {k: round(v, 3) for k, v in seconds.items()}}
    files["report"] = str(write_text_atomic(config.report_path, json.dumps(report, indent=2, allow_nan=False) + "\n"))
    import cv2

    title = (f"{result.pairs_used} pairs, RMS {result.rms_px:.3f} px, epipolar {result.epipolar_rms_px:.3f} px, "
             f"baseline {result.baseline_mm:.2f} mm")
    ok, png = cv2.imencode(".png", coverage_map(coverage, title))
    files["coverage_map"] = str(_write_bytes(config.coverage_path, png.tobytes()))
    return StereoCalibrationRun(result, coverage, files, source, len(views), factory, seconds)


class _NoProgress:
    def __enter__(self):
        return lambda *a, **k: None

    def __exit__(self, *exc):
        return False


def _no_progress(title):
    return _NoProgress()
