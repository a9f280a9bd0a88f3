"""handeye: hand-eye calibration of a stereo camera on an ABB robot flange, from capture to tooldata.

The package is five rooms, each a sub-package with its own public names (see its docstring and
``__all__``):

- :mod:`handeye.calibration`: the numeric core (sessions on disk, the methods, kinematics);
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
