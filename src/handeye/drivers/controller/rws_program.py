"""The RAPID program of the ``rws`` back end (a mixin of
:class:`~handeye.drivers.controller.rws_client.RwsController`): upload the modules through the file
service, load them into the task, reset the program pointer, start and stop execution."""

from __future__ import annotations

import time
from collections.abc import Iterable
from typing import TYPE_CHECKING

from .errors import InvalidRequest
from .interface import Deadline
from .protocol import PROTOCOL_VERSION
from .rws_access import RwsAccess

__all__ = ["RwsProgram"]

# For the type checker only: the mixin's methods use RwsAccess's and RwsHttp's (RwsController mixes them
# in); at run time its base is object, so RwsController's own base list alone makes its method order.
_Host = RwsAccess if TYPE_CHECKING else object


class RwsProgram(_Host):
    """Loading, starting and stopping the program under mastership (see the module docstring)."""

    # Set by RwsController.__init__.
    link_module: str

    def load_program(self, modules: Iterable[tuple[str, str]], timeout: float | None = None, folder: str = "$HOME/handeye") -> None:
        """Upload RAPID modules, load them into the task (replacing those of the same name), reset the
        program pointer and start ``main``.

        Parameters
        ----------
        modules : iterable of (filename, text)
            ``HeMain.mod``, ``HeRws.mod``, ``HeTool.mod`` (what ``handeye rapid generate`` writes).
        """
        deadline = self._budget(timeout if timeout is not None else max(self.timeout, 10.0))
        files = [(str(name), str(text)) for name, text in modules]
        if not files:
            raise InvalidRequest("no RAPID modules to load")

        def load(d: Deadline) -> None:
            self._execution("stop", d, {"stopmode": "stop", "usetsp": "normal"})
            for name, text in files:
                self._request("PUT", f"/fileservice/{folder}/{name}", d, data=text.encode("latin-1"),
                              what=f"upload {name}")
                if self.generation == 1:
                    path = f"/rw/rapid/tasks/{self.task}?action=loadmod"
                else:
                    path = f"/rw/rapid/tasks/{self.task}/loadmod"
                self._request("POST", path, d, data={"modulepath": f"{folder}/{name}", "replace": "true"},
                              what=f"load {name}")
            self._execution("resetpp", d, {})
            if any(name.lower().startswith(self.link_module.lower() + ".") for name, _ in files):
                # a PERS keeps the last run's value until HeLinkOpen runs: clear it, so that a stale READY
                # is not taken for the new program's
                self._set_symbol(self.link_module, "heRwsLink", [0, 0, 0, 0, 0], d)
            self._execution("start", d, {"regain": "continue", "execmode": "continue", "cycle": "forever",
                                         "condition": "none", "stopatbp": "disabled", "alltaskbytsp": "false"})

        self._call("load the program", lambda d: self._as_master("load the program", load, d), deadline=deadline)
        while self._call("wait for the program", lambda d: self._symbol_value(self.link_module, "heRwsLink", d),
                         deadline=deadline)[4] != PROTOCOL_VERSION:
            if deadline.remaining() <= self.poll_s:
                raise self.timeout_error(f"the program loaded at {self.address} did not start within "
                                         f"{deadline.seconds:g} s (heRwsLink stays cleared): check the FlexPendant")
            time.sleep(self.poll_s)
        self._info = None
        self._connected = False  # read the program's identity again
        self.connect(max(deadline.remaining(), self.timeout))

    def stop_program(self, timeout: float | None = None) -> None:
        """Stop RAPID execution (the end of a capture)."""
        self._call("stop the program", lambda d: self._as_master(
            "stop the program", lambda d2: self._execution("stop", d2, {"stopmode": "stop", "usetsp": "normal"}), d),
            timeout)

    def _execution(self, action: str, deadline: Deadline, data: dict) -> None:
        path = f"/rw/rapid/execution?action={action}" if self.generation == 1 else f"/rw/rapid/execution/{action}"
        self._request("POST", path, deadline, data=data, what=f"execution {action}")
