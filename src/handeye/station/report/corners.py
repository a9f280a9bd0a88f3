"""The report's note on partial views (issue 37): how many board corners each posture saw."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ...calibration import HandEyeProblem

__all__ = ["corners_section"]


def corners_section(problem: HandEyeProblem) -> str:
    """An HTML section listing the corners seen per posture when some postures saw part of the board
    (``problem.seen``); "" when every posture saw every corner (a checkerboard session: unchanged report)."""
    seen = getattr(problem, "seen", None)
    if seen is None:
        return ""
    counts = np.asarray(seen, bool).sum(axis=1)
    m = seen.shape[1]
    partial = [(int(i), int(c)) for i, c in zip(problem.posture_ids, counts) if c < m]
    rows = "".join(f"<tr><td>{i}</td><td>{c}</td><td>{100 * c / m:.0f} %</td></tr>" for i, c in partial)
    return ("<h2>Corners per posture</h2><section>"
            f'<p class="how">{len(partial)} of {len(counts)} postures saw part of the board ({m} corners; median '
            f"{int(np.median(counts))} seen). Each posture's board pose is the rigid fit of the corners it saw, by id; the "
            "default estimator weighs the unseen corners zero.</p>"
            f"<table><tr><th>posture</th><th>corners seen</th><th>of the board</th></tr>{rows}</table></section>"
            if partial else "")
