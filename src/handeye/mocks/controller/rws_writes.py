"""What the mock Robot Web Services writes (a mixin of
:class:`~handeye.mocks.controller.rws_server.RwsControllerServer`): module data by symbol, mastership,
the manual-mode grant (RMMP), RAPID execution, loading modules from its virtual file system, with
the controller's refusals (403 without mastership or RMMP, 409 with the motors off)."""

from __future__ import annotations

import logging
import threading
from typing import TYPE_CHECKING, Any

from ...drivers import parse_rapid_value
from ...rapid import RapidError
from ...rapid import ModuleSource, parse_module
from ...rapid import aggregate, coerce, coerce_array
from .rws_web import HttpError
from .sources import ControllerProgram

if TYPE_CHECKING:
    from .faults import Faults
    from .runner import RapidRunner

__all__ = ["RwsWrites", "E_MASTERSHIP", "E_RMMP", "E_STATE"]

log = logging.getLogger("handeye.mocks.controller.rws_server")

#: ABB's code in a refusal for a write without mastership (RWS 2.0 manual; reference/abb-controller.md).
E_MASTERSHIP = -1073445862
E_RMMP = -1073445863
E_STATE = -1073445865


class RwsWrites:
    """POST, PUT and DELETE answers (see the module docstring)."""

    # what the mixin uses of the server (RwsControllerServer, its base and RwsReads)
    runner: RapidRunner | None
    source: ControllerProgram
    faults: Faults
    sessions: dict[str, dict]
    files: dict[str, bytes]
    generation: int
    opmode: str
    rmmp_policy: str
    motors_on: bool
    running: bool
    master: str | None
    writes: int
    _lock: threading.RLock
    _pers: dict[tuple[str, str], Any]
    _fresh_modules: set[str]
    _loaded: ControllerProgram | None

    if TYPE_CHECKING:
        def _symbol(self, symbol: tuple) -> Any: ...
        def _symbol_of(self, path: str) -> tuple | None: ...
        def _load(self, program: ControllerProgram) -> None: ...
        def _run(self, program: ControllerProgram) -> None: ...
        def restart(self) -> None: ...

    def _set_symbol(self, symbol, text: str) -> None:
        datum = self._symbol(symbol)
        program = self.runner.program if self.runner is not None else None
        if program is None:  # _symbol found the datum in the loaded program: never None here
            raise HttpError(409, "no RAPID program is loaded", E_STATE)
        if datum.storage == "CONST":
            raise HttpError(400, f"{datum.name} is a CONST", -1073442811)
        try:
            value = parse_rapid_value(text)
            if datum.dims:
                new = coerce_array(aggregate(value), datum.type, datum.dims, program.records, datum.name)
            else:
                new = coerce(aggregate(value), datum.type, program.records, datum.name)
        except (ValueError, RapidError) as exc:
            raise HttpError(400, f"value {text[:60]!r} for {datum.name}: {exc}", -1073442811) from None
        datum.box[0] = new
        self.writes += 1
        if datum.storage == "PERS":
            self._pers[(datum.module.lower(), datum.name.lower())] = new

    def _may_write(self, session: str, what: str, implicit: bool = True) -> None:
        """Refuse a write without the right to it: RMMP in manual mode, mastership held elsewhere.

        RWS 1.0 takes mastership implicitly for a single write when nobody holds it (what
        abb-robot-client relies on); RWS 2.0 requires an explicit request (ABB RWS 2.0 manual).
        """
        if self.opmode.startswith("MAN") and self.sessions.get(session, {}).get("rmmp") != "modify":
            raise HttpError(403, f"{what}: the controller is in manual mode and this client has no RMMP "
                                 "(request it and press Allow on the FlexPendant)", E_RMMP)
        if self.faults.mastership_held:
            raise HttpError(403, f"{what}: mastership is held by another client (FlexPendant)", E_MASTERSHIP)
        if self.master not in (None, session):
            raise HttpError(403, f"{what}: mastership is held by another client", E_MASTERSHIP)
        if self.master is None and not (implicit and self.generation == 1):
            raise HttpError(403, f"{what}: mastership is required; request it first", E_MASTERSHIP)

    def _post(self, path, action, form, session):
        gen2 = self.generation == 2
        if path.startswith("/rw/mastership"):
            verb = path.rsplit("/", 1)[-1] if gen2 else action
            return self._mastership(verb, session)
        if path == "/users/rmmp":
            return self._request_rmmp(form, session)
        if path == "/rw/panel/restart" or (path == "/rw/panel" and action == "restart"):
            self._may_write(session, "restart")
            self.restart()
            return 204, None
        if path.startswith("/rw/rapid/execution"):
            verb = path.rsplit("/", 1)[-1] if gen2 else action
            return self._execution(verb, session)
        if path.startswith("/rw/rapid/tasks/T_ROB1"):
            verb = path.rsplit("/", 1)[-1] if gen2 else action
            if verb == "loadmod":
                return self._loadmod(form, session)
            raise HttpError(400, f"task action {verb!r} is not simulated")
        symbol = self._symbol_of(path)
        if symbol is not None and (gen2 or action == "set"):
            if "value" not in form:
                raise HttpError(400, "a symbol write needs the form field value", -1073442811)
            with self._lock:
                self._may_write(session, f"write {'/'.join(s for s in symbol if s)}")
                self._set_symbol(symbol, form["value"])
            return 204, None
        raise HttpError(404, f"no resource {path} (action {action})", -1073442812)

    def _mastership(self, verb, session):
        with self._lock:
            if verb == "request":
                if self.opmode.startswith("MAN") and self.sessions.get(session, {}).get("rmmp") != "modify":
                    raise HttpError(403, "mastership: the controller is in manual mode and this client has no RMMP "
                                         "(request it and press Allow on the FlexPendant)", E_RMMP)
                if self.faults.mastership_held or self.master not in (None, session):
                    raise HttpError(403, "mastership is held by another client (FlexPendant)", E_MASTERSHIP)
                self.master = session
                return 204, None
            if verb == "release":
                if self.master == session:
                    self.master = None
                return 204, None
        raise HttpError(400, f"mastership action {verb!r} unknown")

    def _request_rmmp(self, form, session):
        if form.get("privilege") != "modify":
            raise HttpError(400, "RMMP privilege must be modify")
        self.sessions[session]["rmmp_asked"] = True
        if self.rmmp_policy == "allow":
            self.sessions[session]["rmmp"] = "modify"
        elif self.rmmp_policy == "deny":
            self.sessions[session]["rmmp"] = "denied"
        return 202, None

    def _execution(self, verb, session):
        with self._lock:
            self._may_write(session, f"execution {verb}")
            if verb == "start":
                if not self.motors_on:
                    raise HttpError(409, "cannot start: the motors are off", E_STATE)
                if not self.running:
                    try:
                        self._run(self.source)
                    except RapidError as exc:  # link errors of the loaded modules, as the pendant shows them
                        raise HttpError(409, f"cannot start the program: {exc}", E_STATE) from None
            elif verb == "stop":
                if self.runner is not None:
                    self.runner.stop()
            elif verb != "resetpp":  # the mock always starts from main: resetpp has nothing more to do
                raise HttpError(400, f"execution action {verb!r} unknown")
        return 204, None

    def _loadmod(self, form, session):
        with self._lock:
            self._may_write(session, "load module")
            if self.running:
                raise HttpError(409, "load module: the task is running; stop it first", E_STATE)
            path = form.get("modulepath", "")
            data = self.files.get(self._file_key(path))
            if data is None:
                raise HttpError(400, f"load module: no file {path}", -1073442811)
            name = path.rsplit("/", 1)[-1]
            text = data.decode("latin-1")
            try:
                module = parse_module(text, name).name
            except RapidError as exc:
                raise HttpError(400, f"load module {name}: {exc}", -1073442811) from None
            kept = [m for m in self.source.modules if parse_module(m.text, m.source).name.lower() != module.lower()]
            if len(kept) == len(self.source.modules) or form.get("replace", "false").lower() == "true":
                program = ControllerProgram(tuple(kept) + (ModuleSource(text, name),), self.source.origin,
                                            self.source.link, self.source.tool_name)
                self._fresh_modules.add(module.lower())
                self.source = program
                try:
                    self._load(program)  # linked now: its symbols are there before the start
                except RapidError as exc:
                    # a controller loads a module whose references are not there yet (the next module
                    # brings them); the link errors stop the start, as on the FlexPendant
                    log.info("mock RWS: %s loaded, not linked yet: %s", name, exc)
                    self._loaded = None
            else:
                raise HttpError(409, f"load module: {module} is loaded already (replace=true replaces it)", E_STATE)
        return 204, None

    @staticmethod
    def _file_key(path: str) -> str:
        path = path.strip("/")
        return path if path.startswith("$") else "$HOME/" + path

    def _files(self, method, path, body, session):
        key = self._file_key(path)
        if method == "PUT":
            self.files[key] = bytes(body)
            return 201, None
        if method == "DELETE":
            self.files.pop(key, None)
            return 204, None
        if method == "GET" and key in self.files:
            return 200, (self.files[key], "text/plain")
        raise HttpError(404, f"no file {key}", -1073442812)
