"""Where the full calibration itself lands, against the two truths the quick update is compared with.

The quick update's misses against the physical mount (``bench_verify.py --cases update``) lie along
the flange axis and are the size of the true arm's last-link length error. This script shows that a
full 30-posture calibration carries the same offset: for each seed it captures and solves the
baseline on the embedded mock station (as ``bench_verify.py`` does) and prints the baseline's error
against the physical mount (``DEFAULT_MOUNT`` on the true flange) and against the mount behind the
arm's last-link deviation (``last_link_mount``: what the controller's nominal last link needs in its
tooldata), each in the result's reported sigmas, beside the true arm's ``d6`` error.

Usage:
    python benchmarks/verify/bench_last_link.py --seeds 106,111,112,130,100,101
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_verify import baseline, last_link_mount  # noqa: E402

from handeye.calibration.kinematics import load_robot  # noqa: E402
from handeye.mocks.station import DEFAULT_MOUNT, perturbed_robot  # noqa: E402
from handeye.station.config import default_config  # noqa: E402


def one_seed(seed: int) -> str:
    config = default_config().as_mock()
    config = replace(config, mock=replace(config.mock, seed=seed), plan=replace(config.plan, seed=seed))
    nominal = load_robot(config.robot)
    true = perturbed_robot(nominal, config.mock.kinematic_error_mm, config.mock.kinematic_error_deg, seed)
    d6_error = float(true.dh[-1][0] - nominal.dh[-1][0])
    with tempfile.TemporaryDirectory(prefix="bench-last-link-") as tmp:
        base, _ = baseline(config, Path(tmp) / "base")
    result = base.assessment.result
    sigma = np.asarray(result.uncertainty["translation_mm"], float)
    cells = []
    for name, truth in (("physical", DEFAULT_MOUNT), ("last link", last_link_mount(config, DEFAULT_MOUNT))):
        err = result.x[:3, 3] - truth[:3, 3]
        cells.append(f"{name}: error {np.round(err, 3)} mm, |error|/sigma {np.round(np.abs(err) / sigma, 1)}")
    return f"seed {seed}: d6 error {d6_error:+.3f} mm, sigma {np.round(sigma, 3)} mm; " + "; ".join(cells)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="106,111,112,130,100,101", help="comma-separated trial seeds")
    args = parser.parse_args(argv)
    for seed in [int(s) for s in args.seeds.split(",") if s]:
        print(one_seed(seed), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
