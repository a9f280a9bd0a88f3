"""The live view's core: takes the capture's events without slowing it, and publishes the page's state.

The capture thread calls :meth:`ViewHub.observe`: a grab (``Measured``) only replaces the latest
frame (older ones are dropped, never queued), any other event is appended to a short list; both
under a lock held for a few assignments, then a wake-up. Everything else happens in the hub's own
thread: folding the events into :class:`~handeye.station.view.state.ViewState` (coverage, hint, the
running calibration) and encoding the latest frame as JPEG, at most once per
``frame_interval_s`` (so at most ``1 / frame_interval_s`` encodings a second, however fast frames
come). The HTTP server's clients wait in :meth:`ViewHub.wait` for a newer state or frame.
"""

from __future__ import annotations

import json
import threading
import time

from ..capture_events import Measured, Prompt, Verdict
from .frames import encode_side, quick_corners
from .state import ViewState

__all__ = ["LIVE_AFTER_S", "ViewHub"]

#: A live frame is grabbed for the page when the capture has waited for the robot this long (s) and
#: grabbed nothing meanwhile (see ``station.view.feed``): a short planned move gets none.
LIVE_AFTER_S = 0.25


class ViewHub:
    """See the module docstring.

    Parameters
    ----------
    config : StationConfig
    stereo_model : drivers.camera.stereo.StereoModel
    frame_interval_s : float
        Shortest time between two JPEG encodings.
    """

    def __init__(self, config, stereo_model, frame_interval_s: float = 0.2):
        self.state = ViewState(config, stereo_model)
        self.corners = tuple(config.target.corners)
        self.frame_interval_s = frame_interval_s
        self._lock = threading.Lock()
        self._changed = threading.Condition()
        self._wake = threading.Event()
        self._events: list = []
        self._frame = None  # (Measured or live frame, live?)
        self._frame_at = self._waiting_since = time.monotonic()
        self.waiting = False  # the capture waits for the robot (a Prompt since the last grab)
        self.clients = 0
        self.state_json, self.state_version = "{}", 0
        self.frame_json, self.frame_version = "", 0
        self.encoded = 0
        self.closed = False
        self._thread = threading.Thread(target=self._run, name="view-hub", daemon=True)

    # ---------------------------------------------------------------------------- capture side
    def observe(self, event) -> None:
        """The capture's observer (``station.capture_events``): returns at once."""
        with self._lock:
            if isinstance(event, Measured):
                self._frame, self._frame_at, self.waiting = (event, False), time.monotonic(), False
            else:
                self._events.append(event)
                if isinstance(event, Prompt) or (isinstance(event, Verdict) and self.state.mode == "guided"):
                    self.waiting, self._waiting_since = True, time.monotonic()  # (guided: the operator jogs on)
        self._wake.set()

    def wants_live_frame(self) -> bool:
        """A page is open, the capture waits for the robot and has not grabbed for :data:`LIVE_AFTER_S`."""
        with self._lock:
            return (self.clients > 0 and self.waiting and not self.closed
                    and time.monotonic() - max(self._frame_at, self._waiting_since) >= LIVE_AFTER_S)

    def offer_live(self, frame) -> None:
        """A frame grabbed for the page alone (``station.view.feed``)."""
        with self._lock:
            if self.waiting:
                self._frame, self._frame_at = (frame, True), time.monotonic()
        self._wake.set()

    # ------------------------------------------------------------------------------ hub thread
    def start(self) -> ViewHub:
        self._publish_state()
        self._thread.start()
        return self

    def close(self) -> None:
        self.closed = True
        self._wake.set()
        self._thread.join(timeout=5.0)
        with self._changed:
            self._changed.notify_all()

    def _run(self) -> None:
        last_encode = 0.0
        while not self.closed:
            self._wake.wait(0.1)
            self._wake.clear()
            with self._lock:
                events, self._events = self._events, []
            for event in events:
                self.state.apply(event)
            if events:
                self._publish_state()
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

    def _publish_frame(self, item, live: bool) -> None:
        if live:
            frame, posture, found, predicted = item, None, [quick_corners(im, self.corners) for im in (item.left, item.right)], None
        else:
            frame, posture, result = item.frame, item.posture, item.result
            found = [None, None] if result is None else [result.left_px, result.right_px]
            predicted = self.state.predictor.predict_px(item.tool02base)
        images = [encode_side(im, self.corners, f, None if predicted is None else predicted[k])
                  for k, (im, f) in enumerate(zip((frame.left, frame.right), found))]
        data = {"seq": self.frame_version + 1, "posture": posture, "live": live,
                "found": [f is not None for f in found], "predicted": predicted is not None,
                "problem": None if live else item.problem, "left": images[0], "right": images[1]}
        text = json.dumps(data)
        with self._changed:
            self.frame_json, self.frame_version = text, self.frame_version + 1
            self.encoded += 1
            self._changed.notify_all()

    # ------------------------------------------------------------------------------ server side
    def wait(self, state_version: int, frame_version: int, timeout_s: float) -> tuple:
        """Wait until the state or the frame is newer than the versions given (or ``timeout_s``, or the
        hub closes): ``(state_version, state_json, frame_version, frame_json)``."""
        with self._changed:
            self._changed.wait_for(lambda: self.closed or self.state_version != state_version
                                   or self.frame_version != frame_version, timeout_s)
            return self.state_version, self.state_json, self.frame_version, self.frame_json

    def client(self, delta: int) -> None:
        with self._lock:
            self.clients += delta
