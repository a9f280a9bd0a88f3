"""``handeye writeback`` as a workflow: which result, which controller, what is refused, what is recorded.

1. the station config (``--config``, or the embedded mock's with ``--mock``) and SESSION (lengths in
   mm) are read; a rehearsal's controller is checked to be the standalone mock, and a mock or
   simulated session is refused for a real controller (``station.writeback.check_session_origin``);
2. the result: a check's folder (``handeye verify``) gives its quick update, judged by its
   uncertainty (``station.verify.update``); any other SESSION gives its saved ``result.yaml``
   (``station.result_file``: refused when older than the postures or of another ``--method``; solved
   and saved first, saying so, when there is none), judged against the config's quality thresholds;
3. ``--dry-run`` prints the RAPID literal; otherwise the controller link opens and
   ``station.writeback.writeback`` backs up, writes and reads back;
4. every write is recorded in the history beside the sessions (``station.verify.reference``: the
   write-back ``handeye verify`` follows).

The command module (``station.commands.writeback``) only parses the arguments and calls :func:`run_writeback`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["WritebackRequest", "run_writeback", "writeback_source"]


@dataclass(frozen=True)
class WritebackRequest:
    """What ``handeye writeback`` was asked (its arguments)."""

    session: str
    config: str | None = None
    mock: bool = False
    dry_run: bool = False
    force: bool = False
    method: str | None = None
    units: str = "mm"


def writeback_source(request: WritebackRequest, session, config, origin: str | None,
                     say: Callable[[str], None]) -> tuple:
    """``(result, passed, reason, is_check)``: what would be written and its verdict (see the module docstring)."""
    from .report.assessment import assess
    from .report.quality import config_thresholds
    from .result_file import current_outcome
    from .verify.update import verify_check

    check = verify_check(request.session)
    if check is not None:  # a check's folder: its quick update is the result, judged by its uncertainty
        result, passed, reason = check
        say(f"quick update of handeye verify: {reason}")
        return result, passed, reason, True
    outcome = current_outcome(session, request.session, request.method, request.units, origin, say=say)
    assessment = assess(outcome, config_thresholds(config))
    verdict = assessment.verdict
    if verdict is None:  # assess with thresholds always judges
        from ..base import HandEyeError

        raise HandEyeError("the calibration was not judged against the quality thresholds")
    result, passed, reason = assessment.result, verdict.passed, verdict.line()
    say(f"calibration ({result.method}): {reason}")
    return result, passed, reason, False


def _station(request: WritebackRequest):
    """The station config and SESSION as read: ``(config, session, origin, mock_controller)``."""
    from ..calibration import session_in_mm
    from ..calibration import read_session
    from .config.station import default_config, load_config
    from .origin import MOCK, session_origin
    from .runtime import check_rehearsal
    from .config.station_kind import station_kind
    from .writeback import check_session_origin

    config = load_config(request.config) if request.config else default_config()
    if request.mock:
        config = config.as_mock()
    session = read_session(request.session)
    origin = session_origin(session)
    session = session_in_mm(session, request.units)
    mock_controller = station_kind(config) == MOCK  # the embedded mock, or a rehearsal's standalone one
    if not request.dry_run and config.is_rehearsal:
        check_rehearsal(config)  # the controller named is the standalone mock's: a mock session may go there
    if not request.dry_run:
        check_session_origin(origin, mock_controller)
    return config, session, origin, mock_controller


def run_writeback(request: WritebackRequest, say: Callable[[str], None] = lambda m: print(m, flush=True)) -> int:
    """Run ``handeye writeback`` (see the module docstring); returns the exit status.

    Raises
    ------
    HandEyeError
        Every refusal, in one line (``station.writeback.WritebackError``, ``result_file.ResultError``, ...).
    """
    from .origin import origin_line
    from .runtime import MOCK_BANNER, open_controller_link, rehearsal_banner
    from .writeback import side_by_side, writeback

    config, session, origin, mock_controller = _station(request)
    origin_said = origin_line(origin)
    if origin_said:
        say(origin_said)
    result, passed, reason, is_check = writeback_source(request, session, config, origin, say)
    common: dict[str, Any] = dict(verdict_passed=passed, verdict_reason=reason, force=request.force, origin=origin, progress=say)
    if request.dry_run:
        say(writeback(request.session, config, result, None, dry_run=True, **common).literal)
        return 0
    if config.is_mock:
        say(MOCK_BANNER)
    elif config.is_rehearsal:
        say(rehearsal_banner(config))
    with open_controller_link(config, session_dir=request.session) as link:
        outcome = writeback(request.session, config, result, link.controller, mock_controller=mock_controller, **common)
    _record(request.session, outcome, "quick update written" if is_check else f"calibration written ({result.method})")
    tag = "MOCK " if outcome.mock else ""
    say(side_by_side(outcome.old, outcome.new))
    say(outcome.literal)
    say(tag + ("read back: identical to the last digit the controller keeps" if outcome.readback_ok
               else "read back: DIFFERENT"))
    from .plant.hooks import after_writeback  # the plant's broker, when the config has plant:

    after_writeback(request, config, outcome, is_check, reason)
    return 0


def _record(folder, outcome, what: str) -> None:
    """The write's record in the history (the write-back verify follows); a history that cannot be written
    is one line on stderr: the tool data is written and read back all the same."""
    import sys

    from ..base import HandEyeError
    from .verify.history import append_record, history_path
    from .verify.reference import written_record

    try:
        append_record(history_path(folder), written_record(folder, outcome, what))
    except HandEyeError as exc:
        print(f"handeye writeback: warning: {exc}: the write is not in the history, so handeye verify does not know "
              "of it", file=sys.stderr)
