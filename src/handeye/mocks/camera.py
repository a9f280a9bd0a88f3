"""A mock Bumblebee XB3: renders the printed board into the three sensors and packs a real frame.

Rendering, per view (left, centre, right) through the stereo model (``StereoModel.view``):

1. Every pixel centre ``(x, y)`` (integers, OpenCV convention) is turned into a normalised ray
   (``K^-1``, or ``undistortPointsIter`` when the view has lens distortion, computed once per
   camera) and intersected with the board plane, giving board coordinates ``(u, v)`` in mm; the
   printed sheet's reflectance there (black or white square, white margin, grey background) is the
   pixel's value.
2. Pixels whose footprint straddles an edge (a square edge or the sheet's border) are
   supersampled on an ``s x s`` grid inside the pixel: sub-sample ``k`` of pixel ``x`` sits at
   ``x + (k + 0.5) / s - 0.5``, which is the high-resolution pixel centre mapping
   ``x_hi = s * x + (s - 1) / 2`` (so the anti-aliased image has no (s-1)/(2s)-pixel bias). Each
   sub-sample is jittered inside its cell (stratified sampling), so the box filter is estimated
   without a bias tied to the edge's phase. Only edge pixels are supersampled, which keeps a frame
   cheap.
3. A slight Gaussian blur (optics), then per-channel gains of the colour filter array, sensor noise
   (read noise plus shot noise) and 8-bit quantisation; colour heads sample a GBRG mosaic.
4. The three planes are packed into the XB3 Format_7 3-sensor RGB8 layout (byte 0 = right,
   1 = centre, 2 = left) and decoded by the real driver code (``drivers.camera.decode``), so every
   mock frame goes through the same decoding path as a real one.

:class:`MockCamera` is the ``"mock"`` back end of ``open_camera``: its scene (board pose in the
base frame, camera pose provider, e.g. the simulated robot's flange pose times the hidden camera
mount) can be changed between grabs.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, replace
from collections.abc import Sequence
from typing import TYPE_CHECKING, Callable

import cv2
import numpy as np
import numpy.typing as npt

from ..drivers import decode_xb3_frame, pack_rgb8
from ..drivers import CameraError
from ..drivers import Camera, StereoFrame
from ..drivers import StereoModel, nominal_xb3_model
from .world import Lighting, PrintedBoard, hard_lighting

if TYPE_CHECKING:
    from .printed_targets import Occlusion

__all__ = ["RenderOptions", "ViewRenderer", "StereoRenderer", "MockCamera", "render_views", "render_xb3_frame",
           "hard_options"]

VIEWS = ("left", "centre", "right")


@dataclass(frozen=True)
class RenderOptions:
    """How the mock sensor images a scene.

    Attributes
    ----------
    supersample : int
        ``s``: edge pixels are sampled on an ``s x s`` grid.
    jitter : bool
        Jitter each sub-sample inside its cell (stratified sampling); ``False`` puts it at the cell centre.
    blur_sigma_px : float
        Gaussian blur of the optics (0 = none).
    read_noise_dn : float
        Standard deviation of the read noise (grey levels).
    shot_noise : float
        Shot-noise variance per grey level (variance = read^2 + shot_noise * value).
    black, white, background : float
        Grey levels of black squares, white paper and the background behind the sheet.
    lighting : Lighting or None
        Uneven light, glare, shadow and vignetting (:class:`~handeye.mocks.world.Lighting`); ``None`` = even.
    jpeg_quality : int
        Grey image pairs (:meth:`StereoRenderer.gray_pair`) go through JPEG at this quality, as
        images saved by a frame grabber or a phone would (0 = lossless, no JPEG).
    channel_gains : tuple of float
        Response of the R, G and B filters to the (neutral) scene, before white balance.
    colour : bool
        Colour head (GBRG mosaic) or mono head.
    """

    supersample: int = 6
    jitter: bool = True
    blur_sigma_px: float = 0.6
    read_noise_dn: float = 1.0
    shot_noise: float = 0.02
    black: float = 28.0
    white: float = 215.0
    background: float = 105.0
    channel_gains: tuple = (0.80, 1.0, 0.70)
    colour: bool = True
    lighting: Lighting | None = None
    jpeg_quality: int = 0


def _view_pose(target2cam: np.ndarray, r: np.ndarray, t: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = r @ target2cam[:3, :3]
    out[:3, 3] = r @ target2cam[:3, 3] + t
    return out


class ViewRenderer:
    """Renders the board as one camera (K, D) sees it; keeps the per-camera ray map.

    Parameters
    ----------
    camera_matrix : ndarray, shape (3, 3)
    dist_coeffs : ndarray
    image_size : tuple of int
        ``(width, height)``.
    """

    def __init__(self, camera_matrix: npt.ArrayLike, dist_coeffs: npt.ArrayLike, image_size: Sequence[int]):
        self.k = np.asarray(camera_matrix, float)
        self.d = np.asarray(dist_coeffs, float).ravel()
        self.size = (int(image_size[0]), int(image_size[1]))
        self.distorted = bool(np.any(self.d != 0))
        self._ray_cache = None
        self._vig_key, self._vig = None, None
        w, h = self.size
        self._bg_ramp = (0.9 + 0.2 * np.arange(w, dtype=np.float32) / w)[None, :]

    # ----------------------------------------------------------------- rays
    def _ray_map(self) -> np.ndarray:
        """Normalised undistorted coordinates of every pixel centre, ``(h, w, 2)`` float64 (distorted cameras)."""
        if self._ray_cache is None:
            w, h = self.size
            xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
            pts = np.stack([xs, ys], axis=-1).reshape(-1, 1, 2)
            crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 1e-12)
            # R and P None (identity: normalised coordinates), as OpenCV documents; its stubs do not allow None
            rays = cv2.undistortPointsIter(pts, self.k, self.d, None, None, crit)  # pyright: ignore[reportCallIssue, reportArgumentType]
            self._ray_cache = rays.reshape(h, w, 2)
        return self._ray_cache

    def _rays(self, x0: int, x1: int, y0: int, y1: int) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Rays ``(xn, yn)`` (float32) of the pixel block, and the constant ray Jacobian per pixel
        for undistorted cameras (``None`` for distorted ones: use the block's differences)."""
        if not self.distorted:
            fx, skew, cx = self.k[0]
            fy, cy = self.k[1, 1], self.k[1, 2]
            ys = ((np.arange(y0, y1, dtype=np.float64) - cy) / fy)[:, None]
            xs = np.arange(x0, x1, dtype=np.float64)[None, :]
            xn = ((xs - cx - skew * ys) / fx).astype(np.float32)
            jac = np.array([[1 / fx, -skew / (fx * fy)], [0.0, 1 / fy]])
            return xn, ys.astype(np.float32), jac
        block = self._ray_map()[y0:y1, x0:x1]
        return block[..., 0].astype(np.float32), block[..., 1].astype(np.float32), None

    # ---------------------------------------------------------------- scene
    def render(self, target2view: np.ndarray, board: PrintedBoard, options: RenderOptions, rng: np.random.Generator,
               band: tuple[float, float] | None = None) -> np.ndarray:
        """Ideal (noise-free, unblurred) image ``(h, w)`` float32 of the board seen from ``target2view``
        (``band``: ``(u0, u1)`` mm of the board covered by an occluder, ``mocks.printed_targets``)."""
        image = self._render(target2view, board, options, rng, band)
        if options.lighting is not None and options.lighting.vignetting:
            image *= self._vignetting(options.lighting)
        return image

    def _vignetting(self, lighting: Lighting) -> np.ndarray:
        key = ("vignetting", lighting.vignetting)
        vignetting = self._vig
        if self._vig_key != key or vignetting is None:
            vignetting = lighting.in_image(*self.size)
            self._vig_key, self._vig = key, vignetting
        return vignetting

    def _render(self, target2view, board, options, rng, band=None) -> np.ndarray:
        w, h = self.size
        image = np.empty((h, w), np.float32)
        image[:] = options.background * self._bg_ramp
        outline = board.outline(24)
        cam = outline @ target2view[:3, :3].T + target2view[:3, 3]
        if np.all(cam[:, 2] <= 0):
            return image
        if np.any(cam[:, 2] <= 0):
            x0, x1, y0, y1 = 0, w, 0, h  # sheet crosses the camera plane: render everything
        else:
            px, _ = cv2.projectPoints(cam, np.zeros(3), np.zeros(3), self.k, self.d)
            px = px.reshape(-1, 2)
            x0 = int(np.clip(np.floor(px[:, 0].min()) - 3, 0, w))
            x1 = int(np.clip(np.ceil(px[:, 0].max()) + 4, 0, w))
            y0 = int(np.clip(np.floor(px[:, 1].min()) - 3, 0, h))
            y1 = int(np.clip(np.ceil(px[:, 1].max()) + 4, 0, h))
        if x1 - x0 < 3 or y1 - y0 < 3:
            return image
        # Board plane -> normalised image is the homography [r1 r2 t]; its inverse maps rays to (u, v).
        inv = np.linalg.inv(np.column_stack([target2view[:3, 0], target2view[:3, 1], target2view[:3, 3]]))
        xn, yn, jac = self._rays(x0, x1, y0, y1)
        u, v, front = _board_coords(inv, xn, yn)
        labels = _labels(u, v, front, board, band)
        bg = options.background * self._bg_ramp[:, x0:x1]
        levels = np.array([0.0, options.white, options.black, OCCLUDER_LEVEL], np.float32)
        block = np.where(labels == 0, bg, levels[labels])
        lighting = options.lighting
        lit = lighting is not None and not lighting.is_even
        if lit and lighting is not None:  # the light on the sheet, per pixel centre (smooth at the scale of a pixel)
            u, v = np.broadcast_arrays(u, v)
            gain, added = lighting.on_board(u, v, board)
            block = np.where(labels == 0, block, block * gain + added)
        # A straight edge through a pixel's footprint separates some of the 3x3 neighbouring pixel
        # centres: pixels whose neighbourhood holds two labels are the ones to supersample.
        kernel = np.ones((3, 3), np.uint8)
        edge = cv2.dilate(labels, kernel) != cv2.erode(labels, kernel)
        ey, ex = np.nonzero(edge)
        if len(ey):
            s = int(options.supersample)
            cells = (np.arange(s) + 0.5) / s - 0.5          # x_hi = s*x + (s-1)/2, in pixel units
            ox, oy = np.meshgrid(cells, cells)
            ox, oy = ox.ravel().astype(np.float32), oy.ravel().astype(np.float32)
            n = len(ey)
            ox, oy = _sample_offsets(ox, oy, n, s, rng if options.jitter else None)
            if jac is not None:  # px + J @ offset, summed in this order (in place: same bits, fewer passes)
                sx = np.float32(jac[0, 0]) * ox
                sx += xn[0 if xn.shape[0] == 1 else ey, ex][:, None]
                sx += np.float32(jac[0, 1]) * oy
                sy = np.float32(jac[1, 1]) * oy
                sy += yn[ey, 0 if yn.shape[1] == 1 else ex][:, None]
            else:  # linearised ray map inside the pixel (the distortion is smooth at this scale)
                gx_y, gx_x = np.gradient(xn)
                gy_y, gy_x = np.gradient(yn)
                sx = xn[ey, ex][:, None] + gx_x[ey, ex][:, None] * ox + gx_y[ey, ex][:, None] * oy
                sy = yn[ey, ex][:, None] + gy_x[ey, ex][:, None] * ox + gy_y[ey, ex][:, None] * oy
            sub = _labels(*_board_coords(inv, sx, sy), board, band)
            sheet = levels[sub]
            if lit:
                sheet = sheet * gain[ey, ex][:, None] + added[ey, ex][:, None]
            values = np.where(sub == 0, bg[0, ex][:, None], sheet)
            block[ey, ex] = values.mean(axis=1)
        image[y0:y1, x0:x1] = block
        return image


