"""The link modules of the generated RAPID program, one per controller protocol.

This is rapid's own table (``rapid`` never imports the drivers); a test checks that it names exactly
the controller back ends the drivers register, so a new protocol cannot get one without the other.
"""

from __future__ import annotations

__all__ = ["LINK_MODULES", "PROTOCOLS"]

#: Controller protocol -> the RAPID module that speaks it on the controller.
LINK_MODULES = {"socket": "HeSocket", "serial": "HeSerial", "modbus": "HeIo", "rws": "HeRws"}
#: The protocols a RAPID program can be generated for.
PROTOCOLS = tuple(LINK_MODULES)
