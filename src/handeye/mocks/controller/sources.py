"""The RAPID program a mock controller runs: generated for its link, or the modules of a folder.

A controller runs what is loaded into its task. The mock loads either the modules ``handeye rapid
generate`` writes for the station (:func:`generated_program`: HeMain, the link module, HeTool, and
HeKey.sys when there is a write key) or the ``*.mod``/``*.modx``/``*.sys`` files of a folder
(:func:`program_from_folder`, what ``handeye mock controller --program DIR`` and a capture's
``SESSION/rapid`` give).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
import os
from collections.abc import Iterable
from pathlib import Path

from ...drivers import RAPID_LINKS
from ...rapid import RapidError
from ...rapid import render_key, render_program
from ...rapid import ModuleSource, parse_module
from ...rapid import RapidStation, default_station

__all__ = ["ControllerProgram", "generated_program", "program_from_folder", "keep_system_modules", "MODULE_SUFFIXES",
           "NEVER_LATE_S"]

#: Files a folder's modules are read from.
MODULE_SUFFIXES = (".mod", ".modx", ".sys")
#: The acknowledgement timeout a mock without one renders (the longest the station allows).
NEVER_LATE_S = 3600.0


@dataclass(frozen=True)
class ControllerProgram:
    """Modules loaded into the controller's task.

    Attributes
    ----------
    modules : tuple of ModuleSource
    origin : str
        Where they come from, for messages (``generated for socket``, a folder).
    link : str or None
        The protocol of the link module among them (a controller back end's name).
    tool_name : str or None
        The PERS tooldata holding the camera (None: the program's only PERS tooldata).
    """

    modules: tuple
    origin: str
    link: str | None = None
    tool_name: str | None = None


def _link_of(names, origin: str, protocol: str | None = None) -> str | None:
    """The protocol whose link module is among the module ``names``: ``protocol`` when its module is
    there (back ends may share one: a plug-in running the socket link's HeSocket), else the one found."""
    found = [name for name in RAPID_LINKS if RAPID_LINKS[name].module.lower() in names]
    if protocol in found:
        return protocol
    if len({RAPID_LINKS[name].module.lower() for name in found}) > 1:
        raise RapidError(f"{origin} holds the link modules of {' and '.join(found)}: load one")
    return found[0] if found else None


def generated_program(protocol: str, station: RapidStation | None = None, *, postures: Iterable[Iterable[float]] | None = None,
                      ack_timeout_s: float | None = 30.0, idle_timeout_s: float | None = None,
                      write_key: str | None = None, pc_address: str | None = None) -> ControllerProgram:
    """The modules ``handeye rapid generate`` writes for ``protocol``, with the mock's settings.

    The socket server binds the controller's LAN address (``GetSysInfo(\\LanIp)``: the mock's
    host); ``ack_timeout_s=None`` renders the longest acknowledgement timeout (never LATE in practice).
    """
    base = station or default_station()
    changes = {"protocol": protocol, "links": RAPID_LINKS, "controller_address": "auto", "write_key": write_key,
               "ack_timeout_s": NEVER_LATE_S if ack_timeout_s is None else ack_timeout_s}
    if postures is not None:
        changes["postures"] = tuple(tuple(float(v) for v in row) for row in postures)
    if idle_timeout_s is not None:
        changes["idle_timeout_s"] = idle_timeout_s
    if pc_address is not None:
        changes["pc_address"] = pc_address
    station = base.with_(**changes)
    try:
        hash(station)
    except TypeError:  # a station holding arrays cannot be a cache key: render it afresh
        modules = _rendered.__wrapped__(station, protocol)
    else:
        modules = _rendered(station, protocol)
    return ControllerProgram(modules, f"generated for {protocol}", protocol, station.tool_name)


@lru_cache(maxsize=64)
def _rendered(station: RapidStation, protocol: str) -> tuple:
    """The checked modules of ``station`` for ``protocol``, as a tuple of ModuleSource.

    Cached: rendering and its checks are pure functions of the (frozen) station, and one process may
    start many mock controllers of the same station (a test run starts hundreds).
    """
    modules = render_program(station, protocol=protocol)
    if station.write_key is not None:
        modules.append(render_key(station))
    return tuple(ModuleSource(m.text, m.filename) for m in modules)


def program_from_folder(folder: str | os.PathLike[str], protocol: str | None = None) -> ControllerProgram:
    """The modules in ``folder`` (system modules and program modules alike).

    Raises
    ------
    RapidError
        No such folder, no module in it, unreadable files, or a link module of another protocol.
    """
    path = Path(folder)
    if not path.is_dir():
        raise RapidError(f"--program {path}: no such folder (it holds the .mod/.sys files to run)")
    files = sorted(p for p in path.iterdir() if p.suffix.lower() in MODULE_SUFFIXES and p.is_file())
    if not files:
        raise RapidError(f"--program {path}: no RAPID modules ({', '.join(MODULE_SUFFIXES)}) in it")
    modules = []
    for file in files:
        try:
            modules.append(ModuleSource(file.read_text(encoding="latin-1"), file.name))
        except OSError as exc:
            raise RapidError(f"--program {path}: cannot read {file.name} ({exc.strerror})") from None
    link = _link_of({f.stem.lower() for f in files}, str(path), protocol)
    if protocol is not None and link is not None and link != protocol:
        raise RapidError(f"--program {path} holds {RAPID_LINKS[link].module} ({link}), not the {protocol} link module "
                         f"{RAPID_LINKS[protocol].module}: choose --protocol {link}")
    return ControllerProgram(tuple(modules), str(path), link)


def keep_system_modules(new: ControllerProgram, old: ControllerProgram | None) -> ControllerProgram:
    """``new`` plus the system modules of ``old`` it does not replace: system modules (``SYSMODULE``,
    such as HeKey.sys) stay loaded when the program modules are replaced."""
    if old is None:
        return new
    names = {parse_module(m.text, m.source).name.lower() for m in new.modules}
    kept = []
    for module in old.modules:
        parsed = parse_module(module.text, module.source)
        if parsed.is_system and parsed.name.lower() not in names:
            kept.append(module)
    return ControllerProgram(tuple(kept) + tuple(new.modules), new.origin, new.link or old.link,
                             new.tool_name or old.tool_name)