def _sample_offsets(ox, oy, n: int, s: int, rng):
    """Sub-sample offsets ``(n, s * s)`` float32 of ``n`` edge pixels: the cell centres ``ox``, ``oy``
    (``(s * s,)``), each jittered inside its cell by ``(U - 0.5) / s`` when ``rng`` is given (x first)."""
    if rng is None:
        return np.tile(ox, (n, 1)), np.tile(oy, (n, 1))
    out = []
    for centre in (ox, oy):
        jitter = rng.random((n, s * s), dtype=np.float32)
        jitter -= 0.5
        jitter /= s
        jitter += centre
        out.append(jitter)
    return out[0], out[1]


def _board_coords(inv: np.ndarray, xn, yn):
    """Board coordinates (mm) where rays ``(xn, yn, 1)`` meet the board plane, and whether in front.

    Each coordinate is ``(i0 * xn + i1 * yn + i2) / (i6 * xn + i7 * yn + i8)`` in float32, evaluated
    in that order (the products, then the sums left to right, then the reciprocal of the denominator
    times the numerator) with the results written in place: the images depend on these bits.
    """
    i = inv.astype(np.float32)

    def affine(row):
        out = i[row, 0] * xn + i[row, 1] * yn  # xn or yn may be a row or a column (undistorted rays)
        out += i[row, 2]
        return out

    hw = affine(2)
    front = hw > 1e-9
    hw[~front] = 1.0
    rw = np.divide(1.0, hw, out=hw)
    u = affine(0)
    u *= rw
    v = affine(1)
    v *= rw
    return u, v, front


