"""The live view of a ChArUco capture in a real browser (issue 37): headless Chromium loads the page of
`handeye capture --mock --guided --view` with a ChArUco board, a band of it covered at every posture
(``mock.occlude``), and each posture's frame shows the corners the capture measured, each in its id's
colour (``station.view.frames.corner_colours``), so the page says which part of the board is seen.

Skips, saying why, without Chromium (Debian: `chromium`, `chromium-driver`) or selenium.
"""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest

from handeye.geometry.targets import STATION_CHARUCO
from test_live_view_browser import CHROMIUM, DRIVER, _browser, live_view_url

POSTURES = 3

pytestmark = pytest.mark.skipif(CHROMIUM is None or DRIVER is None,
                                reason="no headless Chromium here (apt-get install chromium chromium-driver)")

CONFIG = ("controller: {protocol: mock}\ncamera: {backend: mock}\nboard: {type: charuco}\n"
          "mock: {occlude: {postures: 1.0, band: [0.25, 0.4]}}\n")


@pytest.fixture(scope="module")
def watched(tmp_path_factory):
    """What the page drew over every frame of a guided ChArUco capture of POSTURES postures."""
    browser = _browser()
    root = tmp_path_factory.mktemp("charuco_view")
    (root / "station.yaml").write_text(CONFIG)
    session = root / "session"
    command = [sys.executable, "-m", "handeye.station", "capture", "--config", str(root / "station.yaml"), "--mock",
               "--session", str(session), "--postures", str(POSTURES), "--guided", "--view"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    lines = []
    try:
        browser.get(live_view_url(process, lines))
        drawn = []
        while process.poll() is None:
            drawn = browser.execute_script("return (window.viewLog.drawn || []).slice();") or drawn
            time.sleep(0.2)
        time.sleep(0.3)
        drawn = browser.execute_script("return (window.viewLog.drawn || []).slice();") or drawn
        yield {"session": session, "drawn": drawn, "rc": process.returncode,
               "output": "".join(lines) + process.stdout.read()}
    finally:
        if process.poll() is None:
            process.kill()
        process.wait(timeout=30)
        browser.quit()


def test_each_posture_shows_the_corners_it_measured_in_their_ids_colours(watched):
    from handeye.calibration.session import read_session
    from handeye.station.view.frames import corner_colours

    assert watched["rc"] == 0, watched["output"]
    postures = read_session(watched["session"]).postures
    assert len(postures) == POSTURES
    partial = 0
    for posture in postures:
        ids = np.asarray(posture.corner_ids, int)
        partial += len(ids) < STATION_CHARUCO.count
        own = [r for r in watched["drawn"] if r["kind"] == "measured" and r["posture"] == posture.index]
        assert own, f"posture {posture.index}'s measured frame was never drawn"
        for record in own:
            for side in ("left_ids", "right_ids"):
                shown = [int(i) for i, _ in record[side]]
                assert shown == ids.tolist()  # the matched corners the capture triangulated, by id
                assert [fill for _, fill in record[side]] == corner_colours(ids, STATION_CHARUCO)
    assert partial >= 1, "no posture saw part of the board: the band did not cover it"


def test_the_colours_say_which_part_of_the_board_is_seen():
    from handeye.station.view.frames import corner_colours

    every = corner_colours(np.arange(STATION_CHARUCO.count), STATION_CHARUCO)
    assert len(set(every)) == STATION_CHARUCO.count  # one colour per id
    assert corner_colours([5, 40], STATION_CHARUCO) == [every[5], every[40]]  # stable: the id alone decides
    nx = STATION_CHARUCO.corners[0]
    hue = lambda c: __import__("colorsys").rgb_to_hls(*(int(c[k:k + 2], 16) / 255 for k in (1, 3, 5)))  # noqa: E731
    assert hue(every[0])[0] < hue(every[nx - 1])[0]  # the hue runs along the long side
    assert hue(every[0])[1] < hue(every[nx * (STATION_CHARUCO.corners[1] - 1)])[1]  # lighter down the short side
