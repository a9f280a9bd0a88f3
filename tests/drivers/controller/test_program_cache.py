"""The mock renders a station's RAPID modules once per process: starts after the first reuse them."""

from __future__ import annotations

from handeye.mocks.controller import generated_program, start_mock_controller


def test_the_same_station_reuses_its_rendered_modules():
    first = generated_program("socket", ack_timeout_s=None, write_key="cache-key-0123")
    again = generated_program("socket", ack_timeout_s=None, write_key="cache-key-0123")
    assert again.modules is first.modules
    assert any("cache-key-0123" in m.text for m in first.modules)


def test_a_different_setting_renders_its_own_modules():
    one = generated_program("serial", ack_timeout_s=None, write_key="cache-key-0123")
    other = generated_program("serial", ack_timeout_s=None, write_key="other-key-4567")
    late = generated_program("serial", ack_timeout_s=2.5)
    assert other.modules != one.modules and late.modules not in (one.modules, other.modules)
    assert any("other-key-4567" in m.text for m in other.modules)
    assert not any("cache-key-0123" in m.text for m in other.modules + late.modules)


def test_a_server_started_twice_runs_the_cached_program(no_leaked_threads):
    with start_mock_controller("socket", time_scale=0.002, ack_timeout_s=None) as a, \
            start_mock_controller("socket", time_scale=0.002, ack_timeout_s=None) as b:
        assert a.program.loaded.modules is b.program.loaded.modules
