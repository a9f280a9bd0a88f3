"""handeye: hand-eye calibration of a stereo camera on an ABB robot flange, from capture to tooldata.

The package is eight rooms, each a sub-package whose ``__init__`` is its face (its public names, see its
docstring and ``__all__``); a room imports only the rooms below it, from their faces:

- :mod:`handeye.base`: errors, safe files, the YAML reader, the extension registries (stdlib and PyYAML);
- :mod:`handeye.geometry`: rotations, transforms, the checkerboard's description;
- :mod:`handeye.robot`: kinematics from the robot files, the cell, clearance and self-collision, views;
- :mod:`handeye.calibration`: the hand-eye numbers (sessions on disk, the methods, metrics);
- :mod:`handeye.drivers`: the controller link and the camera, back ends by name;
- :mod:`handeye.rapid`: the RAPID program of the station;
- :mod:`handeye.mocks`: the simulated controller and camera;
- :mod:`handeye.station`: the station's configuration, capture, write-back and the ``handeye`` command.

Importing ``handeye`` imports none of them.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("handeye")
except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
