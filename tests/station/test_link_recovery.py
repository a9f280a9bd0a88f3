"""A guided capture resumes on the embedded mock station after the PC lost its link half-way.

The PC "loses power" between two runs: its connection to the controller is neither used nor
closed again (half-open, as after a power loss or a pulled cable), and the PC comes back with a
new connection. The mock program keeps running the whole time; nothing is restarted.
"""

from dataclasses import replace

import pytest

from handeye.calibration.session import read_session
from handeye.station.capture.loop import capture
from handeye.station.config.station import default_config
from handeye.station.runtime import open_station

IDLE = 0.5


def _config(postures: int, protocol: str):
    config = default_config()
    return replace(config, plan=replace(config.plan, postures=postures), mock=replace(config.mock, protocol=protocol),
                   controller=replace(config.controller, idle_timeout_s=IDLE))


def _lose_power(controller):
    """The PC vanishes: its connection stays open on the controller's side, never used, never closed.

    Returns the abandoned connection (closed by the test at the end, for the leak checks).
    """
    for name in ("_transport", "_client"):  # line back ends / Modbus back end (private: the test plays the crash)
        held = getattr(controller, name, None)
        if held is not None:
            setattr(controller, name, None)
            return held
    raise AssertionError("the controller was not connected")


@pytest.mark.parametrize("protocol", ["socket", "serial", "modbus"])
def test_a_half_open_connection_does_not_stop_the_capture_from_resuming(tmp_path, protocol, no_leaked_threads):
    config = _config(4, protocol)
    with open_station(config, mock=True) as link:
        server = link.mock.server
        first = capture(config, tmp_path / "s", link, stop_after=2)
        assert first.captured == [0, 1]
        moves = server.robot.moves
        ghost = _lose_power(link.controller)
        try:
            assert not link.controller.is_connected
            second = capture(config, tmp_path / "s", link)
        finally:
            ghost.close()
        assert link.mock.server is server and server.running  # the same mock program, never restarted
        assert server.robot.moves > moves
    assert second.already == [0, 1] and second.captured == [2, 3] and not second.skipped
    assert sorted(p.index for p in read_session(tmp_path / "s").postures) == [0, 1, 2, 3]
    if protocol == "socket":
        assert server.takeovers + server.idle_closes >= 1
    if protocol == "serial":
        assert server.takeovers >= 1
