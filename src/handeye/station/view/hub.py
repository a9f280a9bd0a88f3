"""The live view's core: takes the capture's events without slowing it, and publishes the page's state.

The capture thread calls :meth:`ViewHub.observe`: a grab (``Measured``) only replaces the latest
frame (older ones are dropped, never queued), any other event is appended to a short list; both
under a lock held for a few assignments, then a wake-up. Everything else happens in the hub's own
thread: folding the events into :class:`~handeye.station.view.state.ViewState` (coverage, hint, the
running calibration) and encoding the latest frame as JPEG with, per side, whether the board was
found and its corners (the capture's own for a measured frame, its detector's for any other:
``frames``), at most once per
``frame_interval_s`` (so at most ``1 / frame_interval_s`` encodings a second, however fast frames
come). The HTTP server's clients wait in :meth:`ViewHub.wait` for a newer state or frame.
"""

from __future__ import annotations

import json
import threading
import time

from ..capture.events import CaptureEnded, Measured, Prompt, Verdict
from .frames import corner_colours, detected_corners_with_ids, encode_image, page_ids, page_points
from .state import ViewState

__all__ = ["GRAB", "LIVE", "LIVE_AFTER_S", "LIVE_PERIOD_S", "MEASURED", "ViewHub"]

#: The kinds of frame on the page: a live frame (``feed``), the capture's grab as it came, the same
#: grab with the corners the capture measured (and the predicted ones).
LIVE, GRAB, MEASURED = "live", "grab", "measured"
#: The corners of a capture's grab that it is measuring: the page says "measuring", not "no board".
MEASURING = object()

#: Live frames are grabbed for the page once the capture has waited for the robot this long (s), and
#: until it grabs again (see ``station.view.feed``): a short planned move gets none.
LIVE_AFTER_S = 0.25
#: Meanwhile the next live grab starts this long (s) after the last frame came (the grab itself takes longer).
LIVE_PERIOD_S = 0.05


