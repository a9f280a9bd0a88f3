"""The factory (Triclops) calibration of a Bumblebee head as a nominal rectified stereo model.

Triclops stores the head's calibration in a ``.cal`` file (read out of the camera, or saved by
FlyCapture/Triclops tools) whose lens model is a warp grid that does not convert to OpenCV
distortion coefficients. What does convert is the *rectified* pinhole model Triclops gives for
its rectified images: one focal length, one image centre and the baseline, the same for both
cameras, no distortion, cameras side by side. That model is exact for images rectified by
Triclops and a nominal start (for a station without its own stereo calibration, or to compare a
calibration with) for raw frames.

Accepted inputs (:func:`read_triclops_model` tells them apart by their content):

1. A Triclops ``.cal`` file (text), whose header holds, one per line, a keyword and numbers::

       SensorResolution 1280 960      # W H of the sensor (pixels)
       FocalLength 0.768047 1.024063  # f / W and f / H (normalised; both give f in pixels)
       ImageCenter 0.503203 0.513958  # cx / W and cy / H (fractions of width and height)
       BaseLine 0.239983              # metres

   Other lines (``Version``, ``SerialNumber``, ``CameraConfiguration``, camera ids and positions,
   the warp grids) are ignored. Without ``SensorResolution`` give the image size (``size``).

2. The three values Triclops' API returns for a rectified resolution, as YAML (``key: value``) or
   INI (``key = value``, any or no ``[section]``)::

       image_width: 1280          # the rectified resolution (triclopsGetResolution gives rows, cols)
       image_height: 960
       focal_length: 983.1        # triclopsGetFocalLength: pixels at this resolution
       center_row: 493.4          # triclopsGetImageCenter(context, &centerRow, &centerCol): ROW first
       center_col: 643.6
       baseline: 0.23998          # triclopsGetBaseline: metres

   ``focal_length_px``, ``center_row_px``/``center_col_px``, ``baseline_m`` or ``baseline_mm`` are
   accepted too (``cx``/``cy`` for the columns and rows). Some Triclops versions return the centre
   (and the focal length) normalised by the image size; values of at most 1 (a focal length below 10)
   are read that way and the model's name says so.

The model (camera 1 = left, as everywhere in the project): ``K1 = K2 = [[f, 0, cx], [0, f, cy],
[0, 0, 1]]``, no distortion, ``R = I``, ``T = (-baseline_mm, 0, 0)`` (Triclops' reference is the
right camera; the rectified geometry is the same seen from either side). A model asked for at
another size is scaled keeping pixel centres: ``c' = (c + 0.5) s - 0.5``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import configparser
import re
from pathlib import Path

import numpy as np

from ...base import parse_yaml, read_file_bytes
from .errors import StereoModelError
from .stereo import StereoModel

if TYPE_CHECKING:
    import os

__all__ = ["TriclopsValues", "read_triclops_model", "parse_triclops_text", "rectified_model"]


class TriclopsValues(dict):
    """The rectified values read from a file: ``width``, ``height`` (px), ``f_px``, ``cx``, ``cy`` (px),
    ``baseline_mm``, ``source`` (``"cal"`` or ``"api"``) and ``normalised`` (values given as fractions)."""


_CAL_KEYS = {"sensorresolution", "focallength", "imagecenter", "baseline"}
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _cal_header(text: str) -> dict:
    """Keyword -> list of numbers for the ``.cal`` header lines we use (``BaseLine 0.24``)."""
    out = {}
    for line in text.splitlines():
        parts = re.split(r"[\s:=,]+", line.strip(), maxsplit=1)
        if len(parts) < 2 or parts[0].lower() not in _CAL_KEYS or parts[0].lower() in out:
            continue
        numbers = re.findall(_NUMBER, parts[1].split("#")[0])
        out[parts[0].lower()] = [float(v) for v in numbers]
    return out


def _scalar(value) -> float | None:
    """A number from a YAML/INI scalar (nothing else is looked at: lists and maps are skipped unread)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        return None
    try:
        number = float(str(value).split("#")[0].strip()[:64])
    except ValueError:
        return None
    return number if np.isfinite(number) else None


