"""The link module of a generated RAPID program: the module that speaks one controller protocol on
the controller's side.

A link is a :class:`RapidLink`: the module's name and its template (or a function rendering it). A
controller back end carries its own (``ControllerBackend.rapid_link`` in the drivers' registry, a
plug-in's included); ``rapid`` never imports the drivers, so whoever reads the registry hands the
links to the station (``RapidStation.links``). Standing alone, ``rapid`` knows the package's own
links (:data:`BUILT_IN_LINKS`), the RAPID side of the package's back ends.

Every template is filled from the same fields (:func:`handeye.rapid.generate.link_fields`): the
station's timeouts, tool name, protocol version and key tries; the line protocol's session data,
dispatcher and key check; the socket server's addresses and slices; the serial channel; the I/O
publishing period and key gate; the RWS poll rate. A template uses those it needs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import string
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

from .errors import RapidError

if TYPE_CHECKING:
    from .station import RapidStation

__all__ = ["RapidLink", "BUILT_IN_LINKS", "LINK_MODULES", "PROTOCOLS", "TEMPLATES", "read_template",
           "HE_SOCKET", "HE_SERIAL", "HE_IO", "HE_RWS"]

#: The folder of the package's templates (a relative template name is looked up here).
TEMPLATES = Path(__file__).with_name("templates")


def read_template(name: str | Path) -> string.Template:
    """The template ``name`` (a file name in :data:`TEMPLATES`, or a path)."""
    path = Path(name)
    if not path.is_absolute():
        path = TEMPLATES / path
    try:
        return string.Template(path.read_text(encoding="ascii"))
    except (OSError, UnicodeDecodeError) as exc:
        raise RapidError(f"cannot read the RAPID template {path}: {exc}") from None


@dataclass(frozen=True)
class RapidLink:
    """The RAPID module speaking one protocol on the controller.

    Attributes
    ----------
    module : str
        The module's name (a RAPID identifier; written as ``<module>.mod``).
    template : str or Path or None
        Its template (:class:`string.Template` syntax), a file name in ``rapid/templates`` or a path.
    render : callable or None
        ``render(station, fields) -> str``: renders the module instead of a template (``fields``:
        what a template would be filled with).
    write_key : bool
        Tool writes over this link carry the station's write key (``HeKey.sys`` is generated with a
        keyed station); False: the controller authorises them itself (Robot Web Services).
    help : str
        What the module does, one line (``handeye rapid generate --help`` lists every link's; empty:
        its back end's help).
    """

    module: str
    template: str | Path | None = None
    render: Callable | None = None
    write_key: bool = True
    help: str = ""

    def text(self, station: RapidStation, fields: Mapping) -> str:
        """The module's text for ``station``, from the common ``fields``."""
        if self.render is not None:
            return self.render(station, fields)
        if self.template is None:
            raise RapidError(f"the link module {self.module} has neither a template nor a renderer")
        try:
            return read_template(self.template).substitute(fields)
        except KeyError as exc:
            raise RapidError(f"the template of {self.module} uses ${exc.args[0]}, which no station field provides; "
                             f"known: {', '.join(sorted(fields))}") from None


HE_SOCKET = RapidLink("HeSocket", "HeSocket.mod.tmpl", help="line-protocol server over TCP, accepting only the PC's address")
HE_SERIAL = RapidLink("HeSerial", "HeSerial.mod.tmpl", help="the same protocol on a serial channel")
HE_IO = RapidLink("HeIo", "HeIo.mod.tmpl", help="I/O handshake for a Modbus TCP gateway (SetGO/SetDO/WaitDI)")
# Robot Web Services: the PC writes the tool data by symbol, authorised by the controller's own users
# and mastership, so HeRws has no tool path and needs no key.
HE_RWS = RapidLink("HeRws", "HeRws.mod.tmpl", write_key=False,
                   help="posture handshake in PERS data the PC reads and writes over Robot Web Services (RobotWare 6/7)")

#: The package's own back ends' links (what ``rapid`` uses standing alone; the drivers' registry
#: names the same objects, a test checks it).
BUILT_IN_LINKS: Mapping[str, RapidLink] = MappingProxyType(
    {"socket": HE_SOCKET, "serial": HE_SERIAL, "modbus": HE_IO, "rws": HE_RWS})
#: Protocol -> module name of the built-in links.
LINK_MODULES = {name: link.module for name, link in BUILT_IN_LINKS.items()}
#: The protocols of the built-in links.
PROTOCOLS = tuple(BUILT_IN_LINKS)
