"""The kinematic identification on the rendered mock station (``handeye demo``'s capture), per seed.

Per seed: the mock arm gets explicit deviations (``mock.arm`` of the station config: joint zeros
uniform in +-0.05 deg on J2-J5, +-0.3 mm on d1, a1, a2, a3, d4, d6), the embedded station captures
30 planned postures (rendered XB3 images through the real detection and triangulation, the real
controller link), the default estimator and the identification run on the session; 100 held-out
postures looking at the board (``views.sample_eye_in_hand_postures``) give the error of a point
750 mm along the camera axis in the board's frame against the mock's truth, with and without the
correction, next to the prediction. One JSON line per seed (``--out``); the summary as
``bench_kinematics.py`` prints it.

Usage:
    python benchmarks/kinematics/bench_mock_station.py [--seeds 20] [--out benchmarks/kinematics/results_mock.jsonl]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from bench_kinematics import run_seeds, standoff_figures, summary  # noqa: E402

from handeye.calibration.arm_identification import identify_arm  # noqa: E402
from handeye.calibration.arm_parameters import parameter_names  # noqa: E402
from handeye.geometry.board import board_corners  # noqa: E402
from handeye.robot.kinematics import load_robot  # noqa: E402
from handeye.calibration.solve import problem_from_session  # noqa: E402
from handeye.calibration.session import read_session  # noqa: E402
from handeye.calibration.standoff import measured_standoff, predicted_standoff  # noqa: E402
from handeye.robot.views import sample_eye_in_hand_postures  # noqa: E402
from handeye.mocks.arm_truth import ArmDeviations, true_arm  # noqa: E402
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT  # noqa: E402
from handeye.station.config.station import ArmSettings, default_config  # noqa: E402
from handeye.station.capture.loop import capture  # noqa: E402
from handeye.station.runtime import open_station  # noqa: E402

NAMES = parameter_names()
LINKS = ("d1", "a1", "a2", "a3", "d4", "d6")


def one_seed(seed: int, work: Path) -> dict:
    rng = np.random.default_rng(seed)
    zeros = [0.0] + [float(v) for v in rng.uniform(-0.05, 0.05, 4)] + [0.0]
    links = {name: float(rng.uniform(-0.3, 0.3)) for name in LINKS}
    config = default_config()
    config = replace(config, mock=replace(config.mock, arm=ArmSettings(tuple(zeros), links)))
    config = replace(config, mock=replace(config.mock, seed=seed))
    folder = work / f"seed{seed}"
    with open_station(config, mock=True) as link:  # the demo's capture (the demo's write-back needs a PASS)
        capture(config, folder, link)
    session = read_session(folder)
    started = time.perf_counter()
    ident = identify_arm(problem_from_session(session))
    seconds = time.perf_counter() - started
    nominal = load_robot("IRB1400")
    truth = true_arm(nominal, ArmDeviations(tuple(zeros), links))
    board = config.target
    held = sample_eye_in_hand_postures(nominal, DEFAULT_MOUNT, DEFAULT_BOARD, board_corners(board.corners,
                                       board.square_mm), 100, np.random.default_rng(10_000 + seed))
    predicted = predicted_standoff(ident, held)
    with_, without = measured_standoff(truth, DEFAULT_MOUNT, DEFAULT_BOARD, nominal, ident, held)
    out = {}
    for axis in (2, 3, 4, 5):
        j = NAMES.index(f"zero{axis}")
        out[f"J{axis}"] = {"true": zeros[axis - 1], "value": float(ident.values[j]), "sigma": float(ident.sigma[j]),
                           "status": ident.status[j], "z": float((ident.values[j] - zeros[axis - 1]) / ident.sigma[j])}
    row = {"seed": seed, "zeros": out, "seconds": seconds}
    row.update(standoff_figures(predicted, with_, without))
    return row

def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--first", type=int, default=1)
    p.add_argument("--out", default="benchmarks/kinematics/results_mock.jsonl")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        rows = run_seeds(range(args.first, args.first + args.seeds), lambda seed: one_seed(seed, Path(tmp)), args.out,
                         lambda row: f"reduction {row['reduction']:.3f} ({row['measured_with_mm']:.3f} vs "
                         f"{row['measured_without_mm']:.3f} mm), predicted/measured with {row['predicted_over_measured_with']:.2f} "
                         f"without {row['predicted_over_measured_without']:.2f}, z {[round(v['z'], 2) for v in row['zeros'].values()]}")
    print(json.dumps(summary(rows), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
