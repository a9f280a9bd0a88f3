"""The RAPID side: the station settings a program is rendered from, the modules (posture
sequencing, the link to the PC by protocol, the camera's tooldata, the write key), and their checks.

Names load on first use (importing the package is cheap)::

    from handeye.rapid import default_station, render_program, write_modules
    write_modules(render_program(default_station(), protocol="socket"), "rapid_out")

``rapid`` never imports the drivers: a controller back end carries its link module (a
:class:`~handeye.rapid.links.RapidLink`) in the drivers' registry, and whoever reads the registry
hands the links to the station (``RapidStation.links``); standing alone, ``rapid`` knows the
package's own (:data:`~handeye.rapid.links.BUILT_IN_LINKS`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base import lazy_exports

_EXPORTS = {
    "RapidLink": "links",
    "BUILT_IN_LINKS": "links",
    "LINK_MODULES": "links",
    "PROTOCOLS": "links",
    "RapidStation": "station",
    "default_station": "station",
    "load_station": "station",
    "station_from_dict": "station",
    "check_postures": "station",
    "RapidModule": "generate",
    "render_program": "generate",
    "render_main": "generate",
    "render_link": "generate",
    "render_tool": "generate",
    "render_key": "generate",
    "write_modules": "generate",
    "check_program": "checks",
    "RapidError": "errors",
    "ConfigError": "errors",
    "GUIDED_LINKS": "generate",
    "render_guided_program": "generate",
    "station_link": "generate",
    "PROMPTS": "guided",
    "VERDICT_CODES": "guided",
    "hint_code_for": "guided",
    "hint_text": "guided",
    "verdict_text": "guided",
    "Bindings": "interpreter",
    "IoBinding": "interpreter",
    "ModuleSource": "interpreter",
    "MotionBinding": "interpreter",
    "Program": "interpreter",
    "RapidFatalError": "interpreter",
    "RapidRuntimeError": "interpreter",
    "SerialBinding": "interpreter",
    "Task": "interpreter",
    "load_program": "interpreter",
    "parse_module": "interpreter",
    "TcpSockets": "interpreter.net",
    "FlexPendant": "interpreter.pendant",
    "MAX_STRING": "interpreter.values",
    "aggregate": "interpreter.values",
    "coerce": "interpreter.values",
    "coerce_array": "interpreter.values",
    "format_value": "interpreter.values",
    "POSITION_DECIMALS": "literals",
    "QUATERNION_DECIMALS": "literals",
    "pose_literal": "literals",
    "rounded_pose": "literals",
    "tooldata_literal": "literals",
    "IDLE_TIMEOUT_RANGE": "station",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .checks import check_program  # noqa: F401
    from .errors import ConfigError, RapidError  # noqa: F401
    from .generate import GUIDED_LINKS, RapidModule, render_guided_program, render_key, render_link, render_main, render_program, render_tool, station_link, write_modules  # noqa: F401
    from .guided import PROMPTS, VERDICT_CODES, hint_code_for, hint_text, verdict_text  # noqa: F401
    from .interpreter import Bindings, IoBinding, ModuleSource, MotionBinding, Program, RapidFatalError, RapidRuntimeError, SerialBinding, Task, load_program, parse_module  # noqa: F401
    from .interpreter.net import TcpSockets  # noqa: F401
    from .interpreter.pendant import FlexPendant  # noqa: F401
    from .interpreter.values import MAX_STRING, aggregate, coerce, coerce_array, format_value  # noqa: F401
    from .links import BUILT_IN_LINKS, LINK_MODULES, PROTOCOLS, RapidLink  # noqa: F401
    from .literals import POSITION_DECIMALS, QUATERNION_DECIMALS, pose_literal, rounded_pose, tooldata_literal  # noqa: F401
    from .station import IDLE_TIMEOUT_RANGE, RapidStation, check_postures, default_station, load_station, station_from_dict  # noqa: F401
