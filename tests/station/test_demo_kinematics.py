"""``handeye demo --kinematics`` on the embedded mock station: identified offsets next to the hidden ones."""

import numpy as np

from handeye.station.demo import DemoOptions, run_demo
from handeye.station.kinematics_step import demo_lines


def test_demo_identifies_the_hidden_joint_zeros(tmp_path):
    result = run_demo(DemoOptions(str(tmp_path / "demo"), 30, seed=7, report=False, kinematics=True))
    kin = result["kinematics"]
    hidden = kin["hidden"]["joint_zero_deg"]
    for axis in (2, 3, 4, 5):
        value, sigma = kin["joint_zero_deg"][axis - 1], kin["sigma_deg"][axis - 1]
        assert abs(value - hidden[axis - 1]) < 3 * sigma
    assert kin["joint_zero_deg"][0] is None and kin["joint_zero_deg"][5] is None
    text = "\n".join(demo_lines(kin))
    assert "J3 zero" in text and "hidden" in text
    assert kin["standoff_error"]["with_correction_rms_mm"] < kin["standoff_error"]["without_correction_rms_mm"]
    assert np.isfinite(result["errors"]["translation_error_mm"])
