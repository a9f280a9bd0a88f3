"""Station config values that say what to do and do what they say (issue 25, finding 7): an empty host
names what it holds; ``output`` is the folder new sessions go to."""

from pathlib import Path

import pytest
import yaml

from handeye.station.cli import main
from handeye.station.config.station import ConfigError, config_from_dict

REAL = {"controller": {"protocol": "socket"}, "camera": {"backend": "xb3"}}


@pytest.mark.parametrize("host", ["", "   "])
def test_an_empty_host_says_what_it_must_hold(host):
    with pytest.raises(ConfigError) as refused:
        config_from_dict({**REAL, "controller": {"protocol": "socket", "host": host}})
    assert str(refused.value) == "controller.host must not be empty: the controller's IP address or host name"


def test_other_empty_texts_say_empty_and_a_number_still_says_text():
    with pytest.raises(ConfigError, match=r"^tool.name must not be empty$"):
        config_from_dict({**REAL, "tool": {"name": ""}})
    with pytest.raises(ConfigError, match=r"^controller.host must be a text: the controller's IP address or host name; got 7$"):
        config_from_dict({**REAL, "controller": {"protocol": "socket", "host": 7}})


# ------------------------------------------------------------------------------------------ output
MOCK = {"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}


def test_output_is_the_folder_of_new_sessions():
    config = config_from_dict({**MOCK, "output": "sessions"})
    assert config.session_folder("cal_1") == Path("sessions/cal_1")
    assert config.session_folder("sessions/cal_1") == Path("sessions/cal_1")  # as the capture printed it
    assert config.session_folder("/data/cal_1") == Path("/data/cal_1")
    assert config_from_dict(MOCK).session_folder("cal_1") == Path("cal_1")  # no output: as given


def test_capture_puts_a_relative_session_in_the_configs_output_folder(tmp_path, monkeypatch, capsys):
    station = tmp_path / "station.yaml"
    station.write_text(yaml.safe_dump({**MOCK, "output": "sessions", "mock": {"time_scale": 0.001}}))
    monkeypatch.chdir(tmp_path)
    assert main(["capture", "--config", str(station), "--session", "cal_1", "--postures", "5", "--plan-only"]) == 0
    assert (tmp_path / "sessions" / "cal_1" / "preview.png").is_file() and not (tmp_path / "cal_1").exists()
    out = capsys.readouterr().out
    assert "sessions/cal_1/preview.png" in out
