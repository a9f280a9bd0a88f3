"""What the mock Robot Web Services reads (a mixin of
:class:`~handeye.mocks.controller.rws_server.RwsControllerServer`): the simulated arm's joints and
flange pose, the panel, the RMMP state and the task's module data by symbol, printed as RWS prints
RAPID values (float32 numbers)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...drivers import SIMULATION_SYSTEM_NAME
from ...rapid import format_value
from .rws_web import HttpError

if TYPE_CHECKING:
    from ..robot import SimulatedRobot
    from .runner import RapidRunner

__all__ = ["RwsReads", "rws_text", "rws_num"]


def rws_num(value: float) -> str:
    """A num as RWS prints it: the shortest text that gives back the same float32."""
    v = np.float32(value)
    if v == int(v) and abs(v) < 1e9:
        return str(int(v))
    if 1e-4 <= abs(v) < 1e9:
        return np.format_float_positional(v, unique=True, trim="-")
    return np.format_float_scientific(v, unique=True, trim="-").upper()


def _unreadable(value):
    raise HttpError(400, f"a {type(value).__name__} cannot be read over RWS")


def rws_text(value: object) -> str:
    """A RAPID value as RWS prints it (``ValToStr``'s form with RWS's float32 numbers)."""
    return format_value(value, rws_num, _unreadable)


class RwsReads:
    """GET answers (see the module docstring)."""

    # what the mixin uses of the server (RwsControllerServer and its base)
    robot: SimulatedRobot
    runner: RapidRunner | None
    sessions: dict[str, dict]
    generation: int
    robotware: str
    opmode: str
    rmmp_policy: str
    motors_on: bool
    running: bool

    def _read(self, path: str, query) -> list:
        robot = self.robot
        mech = "/rw/motionsystem/mechunits/ROB_1/"
        if path == mech + "jointtarget":
            joints = robot.current_joints
            state = {"_type": "ms-jointtarget", "_title": "ROB_1"}
            state.update({f"rax_{i + 1}": f"{float(v):.6f}" for i, v in enumerate(joints)})
            state.update({f"eax_{c}": "9E+09" for c in "abcdef"})
            return [state]
        if path == mech + "robtarget":
            return [self._robtarget(query)]
        if path in ("/rw/panel/ctrlstate", "/rw/panel/ctrl-state"):
            return [{"_type": "pnl-ctrlstate", "_title": "ctrlstate", "ctrlstate": "motoron" if self.motors_on else "motoroff"}]
        if path == "/rw/panel/opmode":
            return [{"_type": "pnl-opmode", "_title": "opmode", "opmode": self.opmode}]
        if path == "/rw/rapid/execution":
            return [{"_type": "rap-execution", "_title": "execution",
                     "ctrlexecstate": "running" if self.running else "stopped", "cycle": "forever"}]
        if path == "/rw/system":
            return [{"_type": "sys-system", "_title": "system", "name": SIMULATION_SYSTEM_NAME, "rwversion": self.robotware,
                     "rwversionname": f"RobotWare {self.robotware}", "sysid": "{mock}"}]
        if path in ("/users/rmmp", "/users/rmmp/poll"):
            return [self._rmmp_state(path)]
        if path == "/rw/rapid/tasks":
            return [{"_type": "rap-task-li", "_title": "T_ROB1", "name": "T_ROB1", "type": "norm",
                     "taskstate": "linked", "excstate": "started" if self.running else "stopped",
                     "active": "On", "motiontask": "TRUE"}]
        symbol = self._symbol_of(path)
        if symbol is not None:
            value = self._symbol(symbol).box[0]
            return [{"_type": "rap-data", "_title": "/".join(s for s in symbol if s), "value": rws_text(value)}]
        raise HttpError(404, f"no resource {path}", -1073442812)

    def _robtarget(self, query) -> dict:
        tool = query.get("tool", ["tool0"])[0].lower()
        wobj = query.get("wobj", ["wobj0"])[0].lower()
        if tool != "tool0" or wobj != "wobj0":
            raise HttpError(400, f"the mock reports the flange only (tool0, wobj0); got tool={tool}, wobj={wobj}")
        pose = self.robot.tool0_pose()  # what CRobT(\Tool:=tool0 \WObj:=wobj0) gives the program
        p, q = pose.position_mm, pose.quaternion_wxyz
        state = {"_type": "ms-robtargets", "_title": "ROB_1"}
        state.update({c: f"{float(v):.6f}" for c, v in zip("xyz", p)})
        state.update({f"q{i + 1}": f"{float(v):.9f}" for i, v in enumerate(q)})
        state.update({"cf1": "0", "cf4": "0", "cf6": "0", "cfx": "0"})
        state.update({f"eax{c}": "9E+09" for c in "abcdef"})
        return state

    def _rmmp_state(self, path: str) -> dict:
        rights = {s["rmmp"] for s in self.sessions.values()}
        if "modify" in rights:
            status = "GRANTED"
        elif "denied" in rights:
            status = "DENIED"
        elif self.rmmp_policy == "ignore" and any(s.get("rmmp_asked") for s in self.sessions.values()):
            status = "PENDING"  # nobody pressed Allow or Deny on the FlexPendant
        else:
            status = "NONE"
        if path.endswith("poll"):
            return {"_type": "user-rmmp-poll", "_title": "poll", "status": status}
        return {"_type": "user-rmmp", "_title": "rmmp", "privilege": "modify" if status == "GRANTED" else "none",
                "status": status}

    def _symbol_of(self, path: str):
        """``(task, module or None, name)`` of a symbol path of either generation, else None."""
        if self.generation == 1 or path.startswith("/rw/rapid/symbol/data/"):
            prefix = "/rw/rapid/symbol/data/RAPID/"
            if not path.startswith(prefix):
                return None
            parts = path[len(prefix):].strip("/").split("/")
        else:
            prefix = "/rw/rapid/symbol/RAPID/"
            if not path.startswith(prefix) or not path.endswith("/data"):
                return None
            parts = path[len(prefix):-len("/data")].strip("/").split("/")
        # ABB's documentation names symbols RAPID/<task>/<module>/<name>; abb-robot-client sends
        # RAPID/<task>/<name>, which a controller resolves for global data: both are served.
        if len(parts) == 3:
            return tuple(parts)
        if len(parts) == 2:
            return (parts[0], None, parts[1])
        return None

    def _symbol(self, symbol):
        task, module, name = symbol
        if task.upper() != "T_ROB1":
            raise HttpError(404, f"no task {task}", -1073442812)
        program = self.runner.program if self.runner is not None else None
        found = program.datum(name, module) if program is not None else None
        if found is None:
            where = f"{module}/{name}" if module else name
            raise HttpError(404, f"symbol RAPID/{task}/{where} not found", -1073442812)
        return found
