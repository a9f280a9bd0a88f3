"""Station config values that say what to do (issue 25, finding 7): an empty host names what it holds."""

import pytest

from handeye.station.config import ConfigError, config_from_dict

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