class ViewHub:
    """See the module docstring.

    Parameters
    ----------
    config : StationConfig
    stereo_model : drivers.camera.stereo.StereoModel
    frame_interval_s : float
        Shortest time between two JPEG encodings.
    """

    def __init__(self, config, stereo_model, frame_interval_s: float = 0.15):
        self.state = ViewState(config, stereo_model)
        self.board = config.target
        self.frame_interval_s = frame_interval_s
        self._lock = threading.Lock()
        self._changed = threading.Condition()
        self._wake = threading.Event()
        self._events: list = []
        self._frame = None  # (Measured event or StereoFrame, its kind): the latest, not yet encoded
        self._frame_at = self._waiting_since = time.monotonic()
        self.waiting = False  # the capture waits for the robot (a Prompt since the last grab)
        self.clients = 0
        self.state_json, self.state_version = "{}", 0
        self.frame_json, self.frame_version = "", 0
        self.encoded = 0
        self._last_image = (None, 0)  # the camera frame last shown, and its number
        self.closed = self.finished = False
        self._thread = threading.Thread(target=self._run, name="view-hub", daemon=True)

    # ---------------------------------------------------------------------------- capture side
    def observe(self, event) -> None:
        """The capture's observer (``station.capture.events``): returns at once."""
        with self._lock:
            if isinstance(event, Measured):
                self._frame, self._frame_at = (event, MEASURED), time.monotonic()
            else:
                self._events.append(event)
                if isinstance(event, (Prompt, Verdict)):
                    self.waiting, self._waiting_since = True, time.monotonic()
        self._wake.set()

    def capture_grabs(self) -> None:
        """The capture starts a grab (``feed.SharedCamera``): it measures; a planned capture gets no live
        frames until it waits for the robot again."""
        with self._lock:
            self.waiting = False

    def capture_frame(self, frame) -> None:
        """The capture's grab came (``feed.SharedCamera``): shown at once, its corners when measured."""
        with self._lock:
            self._frame, self._frame_at = (frame, GRAB), time.monotonic()
        self._wake.set()

    def wants_live_frame(self) -> bool:
        """A page is open and the last frame is :data:`LIVE_PERIOD_S` old; a planned capture also waits
        for the robot, since :data:`LIVE_AFTER_S`. (A guided capture waits for the operator, not the PC: a
        live frame may come while it measures; the camera's lock keeps the grabs apart.)"""
        with self._lock:
            now = time.monotonic()
            if self.clients <= 0 or self.closed or self.state.ended is not None or now - self._frame_at < LIVE_PERIOD_S:
                return False
            return self.state.mode == "guided" or (self.waiting and now - self._waiting_since >= LIVE_AFTER_S)

    def offer_live(self, frame) -> None:
        """A frame grabbed for the page alone (``station.view.feed``); the capture's own frames go first."""
        with self._lock:
            if self._frame is None or self._frame[1] == LIVE:
                self._frame, self._frame_at = (frame, LIVE), time.monotonic()
        self._wake.set()

    # ------------------------------------------------------------------------------ hub thread
    def start(self) -> ViewHub:
        self._publish_state()
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop, after publishing what the capture said last (the page shows the end of the run)."""
        self.closed = True
        self._wake.set()
        self._thread.join(timeout=5.0)
        self._fold_events()
        if self.state.ended is None:  # closed without the command's last word: an error or Ctrl-C
            self.state.apply(CaptureEnded("the capture stopped (the terminal says why); the postures on disk stay: "
                                          "run the same command to go on", ok=False))
            self._publish_state()
        with self._lock:
            frame, self._frame = self._frame, None
        if frame is not None and frame[1] != LIVE:
            self._publish_frame(*frame)
        with self._changed:
            self.finished = True  # all published: the pages' streams may end once they have sent it
            self._changed.notify_all()

    def _fold_events(self) -> None:
        with self._lock:
            events, self._events = self._events, []
        for event in events:
            self.state.apply(event)
        if events:
            self._publish_state()

    def _run(self) -> None:
        last_encode = 0.0
        while not self.closed:
            self._wake.wait(0.1)
            self._wake.clear()
            self._fold_events()
            if time.monotonic() - last_encode >= self.frame_interval_s:
                with self._lock:
                    frame, self._frame = self._frame, None
                if frame is not None:
                    self._publish_frame(*frame)
                    last_encode = time.monotonic()
            elif self._frame is not None:
                self._wake.set()  # encode it when the interval is over
                time.sleep(max(0.0, self.frame_interval_s - (time.monotonic() - last_encode)))

    def _publish_state(self) -> None:
        text = json.dumps(self.state.to_json())
        with self._changed:
            self.state_json, self.state_version = text, self.state_version + 1
            self._changed.notify_all()

    def _publish_frame(self, item, kind: str) -> None:
        """Encode a frame and publish it with, per side, whether the board was found and its corners (the
        capture's own when it measured this frame; else its detector's, ``frames.detected_corners``) and
        the running calibration's predicted corners, all in the page's pixels; a capture's grab not yet
        measured says neither (``found`` None: measuring)."""
        posture = problem = predicted = None
        ids = [None, None]
        if kind == MEASURED:
            frame, posture, problem = item.frame, item.posture, item.problem
            if item.result is not None:
                found = [item.result.left_px, item.result.right_px]
                ids = [getattr(item.result, "corner_ids", None)] * 2
            else:
                found, ids = self._detect(frame)
            predicted = self.state.predictor.predict_px(item.tool02base)
        elif kind == GRAB:
            frame, found = item, [MEASURING, MEASURING]
        else:
            frame = item
            found, ids = self._detect(item)
        if frame is not self._last_image[0]:
            self._last_image = (frame, self._last_image[1] + 1)
        sides = [self._side(image, corners, side_ids, None if predicted is None else predicted[k])
                 for k, (image, corners, side_ids) in enumerate(zip((frame.left, frame.right), found, ids))]
        data = {"seq": self.frame_version + 1, "image": self._last_image[1], "kind": kind, "live": kind == LIVE,
                "posture": posture, "found": [side["found"] for side in sides], "predicted": predicted is not None,
                "problem": problem, "left": sides[0]["image"], "right": sides[1]["image"], "sides": sides,
                "pattern": list(self.board.corners)}
        text = json.dumps(data)
        with self._changed:
            self.frame_json, self.frame_version = text, self.frame_version + 1
            self.encoded += 1
            self._changed.notify_all()

    def _detect(self, frame) -> tuple[list, list]:
        """Corners and ids (ChArUco) of both images by the capture's detector (``frames.detected_corners_with_ids``)."""
        left, right = (detected_corners_with_ids(im, self.board) for im in (frame.left, frame.right))
        return [left[0], right[0]], [left[1], right[1]]

    def _side(self, image, corners, ids, predicted) -> dict:
        """One image for the page: the JPEG, its size, whether the board was found, its corners in the page's
        pixels, for a ChArUco board their ids and a colour per id (``frames.corner_colours``), and the
        predicted corners."""
        url, scale, size = encode_image(image)
        measuring = corners is MEASURING
        shown = None if measuring else page_ids(corners, ids)
        return {"image": url, "size": size, "found": None if measuring else corners is not None,
                "corners": None if measuring else page_points(corners, scale), "ids": shown,
                "colours": None if shown is None else corner_colours(shown, self.board),
                "predicted": None if predicted is None else page_points(predicted, scale)}

    # ------------------------------------------------------------------------------ server side
    def wait(self, state_version: int, frame_version: int, timeout_s: float) -> tuple:
        """Wait until the state or the frame is newer than the versions given (or ``timeout_s``, or the
        hub has published its last): ``(finished, state_version, state_json, frame_version, frame_json)``,
        ``finished`` True when nothing will follow what it returns."""
        with self._changed:
            self._changed.wait_for(lambda: self.finished or self.state_version != state_version
                                   or self.frame_version != frame_version, timeout_s)
            return self.finished, self.state_version, self.state_json, self.frame_version, self.frame_json

    def client(self, delta: int) -> None:
        with self._lock:
            self.clients += delta
