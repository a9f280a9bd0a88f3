"""The station file's ``plant:`` section: checked key by key, recorded without its secret, and absent by
default, in which case no command imports an MQTT client."""

from __future__ import annotations

import subprocess
import sys

import pytest

from handeye.station.config.station import ConfigError, config_from_dict, default_config
from handeye.station.plant.settings import broker_password

REAL = {"controller": {"protocol": "socket"}, "camera": {"backend": "xb3"}}
PLANT = {"mqtt": {"host": "broker.plant", "topic_prefix": "acme/berlin/body/line2/cell07", "username": "cell07",
                  "password": "s3cret-pw", "tls": {"ca": "/etc/ca.pem"}}}


def test_a_plant_section_is_read_with_its_defaults():
    plant = config_from_dict({**REAL, "plant": PLANT}).plant
    assert plant.cell == "cell07" and plant.station == "cell07" and plant.mqtt.effective_port == 8883
    assert plant.mqtt.tls.enabled and plant.publish_timeout_s == 2.0
    assert config_from_dict({**REAL, "plant": {"mqtt": {"topic_prefix": "a/b/c/d/e"}}}).plant.mqtt.effective_port == 1883


def test_without_a_plant_section_there_is_none_and_the_record_has_none():
    assert default_config().plant is None and config_from_dict(REAL).plant is None
    assert "plant" not in config_from_dict(REAL).to_dict()


@pytest.mark.parametrize("change, message", [
    ({"mqtt": {"host": "b"}}, "plant.mqtt.topic_prefix is missing"),
    ({"mqtt": {"topic_prefix": "acme/berlin/cell07"}}, "enterprise/site/area/line/cell"),
    ({"mqtt": {"topic_prefix": "acme/+/body/line2/cell07"}}, "no \\+ or #"),
    ({"mqtt": {"topic_prefix": "a/b/c/d/e", "port": 70000}}, "plant.mqtt.port must be between 1 and 65535"),
    ({"mqtt": {"topic_prefix": "a/b/c/d/e", "tls": {"cert": "c.pem"}}}, "both cert and key"),
    ({"mqtt": {"topic_prefix": "a/b/c/d/e", "password": "x", "password_env": "PW"}}, "not both"),
    ({"mqtt": {"topic_prefix": "a/b/c/d/e", "password_env": "not a name"}}, "environment variable"),
    ({"mqtt": {"topic_prefix": "a/b/c/d/e", "hots": "b"}}, "unknown key plant.mqtt.hots"),
    ({"mqtt": {"topic_prefix": "a/b/c/d/e"}, "standoff_mm": -1}, "plant.standoff_mm must be between"),
])
def test_a_bad_plant_section_is_refused_naming_the_key(change, message):
    with pytest.raises(ConfigError, match=message):
        config_from_dict({**REAL, "plant": change})


def test_the_password_is_never_recorded_and_the_environment_one_is_read(monkeypatch):
    config = config_from_dict({**REAL, "plant": PLANT})
    assert "s3cret-pw" not in repr(config) and "s3cret-pw" not in str(config.to_dict())
    assert config.to_dict()["plant"]["mqtt"]["password"] == "<set>"
    assert broker_password(config.plant.mqtt) == "s3cret-pw"
    env = config_from_dict({**REAL, "plant": {"mqtt": {"topic_prefix": "a/b/c/d/e", "password_env": "HE_PW"}}})
    monkeypatch.setenv("HE_PW", "from-env")
    assert broker_password(env.plant.mqtt) == "from-env"


def test_no_command_imports_an_mqtt_client_without_a_plant_section(tmp_path):
    """calibrate, writeback and verify on the mock station: paho is never imported (the hooks return at once)."""
    code = f"""
import sys, contextlib, io
from handeye.station.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    assert main(["demo", "--session", r"{tmp_path / 'demo'}", "--postures", "14", "--no-report"]) == 0
    session = r"{tmp_path / 'demo' / 'session'}"
    assert main(["calibrate", session, "--quiet", "--json", r"{tmp_path / 'r.json'}"]) == 0
    assert main(["writeback", session, "--mock"]) == 0
print(sorted(m for m in sys.modules if m.startswith("paho") or m.startswith("handeye.station.plant.")))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "['handeye.station.plant.hooks', 'handeye.station.plant.settings']"
