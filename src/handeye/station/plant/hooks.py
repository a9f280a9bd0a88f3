"""The one call each command makes at its end: publish what it did, when the station has ``plant:``.

:func:`after_calibrate`, :func:`after_writeback` and :func:`after_verify` find the plant settings (the
station file's ``plant:``; for ``calibrate``, which reads no station file, the one the session's capture
recorded), make the event (``station.plant.events``), put it in the outbox and send what waits
(``station.plant.publisher``) within ``plant.publish_timeout_s``. Without ``plant:`` they return at once
and import nothing more (no MQTT client). They never raise and never change the command's exit status:
a fault is one ``warning`` line on stderr, and the events wait in the outbox for the next command.
"""

from __future__ import annotations

import sys

__all__ = ["after_calibrate", "after_writeback", "after_verify", "publish_event", "recorded_plant"]


def _warn(command: str, message: str) -> None:
    print(f"handeye {command}: warning: plant: {message}", file=sys.stderr, flush=True)


def recorded_plant(session):
    """The ``PlantSettings`` a session's capture recorded (``capture.config.plant``), or None."""
    capture = (getattr(session, "extra", None) or {}).get("capture")
    recorded = capture.get("config") if isinstance(capture, dict) else None
    data = recorded.get("plant") if isinstance(recorded, dict) else None
    if not isinstance(recorded, dict) or not isinstance(data, dict):
        return None, {}
    from .settings import plant_rule

    data = {key: value for key, value in data.items()}
    mqtt = dict(data.get("mqtt") or {})
    if mqtt.get("password") == "<set>":  # the record never holds the secret: password_env, or nothing
        mqtt["password"] = None
    data["mqtt"] = mqtt
    return plant_rule(data, "plant", {}), recorded


def publish_event(command: str, plant, make_event) -> None:
    """Make the event (``make_event()``), keep it in the outbox, send what waits; a fault is one warning line."""
    try:
        from .outbox import Outbox
        from .publisher import Link, deliver

        link = Link(plant, plant.publish_timeout_s).start()  # connects while the event is made and kept
        outbox = Outbox(plant.outbox_dir())
        try:
            event = outbox.add(make_event())
        except BaseException:
            link.close()
            raise
        delivery = deliver(plant, outbox, link=link)
        if delivery.fault is not None:
            _warn(command, f"{delivery.fault}; {delivery.waiting} event(s) wait in {outbox.folder} (sent with the next "
                           f"command; this one's is #{event['seq']})")
    except Exception as exc:  # noqa: BLE001 (publishing never fails the command it follows)
        _warn(command, f"the event was not published ({type(exc).__name__}: {exc})")


def after_calibrate(args, outcome, assessment) -> None:
    """``handeye calibrate``'s last call: its result and verdict, when the session's station has ``plant:``."""
    config = getattr(args, "config", None)
    try:
        if config:  # a calibrate that reads a station file (not yet: the session's record otherwise)
            from ..config.station import load_config

            station = load_config(config)
            plant, recorded = station.plant, (station.to_dict() if station.plant is not None else {})
        else:
            plant, recorded = recorded_plant(outcome.session)
    except Exception as exc:  # noqa: BLE001
        _warn("calibrate", f"the session's plant settings cannot be read ({exc}); nothing published")
        return
    if plant is None:
        return
    from .events import calibration_event

    publish_event("calibrate", plant, lambda: calibration_event(plant, recorded, outcome.session_path,
                                                                assessment.result, assessment.verdict))


def after_writeback(args, config, outcome, quick_update: bool, reason: str | None = None) -> None:
    """``handeye writeback``'s last call (not on a dry run): what was written and whether it read back."""
    if getattr(config, "plant", None) is None or outcome is None or outcome.new is None or getattr(args, "dry_run", False):
        return
    from .events import writeback_event

    publish_event("writeback", config.plant, lambda: writeback_event(config.plant, config.to_dict(), args.session,
                                                                     outcome, quick_update, reason))


def after_verify(args, config, data: dict) -> None:
    """``handeye verify``'s last call: the check's verdict, diagnosis and quick update."""
    if getattr(config, "plant", None) is None:
        return
    from .events import verify_event

    publish_event("verify", config.plant, lambda: verify_event(config.plant, config.to_dict(), args.against, data))
