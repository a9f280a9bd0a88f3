"""The station: its configuration, opening its hardware (real or the embedded mock), guided
capture, write-back of the calibrated tooldata, the demo, and the ``handeye`` command.

Every command of ``handeye`` is a library call here (``station.capture.loop.capture``,
``station.writeback.writeback`` ...; grouped by flow: ``config``, ``capture``, ``guided``, ``cell``, ``report``, ``verify``). Names load on first use
(``handeye --help`` stays fast)::

    from handeye.station import load_config, open_station
    config = load_config("station.yaml")
    with open_station(config) as link:
        print(link.controller.read_joints())
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base import lazy_exports

_EXPORTS = {
    "StationConfig": "config.station",
    "ConfigError": "config.station",
    "load_config": "config.station",
    "default_config": "config.station",
    "config_from_dict": "config.station",
    "StationLink": "runtime",
    "open_station": "runtime",
    "open_controller_link": "runtime",
    "CaptureError": "capture.loop",
    "WritebackError": "writeback",
    "run_demo": "demo",
    "DemoOptions": "demo",
    "main": "cli",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .capture.loop import CaptureError  # noqa: F401
    from .cli import main  # noqa: F401
    from .config.station import ConfigError, StationConfig, config_from_dict, default_config, load_config  # noqa: F401
    from .demo import DemoOptions, run_demo  # noqa: F401
    from .runtime import StationLink, open_controller_link, open_station  # noqa: F401
    from .writeback import WritebackError  # noqa: F401
