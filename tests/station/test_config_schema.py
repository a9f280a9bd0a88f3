"""The station config's schema: every key declared once (default, rule, unit, doc) next to its
dataclass; the example file documents each one; the axis count comes from the robot model."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import pytest
import yaml

from handeye.station.config import station as station_config
from handeye.station.config.station import EXAMPLE_FILE, ConfigError, StationConfig, config_from_dict, default_config, describe_keys
from handeye.station.config.schema import Number, check_section, declared_fields, rule_of, schema_keys, setting

REAL = {"controller": {"protocol": "socket"}, "camera": {"backend": "xb3"}}


def _documented_keys(data: dict, prefix: str = "") -> set[str]:
    """Key paths of a station YAML: top-level keys, and down in the sections (``mock.faults.*``, ``mock.arm.*``)."""
    keys = set()
    for name, value in data.items():
        if isinstance(value, dict) and name != "quality" and (not prefix or name in ("faults", "arm")):
            keys |= _documented_keys(value, f"{prefix}{name}.")
        else:
            keys.add(prefix + name)
    return keys


def test_the_example_file_documents_every_key_of_the_schema():
    declared = {path for path, _ in schema_keys(StationConfig)}
    documented = _documented_keys(yaml.safe_load(EXAMPLE_FILE.read_text()))
    assert declared - documented == set(), "keys the example does not show"
    assert documented - declared == set(), "keys the example shows that the schema does not know"


def test_every_field_is_a_declared_key_with_a_rule_and_a_doc():
    sections = [StationConfig] + [f.metadata["keys"] for f in fields(StationConfig) if f.metadata.get("keys")]
    for cls in sections:
        for f in fields(cls):
            if cls is StationConfig and f.name == "source":
                continue  # where the config was read from: not a key
            if f.name == getattr(cls, "EXTRA_FIELD", None):
                continue  # holds the keys declared elsewhere (the controller back ends'), checked below
            assert rule_of(f) is not None, f"{cls.__name__}.{f.name} has no rule"
            assert f.metadata["doc"], f"{cls.__name__}.{f.name} has no doc"
        for f in declared_fields(cls):
            assert rule_of(f) is not None and f.metadata["doc"], f"{cls.__name__}.{f.name}"
    assert len(describe_keys()) == len(list(schema_keys(StationConfig)))
    assert "controller.idle_timeout_s: RAPID and PC: a link silent this long is dropped [s]" in describe_keys()


def test_a_field_without_a_rule_is_no_key_of_the_file():
    @dataclass(frozen=True)
    class Section:
        known: float = setting(1.0, Number(0, 2), "a declared key", "mm")
        internal: float = 3.0  # no setting(): not readable from a file, no silent catch-all range

    assert check_section(Section, {"known": 2}, "s", {}) == {"known": 2.0}
    with pytest.raises(ConfigError, match="unknown key s.internal; known keys of s: known"):
        check_section(Section, {"internal": 1}, "s", {})
    with pytest.raises(ConfigError, match="s.known must be between 0 and 2; got 5"):
        check_section(Section, {"known": 5}, "s", {})


def test_a_config_reads_back_from_its_own_record():
    config = config_from_dict({**REAL, "plan": {"postures": 12, "distance_mm": [600, 900]},
                               "capture": {"save_images": True}, "tool": {"mass_kg": 2.5}})
    record = config.to_dict()
    again = config_from_dict(record, config.source)
    assert replace(again, camera=config.camera) == config
    assert again.camera.nominal_mount_transform() == pytest.approx(config.camera.nominal_mount_transform(), abs=1e-6)


def test_the_defaults_are_the_built_in_station():
    config = config_from_dict({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}})
    assert replace(config, source=default_config().source) == default_config()


def test_secrets_are_masked_from_their_declaration():
    assert [f.name for f in declared_fields(station_config.ControllerSettings) if f.metadata["secret"]] == \
        ["write_key", "password"]  # password: declared by its back end (LinkSetting(secret=True))
    keyed = config_from_dict({**REAL, "controller": {"protocol": "socket", "write_key": "a-secret-key",
                                                     "password": "a-rws-password"}})
    assert keyed.to_dict()["controller"]["write_key"] == "<set>" and "a-secret-key" not in repr(keyed)
    assert keyed.to_dict()["controller"]["password"] == "<set>" and "a-rws-password" not in repr(keyed)
    assert keyed.controller.password == "a-rws-password"


@pytest.fixture
def five_axis_robot(tmp_path):
    """A robot YAML with five axes (the IRB 1400 without its last wrist axis)."""
    robot = yaml.safe_load((EXAMPLE_FILE.parents[2] / "robot" / "robots" / "irb1400.yaml").read_text())
    robot.update(name="FiveAxis", aliases=[], dh=robot["dh"][:5], joint_limits_deg=robot["joint_limits_deg"][:5],
                 max_speed_deg_s=robot["max_speed_deg_s"][:5], bodies=robot["bodies"][:2],  # no flange: no link 6
                 link_bodies=[b for b in robot["link_bodies"] if b["link"] <= 5])  # nor link 6's fitted capsule
    # nor a self-collision pair of link 6 (a pair naming no body of the file is refused at load)
    robot["self_collision"]["pairs"] = [pair for pair in robot["self_collision"]["pairs"] if "link 6" not in pair]
    robot.pop("home_tool0_in_base", None)
    path = tmp_path / "five_axis.yaml"
    path.write_text(yaml.safe_dump(robot))
    return str(path)


def test_joint_rows_have_as_many_values_as_the_robot_has_axes(five_axis_robot):
    config = config_from_dict({**REAL, "robot": five_axis_robot, "plan": {"start_joints_deg": [0, 0, 0, 0, 30]},
                               "postures": [[0, 0, 0, 0, 30], [10, 0, 0, 0, 30]]})
    assert config.plan.start_joints_deg == (0, 0, 0, 0, 30) and len(config.postures[1]) == 5
    with pytest.raises(ConfigError, match="plan.start_joints_deg must be a list of 5 numbers"):
        config_from_dict({**REAL, "robot": five_axis_robot, "plan": {"start_joints_deg": [0, 0, 0, 0, 30, 0]}})
    with pytest.raises(ConfigError, match=r"postures must be a list of joint-angle rows \[a1, \.\.\., a5\]"):
        config_from_dict({**REAL, "robot": five_axis_robot, "postures": []})
    with pytest.raises(ConfigError, match=r"postures must be a list of joint-angle rows \[a1, \.\.\., a6\]"):
        config_from_dict({**REAL, "postures": []})