#: Grey level of the occluding band of ``mock.occlude`` (a dull clamp or probe).
OCCLUDER_LEVEL = 70.0


def _labels(u, v, front, board: PrintedBoard, band=None) -> np.ndarray:
    """0 = background, 1 = white paper, 2 = black square (3 = the occluder over ``band``); square ``(a, b)``
    (``a = floor(u / sq) + 1``, ``b = floor(v / sq) + 1``) is black when ``a + b`` is even (conventions: the
    square between corners 0, 1, nx, nx + 1 is black). A ChArUco sheet is OpenCV's print
    (:func:`~handeye.mocks.printed_targets.printed_labels`), a circle grid black discs
    (:func:`~handeye.mocks.printed_targets.circle_labels`)."""
    if band is not None or getattr(board.geometry, "kind", "checkerboard") != "checkerboard":
        from .printed_targets import circle_labels, occluded, printed_labels  # noqa: PLC0415

        kind = getattr(board.geometry, "kind", "")
        plain = printed_labels(u, v, front, board) if kind == "charuco" else circle_labels(u, v, front, board) \
            if kind == "circles" else _labels(u, v, front, board)
        return occluded(plain, u, band)
    cu0, cu1, cv0, cv1 = board.checker_bounds()
    su0, su1, sv0, sv1 = board.sheet_bounds()
    sq = np.float32(board.square_mm)
    on_sheet = front & (u >= su0) & (u <= su1) & (v >= sv0) & (v <= sv1)
    black = (u >= cu0) & (u < cu1) & (v >= cv0) & (v < cv1)
    parity = np.floor(u / sq)
    parity += np.floor(v / sq)  # (a - 1) + (b - 1), a whole number: even <=> parity - 2 * floor(parity / 2) == 0
    half = np.multiply(parity, np.float32(0.5))
    np.floor(half, out=half)
    half *= np.float32(2.0)
    parity -= half  # (float ``% 2`` gives the same bits, NaN included, at ten times the cost)
    black &= parity == 0
    return on_sheet.astype(np.uint8) + black.astype(np.uint8)


