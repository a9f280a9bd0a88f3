"""The controller back ends' help lines, written from their registry entries
(:data:`handeye.drivers.controller.backends.CONTROLLERS`): what each talks to, its RAPID link
module and its command-line options, for ``handeye robot --help`` and ``handeye rapid generate
--help`` (and the example station file, :mod:`handeye.station.config.example`). A back end added in
code or by a plug-in's entry point shows up in them as a built-in one does; none is written by hand.
"""

from __future__ import annotations

import textwrap

__all__ = ["link_module", "described", "protocol_lines", "link_module_lines"]

_WIDTH = 100


def link_module(name: str):
    """The RAPID link (``rapid.links.RapidLink``) of a controller back end, or None when it has none."""
    from ..drivers import RAPID_LINKS  # noqa: PLC0415 (read when a help text is built)

    return RAPID_LINKS.get(name)


def described(name: str) -> str:
    """``TCP to the RAPID program's server (PC Interface option); RAPID module HeSocket``."""
    from ..drivers import CONTROLLERS  # noqa: PLC0415

    link = link_module(name)
    module = f"; RAPID module {link.module}" if link is not None else "; no RAPID module (capture refuses it)"
    return CONTROLLERS[name].help + module


def protocol_lines() -> list[str]:
    """Two lines per back end, registry order: ``--protocol NAME  what it talks to (its module)`` and its
    options (``ControllerBackend.usage``)."""
    from ..base import quiet_loads  # noqa: PLC0415
    from ..drivers import CONTROLLERS  # noqa: PLC0415

    lines = []
    with quiet_loads():  # a plug-in that does not load is named here, with why
        for name in tuple(CONTROLLERS.names()):
            if CONTROLLERS.get(name) is None:
                lines.append(f"  --protocol {name:<8} not usable: {CONTROLLERS.why_unusable(name)}")
                continue
            lines += [f"  --protocol {name:<8} {described(name)}", f"  {'':<19} {CONTROLLERS[name].usage()}"]
        lines += [f"  --protocol {name:<8} not usable: {CONTROLLERS.why_unusable(name)}"
                  for name in CONTROLLERS.plugin_names() if name not in CONTROLLERS.names()
                  and CONTROLLERS.why_unusable(name) and not any(f"--protocol {name} " in line for line in lines)]
    return lines


def link_module_lines() -> list[str]:
    """``  HeSocket.mod   what it does (protocol socket)`` for every back end with a RAPID link module."""
    from ..drivers import CONTROLLERS, RAPID_LINKS  # noqa: PLC0415

    lines = []
    for name in RAPID_LINKS:
        link = RAPID_LINKS[name]
        text = f"  {link.module + '.mod':<14} {link.help or CONTROLLERS[name].help} (protocol {name})"
        lines += textwrap.wrap(text, _WIDTH, subsequent_indent=" " * 17, break_on_hyphens=False)
    return lines
