"""What a check compares against: SESSION's result, or the latest deliberate write-back that followed it.

Every ``handeye writeback`` (a calibration's result, or a check's quick update) appends a ``writeback``
record to the history beside the sessions (``station.verify.history``) naming the folder written
(``session``) and the calibrated session it descends from (``of``). ``handeye verify --against
SESSION`` follows the last such record:

- none, or one of SESSION itself: the check is against SESSION's result (``result.yaml``);
- a quick update of SESSION (a check's folder ``SESSION-verify-<time>``): the check is against the
  update: its X replaces SESSION's in the baseline, with the update's covariance for X (the board's,
  the arm's and the noise levels stay SESSION's; the cross-covariance of X with them is dropped, which
  counts the board's uncertainty twice at most: a more cautious test), and the controller's tool
  data is compared with the update, so a written update is never reported as a wrong tool to restore;
- a write-back of another session: the check is against SESSION, but a tooldata finding names that
  write-back and never advises undoing it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...base import HandEyeError

if TYPE_CHECKING:
    from ...calibration import CalibrationResult

__all__ = ["Reference", "follow", "lineage", "written_record"]


def _resolved(path) -> str:
    return str(Path(path).resolve())


def lineage(folder) -> str:
    """The calibrated session ``folder`` descends from (resolved): a check's folder gives the session it
    checked (its ``verify.json``, else its name ``SESSION-verify-<time>``), any other folder itself."""
    import json

    folder = Path(folder).resolve()
    outcome = folder / "verify.json"
    if outcome.is_file():
        try:
            named = Path(json.loads(outcome.read_text(encoding="utf-8"))["session"])
        except (OSError, ValueError, KeyError, TypeError):
            named = None
        if named is not None:
            for candidate in ((named,) if named.is_absolute() else (named, folder.parent / named.name)):
                if (candidate / "session.yaml").is_file():
                    return _resolved(candidate)
    if "-verify-" in folder.name:
        return _resolved(folder.parent / folder.name.split("-verify-")[0])
    return str(folder)


def written_record(folder, outcome, what: str) -> dict:
    """The history record of one write-back of ``folder`` (``station.writeback.WritebackOutcome``)."""
    new = outcome.new
    return {"kind": "writeback", "session": _resolved(folder), "of": lineage(folder), "what": what,
            "readback_ok": bool(outcome.readback_ok),
            "tool": {"position_mm": list(new.position_mm), "quaternion_wxyz": list(new.quaternion_wxyz)}}


@dataclass(frozen=True)
class Reference:
    """The write-back a check follows (:func:`follow`).

    Attributes
    ----------
    kind : str
        ``session`` (SESSION's own result), ``update`` (a quick update of SESSION) or ``other``
        (the last write-back was of another session).
    record : dict or None
        The history's ``writeback`` record (None: no write-back recorded).
    result : CalibrationResult or None
        The quick update as a result (``update`` only).
    covariance : ndarray, shape (6, 6) or None
        The update's covariance of ``(δx)`` in the baseline's parameters (mm, rad; ``update`` only).
    """

    kind: str
    record: dict | None = None
    result: CalibrationResult | None = None
    covariance: np.ndarray | None = None

    @property
    def folder(self) -> str | None:
        return None if self.record is None else self.record.get("session")

    def line(self) -> str | None:
        """What the check follows, in one line (None when it is SESSION's own result)."""
        if self.kind == "update":
            return (f"checking against the quick update written from {self.folder} at {(self.record or {}).get('time', '?')} "
                    "(the latest write-back in the history), not the session's own result")
        return None

    def apply(self, baseline):
        """The ``calibration.verification.Baseline`` of the check: SESSION's, with the update's X."""
        if self.kind != "update":
            return baseline
        if self.result is None:  # follow() builds every update with its result and covariance
            from .plan import VerifyError

            raise VerifyError("the quick update the check follows has no result")
        cov = np.array(baseline.covariance, float)
        cov[:6, :] = 0.0
        cov[:, :6] = 0.0
        cov[:6, :6] = self.covariance
        return replace(baseline, x=np.array(self.result.x, float), covariance=cov)


def _update_covariance(result, parent: np.ndarray) -> np.ndarray:
    """The quick update's covariance back in the fit's parameters (``drift_causes.quick_update`` rotates
    its ``(δt, δr)`` into the parent frame and scales radians to degrees: undone here)."""
    block = np.zeros((6, 6))
    block[:3, :3] = block[3:, 3:] = np.asarray(result.x, float)[:3, :3]
    scale = np.r_[np.ones(3), np.full(3, 180.0 / np.pi)]
    inner = block.T @ (np.asarray(parent, float) / np.outer(scale, scale)) @ block
    return 0.5 * (inner + inner.T)


def follow(session_dir) -> Reference:
    """The latest deliberate write-back in the history beside ``session_dir``, as the check uses it.

    Raises
    ------
    VerifyError
        The last write-back is a quick update of SESSION whose check folder can no longer be read.
    """
    from .history import history_path, load_history
    from .plan import VerifyError
    from .update import verify_check

    records = [r for r in load_history(history_path(session_dir)).records if r.get("kind") == "writeback"]
    if not records:
        return Reference("session")
    record = records[-1]
    folder = record.get("session")
    if not isinstance(folder, str):
        return Reference("session")
    of = record.get("of") or lineage(folder)
    session = _resolved(session_dir)
    if of != session:
        return Reference("other", record)
    if _resolved(folder) == session:
        return Reference("session", record)
    try:
        check = verify_check(folder)
        if check is None:
            raise HandEyeError("it holds no verify.json")
        covariance = _update_covariance(check[0], _quick_update(folder)["uncertainty"]["covariance"])
    except (HandEyeError, KeyError, TypeError, ValueError) as exc:
        raise VerifyError(f"the latest write-back in the history is the quick update of {folder}, which cannot be read "
                          f"({exc}): restore that folder, or write a calibration back (handeye writeback {session_dir}) "
                          "to check against it") from None
    return Reference("update", record, check[0], covariance)


def _quick_update(folder) -> dict:
    import json

    from ...base import OutputError
    from ...base import read_text_file

    return json.loads(read_text_file(Path(folder) / "verify.json", "check outcome", OutputError))["quick_update"]