_GAINS: dict = {}


def _gain_map(shape, gains) -> np.ndarray:
    """Per-pixel colour filter gains of a GBRG mosaic (first row G B, second row R G)."""
    key = (shape, tuple(gains))
    if key not in _GAINS:
        r, g, b = gains
        tile = np.array([[g, b], [r, g]], np.float32)
        h, w = shape
        _GAINS[key] = np.tile(tile, (h // 2 + 1, w // 2 + 1))[:h, :w].copy()
    return _GAINS[key]


def _sensor(image: np.ndarray, options: RenderOptions, rng) -> np.ndarray:
    """Blur, colour filter gains (GBRG), noise and 8-bit quantisation of an ideal image.

    The Gaussian noise comes from OpenCV's generator (three times faster than numpy's here),
    seeded from ``rng`` so that a seeded renderer is reproducible.
    """
    if options.blur_sigma_px > 0:
        image = cv2.GaussianBlur(image, (0, 0), options.blur_sigma_px)
    if options.colour:
        image = image * _gain_map(image.shape, options.channel_gains)
    # sqrt(read^2 + shot * max(image, 0)), in place (the same float32 operations, one array)
    sigma = np.maximum(image, 0)
    sigma *= np.float32(options.shot_noise)
    sigma += np.float32(options.read_noise_dn**2)
    np.sqrt(sigma, out=sigma)
    noise = np.empty(image.shape, np.float32)
    cv2.setRNGSeed(int(rng.integers(0, 2**31 - 1)))
    cv2.randn(noise, 0.0, 1.0)  # pyright: ignore[reportCallIssue, reportArgumentType]  # scalar mean and sigma, as OpenCV takes them
    noise *= sigma
    noise += image
    np.maximum(noise, 0.0, out=noise)
    return cv2.convertScaleAbs(noise)  # rounds and saturates at 255


class StereoRenderer:
    """Renders the three XB3 views of a board through a :class:`StereoModel` (ray maps kept per camera)."""

    def __init__(self, model: StereoModel | None = None, board: PrintedBoard | None = None,
                 options: RenderOptions | None = None, seed: int | Sequence[int] | None = None):
        self.model = model or nominal_xb3_model()
        self.board = board or PrintedBoard()
        self.options = options or RenderOptions()
        self.rng = np.random.default_rng(seed)
        self._views: dict[str, ViewRenderer] = {}

    def _renderer(self, view: str) -> ViewRenderer:
        if view not in self._views:
            k, d, _, _ = self.model.view(view)
            self._views[view] = ViewRenderer(k, d, self.model.image_size)
        return self._views[view]

    #: ``(u0, u1)`` mm of the board covered by an occluder in the next renders (``mock.occlude``), or None.
    band: tuple[float, float] | None = None

    def ideal(self, target2cam: np.ndarray, view: str) -> np.ndarray:
        """Noise-free, unblurred float image of one view."""
        _, _, r, t = self.model.view(view)
        return self._renderer(view).render(_view_pose(target2cam, r, t), self.board, self.options, self.rng, self.band)

    def planes(self, target2cam: np.ndarray, views: Sequence[str] = VIEWS, options: RenderOptions | None = None) -> dict:
        """Sensor planes (uint8; GBRG mosaics for a colour head) of ``views``."""
        opts = options or self.options
        return {v: _sensor(self.ideal(target2cam, v), opts, self.rng) for v in views}

    def xb3_frame(self, target2cam: np.ndarray, *, render_centre: bool = True) -> np.ndarray:
        """The packed 3-sensor RGB8 frame ``(h, w, 3)`` uint8 (byte 0 right, 1 centre, 2 left)."""
        views = VIEWS if render_centre else ("left", "right")
        planes = self.planes(target2cam, views)
        if not render_centre:
            w, h = self.model.image_size
            planes["centre"] = np.full((h, w), int(self.options.background), np.uint8)
        return pack_rgb8(planes["right"], planes["centre"], planes["left"])

    def gray_pair(self, target2cam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Left and right grey images of a mono head (the "PNG pair" case), through JPEG when
        ``options.jpeg_quality`` is set."""
        opts = replace(self.options, colour=False)
        planes = self.planes(target2cam, ("left", "right"), opts)
        return _jpeg(planes["left"], opts.jpeg_quality), _jpeg(planes["right"], opts.jpeg_quality)


def _jpeg(image: np.ndarray, quality: int) -> np.ndarray:
    """``image`` after a JPEG round trip at ``quality`` (1-100; 0 = unchanged)."""
    if not quality:
        return image
    ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    decoded = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    if not ok or decoded is None:
        raise ValueError(f"the JPEG round trip at quality {quality} failed")
    return np.asarray(decoded)


def hard_options(rng: np.random.Generator, board: PrintedBoard | None = None, *, colour: bool = False) -> RenderOptions:
    """Random render options made hard the way real images are: defocus blur (sigma 0.6-1.6 px),
    uneven light with vignetting, glare or a shadow half of the time (:func:`~handeye.mocks.world.hard_lighting`),
    more sensor noise (read noise 1.5-4 DN), a darker or brighter exposure, and JPEG at quality 60-90."""
    exposure = float(rng.uniform(0.6, 1.1))
    return RenderOptions(blur_sigma_px=float(rng.uniform(0.6, 1.6)), read_noise_dn=float(rng.uniform(1.5, 4.0)),
                         shot_noise=0.05, black=28.0 * exposure + 5.0, white=min(250.0, 215.0 * exposure),
                         background=105.0 * exposure, colour=colour, lighting=hard_lighting(rng, board),
                         jpeg_quality=int(rng.integers(60, 91)))


def render_views(target2cam: npt.ArrayLike, model: StereoModel | None = None, board: PrintedBoard | None = None,
                 options: RenderOptions | None = None, seed: int | None = None, views: Sequence[str] = VIEWS) -> dict:
    """One-shot rendering: sensor planes of ``views`` for a board at ``target2cam``."""
    return StereoRenderer(model, board, options, seed).planes(np.asarray(target2cam, float), views)


def render_xb3_frame(target2cam: npt.ArrayLike, model: StereoModel | None = None, board: PrintedBoard | None = None,
                     options: RenderOptions | None = None, seed: int | None = None) -> np.ndarray:
    """One-shot rendering of a packed XB3 3-sensor RGB8 frame."""
    return StereoRenderer(model, board, options, seed).xb3_frame(np.asarray(target2cam, float))


PoseSource = Callable[[], np.ndarray]


class MockCamera(Camera):
    """The ``"mock"`` camera back end: a simulated Bumblebee XB3 looking at a printed board.

    Parameters
    ----------
    model : StereoModel, optional
        Geometry of the simulated head (default: the nominal XB3 wide pair).
    board : PrintedBoard, optional
        The sheet (default 13x8 corners, 30 mm squares, 30 mm margin).
    target2base : array-like, shape (4, 4), optional
        Board pose in the base frame (default: facing the camera at the base origin, 1 m away,
        centred between the left and right cameras).
    cam2base : array-like (4, 4) or callable returning one, optional
        Camera pose in the base frame, or a provider called at every grab (e.g.
        ``lambda: robot.tool0_in_base() @ cam2tool0``). Default: the base frame itself.
    options : RenderOptions, optional
    seed : int, optional
    serial : int
    output : {"bgr", "gray"}
        Images in the returned frames.
    render_centre : bool
        Render the centre sensor too (``False`` is faster; the plane is then flat grey).
    frame_period_s : float
        Simulated frame period (the XB3 runs at 16 fps); ``grab`` waits until the next frame is due.
    """

    name = "mock"
    simulated = True

    def __init__(self, model: StereoModel | None = None, board: PrintedBoard | None = None,
                 target2base: npt.ArrayLike | None = None, cam2base: npt.ArrayLike | PoseSource | None = None,
                 options: RenderOptions | None = None, seed: int | Sequence[int] | None = None, serial: int = 7_654_321,
                 output: str = "bgr", render_centre: bool = True, frame_period_s: float = 0.0,
                 occlude: Occlusion | None = None):
        self.renderer = StereoRenderer(model, board, options, seed)
        self._occlusion = None
        if occlude is not None:  # mock.occlude: a band over the board at a share of the postures
            from .printed_targets import OcclusionPicker  # noqa: PLC0415

            self._occlusion = OcclusionPicker(occlude, self.renderer.board.geometry, seed)
        self._serial = int(serial)
        self.output = output
        self.render_centre = render_centre
        self.frame_period_s = float(frame_period_s)
        self._connected = False
        self._lock = threading.Lock()
        self._last = 0.0
        if target2base is None:  # facing the head, 1 m away, centred between the left and right cameras
            target2base = np.eye(4)
            middle = -0.5 * self.renderer.model.T  # right camera at -T in the left camera's frame (R = I nominal)
            target2base[:3, 3] = -self.renderer.board.centre() + np.array([middle[0], 0.0, 1000.0])
        self.set_scene(target2base=target2base, cam2base=cam2base if cam2base is not None else np.eye(4))

    @property
    def model(self) -> StereoModel:
        return self.renderer.model

    @property
    def board(self) -> PrintedBoard:
        return self.renderer.board

    def set_scene(self, *, target2base: npt.ArrayLike | None = None,
                  cam2base: npt.ArrayLike | PoseSource | None = None) -> None:
        """Change the board pose and/or the camera pose (a 4x4 matrix or a callable returning one)."""
        with self._lock:
            if target2base is not None:
                self._target2base = np.asarray(target2base, float).reshape(4, 4)
            if cam2base is not None:
                self._cam2base = cam2base if callable(cam2base) else np.asarray(cam2base, float).reshape(4, 4)

    def target2cam(self) -> np.ndarray:
        """Where the board is in the camera frame right now (the truth of the next grab)."""
        cam2base = self._cam2base() if callable(self._cam2base) else self._cam2base
        cam2base = np.asarray(cam2base, float).reshape(4, 4)
        return np.linalg.inv(cam2base) @ self._target2base

    def connect(self) -> None:
        self._connected = True

    def close(self) -> None:
        self._connected = False

    @property
    def is_connected(self) -> bool:
        return self._connected

    @property
    def serial(self) -> int:
        return self._serial

    def grab(self, timeout_s: float = 2.0) -> StereoFrame:
        """Render the current scene, pack it as an XB3 frame and decode it with the driver's decoder."""
        if not self._connected:
            raise CameraError("mock camera is not connected: call connect() or use it in a with-block")
        with self._lock:
            if self.frame_period_s > 0:
                wait = self._last + self.frame_period_s - time.monotonic()
                if wait > timeout_s:
                    raise CameraError(f"no frame from the mock camera within {timeout_s:g} s")
                if wait > 0:
                    time.sleep(wait)
            truth = self.target2cam()
            if self._occlusion is not None:
                self.renderer.band = self._occlusion.band(self._target2base @ np.linalg.inv(truth))
            packed = self.renderer.xb3_frame(truth, render_centre=self.render_centre)
            self._last = time.monotonic()
        w, h = self.model.image_size
        frame = decode_xb3_frame(packed, "rgb8", w, h, colour=self.renderer.options.colour, output=self.output,
                                 centre=self.render_centre, serial=self._serial)
        frame.raw = packed
        frame.info = {"model": "Bumblebee XB3 (mock)", "target2cam_truth": truth}
        return frame
