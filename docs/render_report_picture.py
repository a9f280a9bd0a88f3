"""Render the front page's picture of the report: ``docs/assets/report.png``.

Runs ``handeye demo`` in a temporary folder and photographs the top of its ``session/report.html``
with headless Chromium (Debian's ``/usr/bin/chromium``)::

    python docs/render_report_picture.py            # writes docs/assets/report.png
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

OUT = Path(__file__).resolve().parent / "assets" / "report.png"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", "--no-first-run", "--hide-scrollbars"]


def main() -> int:
    """Run the demo, photograph its report at 1200 x 1100 px, and write the PNG."""
    browser = shutil.which("chromium") or "/usr/bin/chromium"
    if not Path(browser).exists():
        print("render_report_picture: error: needs Debian's chromium (apt-get install chromium)", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(["handeye", "demo"], cwd=tmp, check=True, stdout=subprocess.DEVNULL)
        report = Path(tmp, "handeye_demo", "session", "report.html")
        subprocess.run([browser, *FLAGS, f"--user-data-dir={tmp}/chromium", "--window-size=1200,1100",
                        f"--screenshot={OUT}", report.as_uri()], check=True, capture_output=True, timeout=120)
    print(f"written {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
