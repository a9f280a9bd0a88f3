"""A third-party package as the tests see one: it adds a controller back end (``loopback``, the
line protocol over TCP on another default port) and two camera back ends (``blank``, grey frames,
and ``tinted`` (the same frames at a grey level the station config sets: ``camera.tint``) through
the entry points of its ``.dist-info``, with no change to handeye.

The controller is declared by one ``ControllerBackend`` (name, class, default port, help), which
also brings the RAPID module its controller runs (``HeLoop``, from this package's own template) and
the mock that serves it (the socket mock's server, running HeLoop); the ``blank`` camera by its class
alone (the registry describes it with the defaults), ``tinted`` by a ``CameraBackend`` declaring its
own setting.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from handeye.drivers import Camera, CameraBackend, ControllerBackend, LinkSetting, MockServer, Setting, SocketController, StereoFrame
from handeye.rapid import RapidLink


class LoopbackController(SocketController):
    """The socket back end under another name: what a plug-in's own protocol would subclass. Its own
    setting ``label`` (``controller.loop_label`` in a station config, ``--loop-label`` on the command
    line) is only kept."""

    protocol = "loopback"

    def __init__(self, host: str = "127.0.0.1", port: int = 11025, *, label: str = "", **options):
        super().__init__(host, port, **options)
        self.label = label


#: The RAPID module of the loopback link: this package's template, filled with handeye's link fields.
RAPID_LINK = RapidLink("HeLoop", Path(__file__).with_name("HeLoop.mod.tmpl"))


def _mock_server(*args, note: str = "", **kwargs):
    """The mock controller of the loopback link: the socket mock running HeLoop (imported when it
    starts), with an option of its own (``note``, kept: ``--loop-note`` of ``handeye mock controller``)."""
    from handeye.mocks import SocketControllerServer

    server = SocketControllerServer(*args, **kwargs)
    server.note = note
    return server


CONTROLLER = ControllerBackend("loopback", f"{__name__}:LoopbackController", default_port=11025,
                               help="the test plug-in's TCP link",
                               link_settings=(LinkSetting("loop_label", str, "plain", "a label the link keeps",
                                                          keyword="label", metavar="TEXT"),),
                               rapid_link=RAPID_LINK,
                               mock=MockServer(_mock_server, 11026, help="HeLoop executed: the line protocol over TCP",
                                               options=(LinkSetting("note", str, None, "a note the mock keeps",
                                                                    flag="--loop-note"),)))


class BlankCamera(Camera):
    """A camera that sees nothing: grey 8 x 8 frames."""

    name = "blank"

    def __init__(self, grey: int = 128):
        self.grey = grey
        self._open = False

    def connect(self) -> None:
        self._open = True

    def close(self) -> None:
        self._open = False

    @property
    def is_connected(self) -> bool:
        return self._open

    def grab(self, timeout_s: float = 2.0) -> StereoFrame:
        image = np.full((8, 8), self.grey, np.uint8)
        return StereoFrame(image, image.copy())


#: The same camera described by a back end with a setting of its own: ``camera.tint`` of a station
#: config (checked 0..255, required), the class's ``grey``.
TINTED = CameraBackend("tinted", f"{__name__}:BlankCamera", help="grey frames at the station's tint",
                       settings=(Setting("tint", int, None, "grey level of the frames", keyword="grey", low=0, high=255,
                                         required="a grey level 0..255"),))
