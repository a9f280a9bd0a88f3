"""Import every real data set of ../shared/datasets, solve it with `mcb` and `mc`, compare with the
published references (other tools' estimates, not truth) and print the X-free consistency figures.

    python benchmarks/import_real_sets/run.py [DATASETS_FOLDER]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.calibration import diagnostics
from handeye.calibration.solve import calibrate_session
from handeye.geometry.transforms import rotation_error_deg
from handeye.station.importers import read_any

SETS = {
    "moveit-calibration": "moveit-calibration/pose_samples.json",
    "visp-eye-in-hand": "visp-eye-in-hand",
    "camodocal-ar-tag": "camodocal-ar-tag/TransformPairsInput.yml",
    "ethz-robot-arm": "ethz-robot-arm",
    "visp-apps-eye-in-hand": "visp-apps-eye-in-hand",
}
#: Published camera poses (datasets/README.md): MoveIt camera in base, ViSP eMc. mm.
REFERENCES = {
    "moveit-calibration": (np.array([659.0, -249.0, 830.0]), Rotation.from_euler("XYZ", [0.230, -2.540, 1.950])),
    "visp-eye-in-hand": (np.array([53.46, -9.52, -45.10]), Rotation.from_rotvec([-0.02347, -0.07939, 1.57459])),
}


def main(root: Path) -> None:
    print("| set | format | set-up (how) | postures | method | t (mm) | d_org mm | to reference |")
    print("|---|---|---|---|---|---|---|---|")
    notes = []
    for name, rel in SETS.items():
        path = root / rel
        if not path.exists():
            print(f"| {name} | missing | | | | | | |")
            continue
        session = read_any(path)
        record = session.extra["import"]
        how = "data" if record["setup_how"].startswith("detected") else record["setup_how"]
        for method in ("mcb", "mc"):
            result = calibrate_session(session, method)
            t = result.x[:3, 3]
            ref = ""
            if name in REFERENCES:
                t_ref, r_ref = REFERENCES[name]
                ref = (f"{np.linalg.norm(t - t_ref):.2f} mm, "
                       f"{rotation_error_deg(result.x[:3, :3], r_ref.as_matrix()):.3f} deg")
            print(f"| {name} | {record['format']} | {session.setup} ({how}) | {len(session.postures)} | {method} | "
                  f"({t[0]:.2f}, {t[1]:.2f}, {t[2]:.2f}) | {result.metrics['d_org_mm']:.2f} | {ref} |")
        a = np.array([p.tool0_in_base for p in session.postures])
        b = np.array([p.target_in_camera for p in session.postures])
        gaps = diagnostics.posture_angle_gaps(diagnostics.relative_angle_gaps(a, b))
        residuals = diagnostics.setup_rotation_residuals(a, b)
        fit = diagnostics.hand_eye_fit(a, b, session.setup)
        worst = np.argsort(gaps)[::-1][:2]
        notes.append(
            f"- {name}: median angle gap per posture: typical {np.median(gaps):.2f} deg, largest "
            + ", ".join(f"{gaps[k]:.2f} (posture {k})" for k in worst)
            + f"; set-up rotation residual eye_in_hand {residuals['eye_in_hand']:.2f} / eye_to_hand "
              f"{residuals['eye_to_hand']:.2f} deg; translation fit {fit['translation_mm']:.1f} mm for motions of "
              f"{fit['motion_mm']:.1f} mm; pitch ratio {diagnostics.screw_pitch_scale(a, b):.3f}; findings: "
            + ("; ".join(f.kind + str(list(f.postures)) for f in diagnostics.diagnose_session(session)) or "none"))
    print()
    print("\n".join(notes))


if __name__ == "__main__":
    default = Path(__file__).resolve().parents[3] / "shared" / "datasets"
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else default)
