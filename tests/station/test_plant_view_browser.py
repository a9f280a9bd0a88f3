"""The fleet view in headless Chromium: ``handeye plant --config plant.yaml`` against a real mosquitto;
a cell whose camera serial changed, and one whose verify says drift, are flagged on the page within 2 s
of the event (issue 38); the page needs its token; ``--json`` prints the same table.

Skips, saying why, without mosquitto or without Chromium and its driver (.ci/system-deps installs them).
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
import urllib.error
import urllib.request

import pytest
import yaml

from plant_broker import MOSQUITTO_MISSING, PREFIX, Broker
from test_live_view_browser import CHROMIUM, DRIVER, _browser

from handeye.station.plant.hooks import publish_event
from handeye.station.plant.settings import plant_rule

pytestmark = [pytest.mark.skipif(MOSQUITTO_MISSING is not None, reason=MOSQUITTO_MISSING or ""),
              pytest.mark.skipif(CHROMIUM is None or DRIVER is None,
                                 reason="no headless Chromium here (apt-get install chromium chromium-driver)")]

FLAG_WITHIN_S = 2.0  # the bound


def _event(plant, kind, **values):
    event = {"topic_prefix": plant.mqtt.topic_prefix, "kind": kind, "station": plant.station, "camera_serial": "XB3-1001",
             "time": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "verdict": "ok", "diagnosis": {"cause": "none"}}
    if kind == "calibrate":
        event.update(verdict="pass", predicted_error_mm=0.21, standoff_mm=800.0, session="cal_01")
    event.update(values)
    return event


def _alarms(browser) -> dict:
    return browser.execute_script(
        "const out = {}; document.querySelectorAll('#fleet tbody tr').forEach(r => "
        "{ out[r.dataset.cell] = r.querySelector('td.alarms').textContent; }); return out;")


def _until(browser, condition, timeout_s):
    deadline = time.monotonic() + timeout_s
    while True:
        seen = _alarms(browser)
        if condition(seen) or time.monotonic() > deadline:
            return seen
        time.sleep(0.05)


@pytest.fixture
def fleet_view(tmp_path):
    broker = Broker(tmp_path / "broker", cells=("cell01", "cell02")).start()
    config = tmp_path / "plant.yaml"
    config.write_text(yaml.safe_dump({"mqtt": broker.fleet_mqtt(), "verify_interval_h": 24, "stale_after_h": 1}))
    process = subprocess.Popen([sys.executable, "-m", "handeye.station", "plant", "--config", str(config)],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    line = process.stdout.readline()
    match = re.search(r"fleet view: (http://\S+)", line)
    try:
        assert match, f"handeye plant printed no URL: {line}{process.stdout.read() if process.poll() is not None else ''}"
        plants = {cell: plant_rule(broker.cell_plant(cell, tmp_path / f"outbox-{cell}"), "plant", {})
                  for cell in ("cell01", "cell02")}
        yield broker, config, match.group(1), plants
    finally:
        process.terminate()
        process.wait(10)
        broker.stop()


def test_a_serial_change_and_a_drift_are_flagged_on_the_page_within_2_s(fleet_view, tmp_path):
    broker, config, url, plants = fleet_view
    with pytest.raises(urllib.error.HTTPError, match="403"):
        urllib.request.urlopen(url.split("?")[0], timeout=5)
    for cell, plant in plants.items():
        publish_event("calibrate", plant, lambda p=plant: _event(p, "calibrate"))
        publish_event("verify", plant, lambda p=plant: _event(p, "verify", size={"translation_mm": 0.02}))
    browser = _browser()
    try:
        browser.get(url)
        cells = {f"{PREFIX}/cell01", f"{PREFIX}/cell02"}
        seen = _until(browser, lambda s: set(s) == cells, 15)
        assert seen == {cell: "none" for cell in cells}, seen
        publish_event("verify", plants["cell01"], lambda: _event(plants["cell01"], "verify", camera_serial="XB3-2002"))
        published = time.monotonic()
        seen = _until(browser, lambda s: "camera serial changed" in s[f"{PREFIX}/cell01"], FLAG_WITHIN_S)
        flagged_s = time.monotonic() - published
        assert "camera serial changed: XB3-1001 -> XB3-2002" in seen[f"{PREFIX}/cell01"], seen
        assert seen[f"{PREFIX}/cell02"] == "none"
        publish_event("verify", plants["cell02"], lambda: _event(
            plants["cell02"], "verify", verdict="drift", diagnosis={"cause": "camera", "translation_mm": 0.8},
            size={"translation_mm": 0.8}))
        published = time.monotonic()
        seen = _until(browser, lambda s: "drift" in s[f"{PREFIX}/cell02"], FLAG_WITHIN_S)
        drift_s = time.monotonic() - published
        assert "drift: 0.800 mm (camera)" in seen[f"{PREFIX}/cell02"], seen
        print(f"flagged after {flagged_s:.2f} s (serial) and {drift_s:.2f} s (drift)")
        spark = browser.execute_script("return document.querySelectorAll('svg.spark').length")
        assert spark == 2
    finally:
        browser.quit()
    out = subprocess.run([sys.executable, "-m", "handeye.station", "plant", "--config", str(config), "--json",
                          "--settle-s", "0.5"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    table = {row["cell"]: row for row in json.loads(out.stdout)["cells"]}
    assert table[f"{PREFIX}/cell02"]["drift_trend_mm"] == [0.02, 0.8]
    assert table[f"{PREFIX}/cell01"]["predicted_error_mm"] == 0.21 and table[f"{PREFIX}/cell01"]["events"] == 3
