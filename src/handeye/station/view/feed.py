"""Live frames for the page while the capture waits for the robot (a planned move, the operator jogging).

The capture grabs only at a posture; between two, the operator would see a still image. While the
capture waits for the robot and has grabbed nothing for ``hub.LIVE_AFTER_S``, and a page is open,
:class:`LiveFeed` grabs a frame for the page alone (``ViewHub.wants_live_frame``). The camera is
shared through :class:`SharedCamera`: one grab at a time, the capture's blocking, the feed's only
when the camera is free (the capture waits at most for one grab in progress, and never for the
page: the feed's frame is detected and encoded in the hub's thread).
"""

from __future__ import annotations

import threading

__all__ = ["LiveFeed", "SharedCamera"]


class SharedCamera:
    """A camera whose ``grab`` is serialised by a lock; everything else is the camera's.

    ``on_grab()`` and ``on_frame(frame)`` (settable) are called when the capture (:meth:`grab`) starts a
    grab and when its frame came: the view shows it at once.
    """

    def __init__(self, camera, on_grab=None, on_frame=None):
        self._camera = camera
        self._lock = threading.Lock()
        self.on_grab, self.on_frame = on_grab, on_frame

    def grab(self, timeout_s: float = 2.0):
        if self.on_grab is not None:
            self.on_grab()
        with self._lock:
            frame = self._camera.grab(timeout_s)
        if self.on_frame is not None:
            self.on_frame(frame)
        return frame

    def try_grab(self, timeout_s: float = 1.0):
        """A frame, or None when someone else is grabbing."""
        if not self._lock.acquire(blocking=False):
            return None
        try:
            return self._camera.grab(timeout_s)
        finally:
            self._lock.release()

    def __getattr__(self, name):
        return getattr(self._camera, name)


class LiveFeed:
    """Grabs live frames for ``hub`` from ``camera`` (a :class:`SharedCamera`) when it wants them."""

    def __init__(self, hub, camera: SharedCamera, poll_s: float = 0.05):
        self.hub, self.camera, self.poll_s = hub, camera, poll_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="view-feed", daemon=True)
        self.grabs = 0

    def start(self) -> LiveFeed:
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def _run(self) -> None:
        from ...base import HandEyeError

        while not self._stop.wait(self.poll_s):
            if not self.hub.wants_live_frame():
                continue
            try:
                frame = self.camera.try_grab()
            except HandEyeError:
                continue  # the capture sees the camera's trouble itself and says so
            if frame is not None:
                self.grabs += 1
                self.hub.offer_live(frame)
