"""The Modbus register map and its 32-bit float conversion (checked against pymodbus' own)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from pymodbus.client import ModbusTcpClient

from handeye.drivers.controller import ConfigError, ToolData
from handeye.drivers.controller.modbus_map import (
    DEFAULT_MAP,
    floats_to_registers,
    load_register_map,
    registers_to_floats,
)
from handeye.mocks.controller import start_mock_controller

F32 = st.floats(width=32, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None)
@given(st.lists(F32, min_size=1, max_size=6), st.sampled_from(["big", "little"]))
def test_float_registers_match_pymodbus(values, word_order):
    regs = floats_to_registers(values, word_order)
    expected = ModbusTcpClient.convert_to_registers(values, ModbusTcpClient.DATATYPE.FLOAT32, word_order=word_order)
    assert regs == expected
    assert registers_to_floats(regs, word_order) == values


def test_word_order_is_explicit():
    assert floats_to_registers([1.0], "big") == [0x3F80, 0x0000]
    assert floats_to_registers([1.0], "little") == [0x0000, 0x3F80]


def test_default_map_is_consistent():
    m = load_register_map()
    assert m.word_order == "big" and m["joints"].size == 12
    assert m.span("tool0_position", "tool0_quaternion") == (22, 14)


def _write_map(tmp_path, change):
    data = yaml.safe_load(DEFAULT_MAP.read_text())
    change(data)
    path = tmp_path / "map.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(word_order="middle"), "word_order"),
    (lambda d: d["registers"].pop("heartbeat"), "heartbeat is missing"),
    (lambda d: d["registers"]["posture"].update(address=11), "overlap"),
    (lambda d: d["registers"]["joints"].update(count=5), "6 x float32"),
    (lambda d: d["registers"]["request"].update(access="robot"), "written by the pc"),
    (lambda d: d.update(format="other"), "format"),
])
def test_bad_maps_are_refused(tmp_path, change, message):
    with pytest.raises(ConfigError, match=message) as info:
        load_register_map(_write_map(tmp_path, change))
    assert info.value.backend == "modbus" and str(info.value).startswith("modbus: register map ")


def test_little_endian_gateway_end_to_end(tmp_path, connect_to):
    path = _write_map(tmp_path, lambda d: d.update(word_order="little"))
    with start_mock_controller("modbus", time_scale=0.002, register_map=path, write_key="little-endian-key") as server:
        with connect_to(server) as c:
            c.goto_posture(5)
            assert np.allclose(c.read_joints(), server.robot.postures[4], atol=1e-4)
            c.acknowledge(5)
            tool = ToolData((10.0, 20.0, 30.0), (0.0, 1.0, 0.0, 0.0), 2.0)
            assert c.set_tool(tool).close_to(tool)
        # a client with the wrong word order reads nonsense and says so
        with pytest.raises(Exception, match="word_order|not valid|not unit|protocol_version"):
            with connect_to(server, register_map=None) as c:
                c.read_tool0_pose()
