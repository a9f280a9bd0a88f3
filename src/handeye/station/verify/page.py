"""The HTML page of a check and of a station's history: the outcome's lines and the trend figure."""

from __future__ import annotations

import base64
import html
from pathlib import Path

from ...base import write_text_atomic
from .history import history_lines, trend_png

__all__ = ["write_history_report"]


def write_history_report(path, history, thresholds, data: dict | None) -> Path:
    """Write the page (the check ``data`` when given, then the history's trend and lines, and the
    damaged records skipped); returns its path. ``history``: a ``verify_history.History`` or its records."""
    records = getattr(history, "records", history)
    skipped = history.skipped_line() if hasattr(history, "skipped_line") else None
    png = base64.b64encode(trend_png(records, thresholds.max_sigma_translation_mm,
                                     thresholds.max_sigma_rotation_deg)).decode("ascii")
    head = ""
    if data is not None:
        diag = data["diagnosis"]
        head = (f"<h2>Check of {html.escape(str(data['session']))}: {html.escape(data['verdict'].upper())}</h2>"
                f"<p>{html.escape(data['reason'])}</p><p>cause: {html.escape(str(diag['cause']))}"
                f"{' ' + str(diag['joint']) if diag.get('joint') else ''}, {diag['translation_mm']:.3f} mm, "
                f"{diag['rotation_deg']:.4f} deg</p>")
    rows = "".join(f"<li><code>{html.escape(line)}</code></li>" for line in history_lines(records))
    text = (f"<!doctype html><html><head><meta charset='utf-8'><title>handeye verify</title></head><body "
            f"style='font-family:sans-serif;max-width:900px;margin:2em auto'>{head}<h2>History</h2>"
            f"<img alt='trend' src='data:image/png;base64,{png}'><ul>{rows}</ul>"
            + (f"<p class='skipped'>{html.escape(skipped)}</p>" if skipped else "") + "</body></html>\n")
    return write_text_atomic(path, text)
