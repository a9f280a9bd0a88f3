import pytest
import yaml

from handeye.station.cli import main
from handeye.station.config.station import EXAMPLE_FILE, ConfigError, config_from_dict, default_config, load_config


def test_default_is_the_mock_station():
    config = default_config()
    assert config.camera.backend == "mock" and config.controller.host == "127.0.0.1"
    assert config.target.corners == (13, 8) and config.plan.postures == 30


def test_example_file_loads_and_documents_every_section():
    config = load_config(EXAMPLE_FILE)
    text = EXAMPLE_FILE.read_text()
    for section in ("robot", "controller", "camera", "target", "plan", "motion", "tool", "capture", "quality", "output", "mock"):
        assert f"\n{section}:" in "\n" + text, section
    assert config.source == str(EXAMPLE_FILE)


@pytest.mark.parametrize("data, message", [
    ({"camera": {"backend": "kinect"}}, "camera.backend must be one of xb3, mock"),
    ({"controller": {"port": 70000}}, "controller.port must be between 1 and 65535"),
    ({"controller": {"hots": "x"}}, "unknown key controller.hots"),
    ({"plan": {"start_joints_deg": [0, 80, 0, 0, 0, 0]}}, "plan.start_joints_deg: axis 2"),
    ({"plan": {"distance_mm": [1200, 700]}}, "plan.distance_mm must be \\[min, max\\]"),
    ({"camera": {"nominal_mount": {"position_mm": [0, 0, 0], "quaternion_wxyz": [1, 1, 0, 0]}}},
     "camera.nominal_mount.quaternion_wxyz must have norm 1"),
    ({"tool": {"mass_kg": 0}}, "tool.mass_kg must be between"),
    ({"tool": {"name": "9tool"}}, "tool.name must be a RAPID identifier"),
    ({"target": {"corners": [13]}}, "target.corners must be two whole numbers"),
    ({"quality": {"max_d_org_mm": -1}}, "quality"),
    ({"camrea": {}}, "unknown section 'camrea'"),
])
def test_bad_values_name_the_key(data, message):
    with pytest.raises(ConfigError, match=message):
        config_from_dict(data)


def test_cli_reports_a_bad_config_in_one_line(tmp_path, capsys):
    bad = tmp_path / "station.yaml"
    bad.write_text(yaml.safe_dump({"controller": {"protocol": "profinet"}}))
    assert main(["capture", "--config", str(bad), "--session", str(tmp_path / "s")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "controller.protocol must be one of socket, serial, modbus" in err[0]
    assert not (tmp_path / "s").exists()


def test_rapid_generate_reads_the_station_config(tmp_path):
    config = tmp_path / "station.yaml"
    config.write_text(EXAMPLE_FILE.read_text())
    assert main(["rapid", "generate", "--config", str(config), "-o", str(tmp_path / "out")]) == 0
    assert (tmp_path / "out" / "HeMain.mod").exists()


@pytest.mark.parametrize("protocol, extra, port", [
    ("socket", {}, 1025), ("modbus", {}, 502), ("rws", {}, 80),
    ("rws", {"tls_fingerprint": "ab" * 32}, 443), ("modbus", {"port": 5020}, 5020), ("rws", {"port": 8080}, 8080)])
def test_a_config_without_a_port_connects_to_the_links_own(protocol, extra, port):
    """controller.port left out means the link's own port (a Modbus gateway is not on the RAPID server's
    1025, an RWS controller is on 80 or 443); a named port wins."""
    from handeye.drivers.controller.backends import CONTROLLERS

    config = config_from_dict({"controller": {"protocol": protocol, "host": "10.0.0.2", **extra},
                               "camera": {"backend": "xb3"}})
    assert CONTROLLERS[protocol].link_options(config.controller)["port"] == port
    rapid = config.rapid_dict([[0.0] * 6])["controller"]
    assert rapid.get("port", 1025) == (extra.get("port", 1025))  # the RAPID socket server's own default