def _api_values(text: str) -> dict[str, float] | None:
    """Flat ``key -> number`` of a YAML or INI file; ``None`` when it is neither."""
    try:
        data = parse_yaml(text, "Triclops values", StereoModelError)
    except StereoModelError:
        data = None
    if not isinstance(data, dict):
        parser = configparser.ConfigParser()
        try:
            parser.read_string(text if text.lstrip().startswith("[") else "[triclops]\n" + text)
        except configparser.Error:
            return None
        data = {k: v for s in parser.sections() for k, v in parser.items(s)}
    flat = {}
    for key, value in data.items():
        if isinstance(value, dict):  # one level of nesting (e.g. a "triclops:" section)
            flat.update({str(k).lower(): v for k, v in value.items()})
        else:
            flat[str(key).lower()] = value
    out = {key: _scalar(value) for key, value in flat.items()}
    return {key: value for key, value in out.items() if value is not None}


def _pick(values: dict[str, float], *names: str) -> tuple[str | None, float | None]:
    for name in names:
        if name in values:
            return name, values[name]
    return None, None


def parse_triclops_text(text: str, where: str = "Triclops file", size: tuple[int, int] | None = None) -> TriclopsValues:
    """The rectified values of a ``.cal`` header or of a YAML/INI file of API values (see the module docstring).

    Parameters
    ----------
    text : str
    where : str
        Name of the file in messages.
    size : tuple of int, optional
        ``(width, height)`` when the file does not give it.

    Raises
    ------
    StereoModelError
        Missing or implausible values, with what to write.
    """
    header = _cal_header(text)
    if {"focallength", "imagecenter", "baseline"} <= set(header):
        fl, ic, bl = header["focallength"], header["imagecenter"], header["baseline"]
        res = header.get("sensorresolution", [])
        if len(res) >= 2:
            width, height = int(res[0]), int(res[1])
        elif size is not None:
            width, height = (int(v) for v in size)
        else:
            raise StereoModelError(f"{where}: no SensorResolution line; give the image size (--size WxH)")
        if len(fl) < 1 or len(ic) < 2 or len(bl) < 1:
            raise StereoModelError(f"{where}: FocalLength needs f/W (and f/H), ImageCenter cx/W and cy/H, BaseLine metres")
        values = TriclopsValues(width=width, height=height, f_px=fl[0] * width, cx=ic[0] * width, cy=ic[1] * height,
                                baseline_mm=bl[0] * 1000.0, source="cal", normalised=True)
        return _checked(values, where)
    api = _api_values(text)
    if not api:
        raise StereoModelError(f"{where}: neither a Triclops .cal file (FocalLength, ImageCenter, BaseLine lines) nor "
                               "YAML/INI with focal_length, center_row, center_col, baseline")
    missing = []
    _, f = _pick(api, "focal_length_px", "focal_length", "focallength", "f")
    _, row = _pick(api, "center_row_px", "center_row", "centerrow", "cy")
    _, col = _pick(api, "center_col_px", "center_col", "centercol", "cx")
    bkey, baseline = _pick(api, "baseline_mm", "baseline_m", "baseline")
    for name, value in (("focal_length", f), ("center_row", row), ("center_col", col), ("baseline", baseline)):
        if value is None:
            missing.append(name)
    if missing:
        raise StereoModelError(f"{where}: missing {', '.join(missing)} (Triclops gives focal_length in px, "
                               "center_row and center_col in px, baseline in metres)")
    assert f is not None and row is not None and col is not None and baseline is not None  # else missing above
    _, w = _pick(api, "image_width", "width", "cols", "ncols")
    _, h = _pick(api, "image_height", "height", "rows", "nrows")
    if w is None or h is None:
        if size is None:
            raise StereoModelError(f"{where}: give image_width and image_height (the rectified resolution), or --size WxH")
        w, h = size
    width, height = int(w), int(h)
    normalised = False
    if 0 < f < 10:  # f / W
        f, normalised = f * width, True
    if 0 < row <= 1 and 0 < col <= 1:  # fractions of the image size
        row, col, normalised = row * height, col * width, True
    if bkey == "baseline_mm":
        baseline_mm = baseline
    elif bkey == "baseline_m" or baseline < 5:
        baseline_mm = baseline * 1000.0
    else:
        raise StereoModelError(f"{where}: baseline {baseline:g} looks like millimetres, but Triclops gives metres; "
                               f"write baseline_mm: {baseline:g} (or baseline: {baseline / 1000:g})")
    values = TriclopsValues(width=width, height=height, f_px=float(f), cx=float(col), cy=float(row),
                            baseline_mm=float(baseline_mm), source="api", normalised=normalised)
    return _checked(values, where)


