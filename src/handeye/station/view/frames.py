"""The live view's images: a stereo frame downscaled and encoded as JPEG (OpenCV), and the board's corners
in the page's pixels for the page to draw over it.

The corners of a frame the capture measured are the capture's own (``TriangulationResult.left_px``,
``right_px``); of any other frame (a live one, a grab that was not measured) they are found by the
capture's own detector, ``drivers.camera.checkerboard.detect_board``, on the full-size image with its
fast search (the region stage, tens of milliseconds found or not; :func:`detected_corners`): the page
says "board found" exactly where the capture would find it, and draws the same corners. A quick search
on the small copy (as before) missed a board whose squares shrink to a dozen pixels there.
"""

from __future__ import annotations

import base64

import numpy as np

__all__ = ["VIEW_WIDTH_PX", "corner_colours", "detected_corners", "detected_corners_with_ids", "encode_image",
           "page_ids", "page_points"]

#: Width of the images on the page, px (the height keeps the camera's aspect).
VIEW_WIDTH_PX = 400
_JPEG_QUALITY = 70


def detected_corners(image: np.ndarray, board) -> np.ndarray | None:
    """The board's inner corners ``(m, 2)`` in ``image`` (full-size px, canonical order) as the capture's
    detector finds them with its fast search; None when it finds none there."""
    return detected_corners_with_ids(image, board)[0]


def detected_corners_with_ids(image: np.ndarray, board) -> tuple[np.ndarray | None, np.ndarray | None]:
    """:func:`detected_corners` and, for a ChArUco board, the ids ``(k,)`` of the corners seen (a partial
    view: which part of the board); ``(None, None)`` when no board is found, ids None for the grids (seen
    whole, in id order)."""
    from ...drivers import detect_board
    from ...drivers import BoardNotFound, FrameError

    try:
        kind = getattr(board, "kind", "checkerboard")
        if kind == "charuco":  # the corners seen, by id (issue 37)
            from ...drivers import detect_charuco

            found = detect_charuco(image, board)
            return found.corners_px, np.asarray(found.ids, int)
        if kind == "circles":
            from ...drivers import detect_circles

            return detect_circles(image, board).corners_px, None
        return detect_board(image, board, search="fast").corners_px, None
    except (BoardNotFound, FrameError):
        return None, None


def corner_colours(ids, board) -> list[str]:
    """A stable colour per corner id (``#rrggbb``): the hue runs along the board's long side (red to magenta
    over the columns), the lightness down its short side (dark to light over the rows), so the colours of a
    partial view say which part of the board is seen.

    Parameters
    ----------
    ids : array-like of int, shape (k,)
        Corner ids (``row * nx + col``, :mod:`handeye.geometry.targets`).
    board : BoardGeometry
        Its ``corners = (nx, ny)``.
    """
    import colorsys

    nx, ny = (int(c) for c in board.corners)
    out = []
    for k in np.asarray(ids, int).ravel():
        row, col = divmod(int(k), nx)
        hue = (300.0 / 360.0) * col / max(nx - 1, 1)
        light = 0.30 + 0.40 * row / max(ny - 1, 1)
        r, g, b = colorsys.hls_to_rgb(hue, light, 1.0)
        out.append(f"#{round(255 * r):02x}{round(255 * g):02x}{round(255 * b):02x}")
    return out


def page_ids(points_px, ids) -> list | None:
    """The ids of the points :func:`page_points` keeps (the finite ones), as ints; None for None."""
    if points_px is None or ids is None:
        return None
    points = np.asarray(points_px, float).reshape(-1, 2)
    return [int(i) for i in np.asarray(ids, int).ravel()[np.all(np.isfinite(points), axis=1)]]


def encode_image(image: np.ndarray, width: int = VIEW_WIDTH_PX) -> tuple[str, float, tuple[int, int]]:
    """One camera's image for the page: ``(data:image/jpeg;base64,... URL, scale, (width, height))``, the
    scale from the image's pixels to the page's.

    Parameters
    ----------
    image : ndarray, shape (h, w) or (h, w, 3), uint8
    width : int
        The page image's width, px.
    """
    import cv2

    image = np.asarray(image)
    scale = width / image.shape[1]
    small = cv2.resize(image, (width, max(1, round(image.shape[0] * scale))), interpolation=cv2.INTER_AREA)
    ok, buffer = cv2.imencode(".jpg", small, [cv2.IMWRITE_JPEG_QUALITY, _JPEG_QUALITY])
    url = "data:image/jpeg;base64," + base64.b64encode(buffer.tobytes()).decode("ascii")
    return url, scale, (int(small.shape[1]), int(small.shape[0]))


def page_points(points_px, scale: float) -> list | None:
    """Corners ``(m, 2)`` of the full-size image as the page's pixels (``[[u, v], ...]``, 0.01 px; points that
    are not finite left out); None for None."""
    if points_px is None:
        return None
    points = np.asarray(points_px, float).reshape(-1, 2)
    points = points[np.all(np.isfinite(points), axis=1)]
    # a full-size pixel centre u maps to (u + 0.5) * scale - 0.5 on the resized copy
    return np.round((points + 0.5) * scale - 0.5, 2).tolist()