def _checked(v: TriclopsValues, where: str) -> TriclopsValues:
    w, h = v["width"], v["height"]
    if not (16 <= w <= 20000 and 16 <= h <= 20000):
        raise StereoModelError(f"{where}: image size {w}x{h} is not plausible")
    if not (0.1 * w < v["f_px"] < 20 * w):
        raise StereoModelError(f"{where}: focal length {v['f_px']:.1f} px is not plausible for a {w}x{h} image")
    if abs(v["cx"] - w / 2) > 0.1 * w or abs(v["cy"] - h / 2) > 0.1 * h:  # factory centres sit within ~20 px
        raise StereoModelError(
            f"{where}: image centre ({v['cx']:.1f}, {v['cy']:.1f}) px is far from the middle of a {w}x{h} image: "
            "check the row/column order (Triclops gives the ROW first) and the units")
    if not (5.0 < v["baseline_mm"] < 5000.0):
        raise StereoModelError(f"{where}: baseline {v['baseline_mm']:.3g} mm is not plausible (Triclops gives metres)")
    return v


def rectified_model(values: TriclopsValues, size: tuple[int, int] | None = None, name: str = "") -> StereoModel:
    """The rectified stereo model of ``values``, scaled to ``size = (width, height)`` if given."""
    w0, h0 = values["width"], values["height"]
    width, height = (int(s) for s in size) if size is not None else (w0, h0)
    sx, sy = width / w0, height / h0
    k = np.array([[values["f_px"] * sx, 0.0, (values["cx"] + 0.5) * sx - 0.5],
                  [0.0, values["f_px"] * sy, (values["cy"] + 0.5) * sy - 0.5],
                  [0.0, 0.0, 1.0]])
    label = name or "Triclops rectified model"
    label += (f" (f {k[0, 0]:.1f} px, centre ({k[0, 2]:.1f}, {k[1, 2]:.1f}), baseline {values['baseline_mm']:.2f} mm"
              f"{', read from normalised values' if values.get('normalised') else ''})")
    return StereoModel((width, height), k, np.zeros(5), k.copy(), np.zeros(5), np.eye(3),
                       np.array([-values["baseline_mm"], 0.0, 0.0]), name=label)


def read_triclops_model(path: str | os.PathLike[str], size: tuple[int, int] | None = None) -> StereoModel:
    """The rectified stereo model of a Triclops ``.cal`` file or a YAML/INI file of Triclops API values.

    Parameters
    ----------
    path : path-like
    size : tuple of int, optional
        ``(width, height)`` of the images the model is for; the file's size when omitted (and
        needed when the file gives none).

    Raises
    ------
    StereoModelError
    """
    path = Path(path)
    data = read_file_bytes(path, "Triclops calibration", StereoModelError, missing=f"Triclops file not found: {path}")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:  # a .cal header is ASCII; what follows it may not be
        text = data.decode("latin-1")
    if "\x00" in text[:4096]:
        raise StereoModelError(f"{path} is a binary file, not a Triclops .cal text file or YAML/INI values")
    values = parse_triclops_text(text, str(path), size)
    return rectified_model(values, size, name=f"Triclops rectified model from {path.name}")
