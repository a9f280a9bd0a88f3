"""Vision benchmark: corner accuracy on rendered XB3 frames, runtime, mock-session cost, real images.

Run from the repository root (after ``pip install -e .``)::

    python benchmarks/vision/bench_vision.py --postures-per-bin 6 --json benchmarks/vision/results.json

Prints a Markdown report (the tables of README.md) and optionally writes the figures as JSON.

1. Accuracy: board poses 0.7-1.2 m away (stratified in 100 mm bins, tilt 0-40 deg, any roll, both
   ways up) are rendered by the mock XB3 (``mocks.camera``) and measured through the product path
   (``drivers.camera.triangulate.triangulate_files``) from files, as ``handeye triangulate`` does:
   grey PNG pairs (a mono head) and raw colour XB3 frames (GBRG mosaics packed in the 3-sensor
   RGB8 layout). Error = triangulated corner minus the true corner (3D, mm). The canonical order is
   checked in every view (left, centre, right): each detected corner must land on the projection of
   the true corner with the same index.
2. Runtime: ``runtime_s`` of every triangulation above (decode + detect + triangulate).
3. Mock session: ``open_camera("mock")``, 30 grabs at 30 camera poses (3 sensors rendered, packed,
   decoded) plus triangulation of each; wall-clock seconds.
4. Real images: the 8 ViSP photographs (``../shared/datasets/visp-apps-eye-in-hand``) through the
   same detector and ``cv2.solvePnP``, then ``calibrate_session(session, "mcb")``.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from handeye.geometry.board import BoardGeometry, board_corners
from handeye.calibration.session import Posture, Session
from handeye.calibration.solve import calibrate_session
from handeye.geometry.transforms import pose_from_transform
from handeye.drivers.camera import open_camera
from handeye.drivers.camera.checkerboard import board_pose_from_corners, detect_board, observe_board
from handeye.drivers.camera.decode import decode_xb3_frame
from handeye.drivers.camera.stereo import StereoModel, nominal_xb3_model, save_stereo_model
from handeye.drivers.camera.triangulate import triangulate_files
from handeye.mocks.camera import StereoRenderer
from handeye.mocks.world import PrintedBoard, sample_board_views
from handeye.station.opencv_reference import solve_opencv

REPO = Path(__file__).resolve().parents[2]
VISP = REPO.parent / "shared" / "datasets" / "visp-apps-eye-in-hand"
BINS = [(700, 800), (800, 900), (900, 1000), (1000, 1100), (1100, 1200)]


def rms(errors) -> float:
    e = np.asarray(errors).reshape(-1, 3)
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def order_ok(corners_px, projected, tol_px=0.5) -> bool:
    return bool(np.max(np.linalg.norm(corners_px - projected, axis=1)) < tol_px)


def accuracy(model: StereoModel, board: PrintedBoard, per_bin: int, seed: int, workdir: Path, label: str) -> dict:
    grid = board_corners(board.corners, board.square_mm)
    renderer = StereoRenderer(model, board, seed=seed)
    stereo_file = save_stereo_model(workdir / f"{label}_stereo.yaml", model)
    rows, runtimes = [], {"png": [], "raw": []}
    order_views = {"png": 0, "raw": 0}
    total = 0
    for b, (lo, hi) in enumerate(BINS):
        poses = sample_board_views(per_bin, model, board, distance_mm=(lo, hi), seed=seed * 100 + b)
        for k, pose in enumerate(poses):
            truth = grid @ pose[:3, :3].T + pose[:3, 3]
            left, right = renderer.gray_pair(pose)
            lp, rp = workdir / f"{label}_{b}_{k}_left.png", workdir / f"{label}_{b}_{k}_right.png"
            cv2.imwrite(str(lp), left)
            cv2.imwrite(str(rp), right)
            frame = renderer.xb3_frame(pose)
            fp = workdir / f"{label}_{b}_{k}.raw"
            frame.tofile(fp)
            png = triangulate_files(left=lp, right=rp, stereo=stereo_file, board=board.geometry)
            raw = triangulate_files(xb3_raw=fp, stereo=stereo_file, board=board.geometry)
            runtimes["png"].append(png.runtime_s)
            runtimes["raw"].append(raw.runtime_s)
            # canonical order in every view: PNG pair (left, right), raw frame (left, centre, right)
            ok_png = order_ok(png.left_px, model.project(truth, "left")) and order_ok(png.right_px, model.project(truth, "right"))
            decoded = decode_xb3_frame(frame, output="gray")
            centre = detect_board(decoded.centre, board.geometry, what="centre image").corners_px
            ok_raw = (order_ok(raw.left_px, model.project(truth, "left")) and order_ok(raw.right_px, model.project(truth, "right"))
                      and order_ok(centre, model.project(truth, "centre")))
            order_views["png"] += ok_png
            order_views["raw"] += ok_raw
            total += 1
            rows.append({"bin": f"{lo}-{hi}", "distance_mm": png.quality["distance_mm"], "tilt_deg": png.quality["tilt_deg"],
                         "png_err": (png.points_mm - truth).tolist(), "raw_err": (raw.points_mm - truth).tolist(),
                         "png_rows_px": png.quality["row_disagreement_rms_px"], "png_plane_mm": png.quality["plane_rms_mm"]})
    table = []
    for lo, hi in BINS:
        sel = [r for r in rows if r["bin"] == f"{lo}-{hi}"]
        table.append({"bin_mm": f"{lo}-{hi}", "postures": len(sel),
                      "png_rms_mm": rms([r["png_err"] for r in sel]), "raw_rms_mm": rms([r["raw_err"] for r in sel]),
                      "png_max_mm": float(max(np.linalg.norm(np.array(r["png_err"]), axis=1).max() for r in sel)),
                      "raw_max_mm": float(max(np.linalg.norm(np.array(r["raw_err"]), axis=1).max() for r in sel)),
                      "tilt_deg": f"{min(r['tilt_deg'] for r in sel):.0f}-{max(r['tilt_deg'] for r in sel):.0f}"})
    return {
        "postures": total,
        "by_distance": table,
        "png_rms_mm": rms([r["png_err"] for r in rows]),
        "raw_rms_mm": rms([r["raw_err"] for r in rows]),
        "worst_posture_png_rms_mm": max(rms(r["png_err"]) for r in rows),
        "worst_posture_raw_rms_mm": max(rms(r["raw_err"]) for r in rows),
        "canonical_order_png": f"{order_views['png']}/{total}",
        "canonical_order_raw": f"{order_views['raw']}/{total}",
        "row_disagreement_png_px_median": float(np.median([r["png_rows_px"] for r in rows])),
        "runtime_s": {k: {"median": float(np.median(v)), "p95": float(np.percentile(v, 95)), "max": float(np.max(v))}
                      for k, v in runtimes.items()},
    }


def mock_session(model: StereoModel, board: PrintedBoard, n: int, seed: int) -> dict:
    poses = sample_board_views(n, model, board, seed=seed)
    target2base = np.eye(4)
    current = {"cam2base": np.eye(4)}
    grab_times, tri_times, errors = [], [], []
    grid = board_corners(board.corners, board.square_mm)
    start = time.perf_counter()
    with open_camera("mock", model=model, board=board, target2base=target2base,
                     cam2base=lambda: current["cam2base"], seed=seed, output="gray") as camera:
        for pose in poses:
            current["cam2base"] = target2base @ np.linalg.inv(pose)
            t0 = time.perf_counter()
            frame = camera.grab()
            t1 = time.perf_counter()
            obs = observe_board(frame.left, frame.right, model, board.geometry)
            t2 = time.perf_counter()
            grab_times.append(t1 - t0)
            tri_times.append(t2 - t1)
            errors.append(obs.points_mm - (grid @ pose[:3, :3].T + pose[:3, 3]))
    total = time.perf_counter() - start
    return {"postures": n, "total_s": total, "grab_median_s": float(np.median(grab_times)),
            "triangulate_median_s": float(np.median(tri_times)), "rms_mm": rms(errors)}


def distortion_case(board: PrintedBoard, per_bin: int, seed: int, workdir: Path) -> dict:
    base = nominal_xb3_model()
    k = base.K1
    model = StereoModel(base.image_size, k, [-0.12, 0.08, 0.0006, -0.0004, 0.0], k, [-0.10, 0.06, -0.0003, 0.0005, 0.0],
                        np.eye(3), base.T, name="nominal XB3 with lens distortion")
    return accuracy(model, board, per_bin, seed, workdir, "dist")


def rejections(model: StereoModel, board: PrintedBoard, workdir: Path) -> list:
    """Bad inputs through triangulate_files: the error class, its one-line message and the time to refuse."""
    from handeye.mocks.world import board_view

    renderer = StereoRenderer(model, board, seed=9)
    pose = board_view(950, 20, 30, 10, board, (120, 0))
    left, right = renderer.gray_pair(pose)
    files = {"left": left, "right": right, "blank": np.full_like(left, 110), "small": left[:480, :640]}
    half = left.copy()
    half[:, 640:] = 110
    files["half"] = half
    paths = {}
    for name, image in files.items():
        paths[name] = workdir / f"bad_{name}.png"
        cv2.imwrite(str(paths[name]), image)
    frame = renderer.xb3_frame(pose).tobytes()
    (workdir / "bad_truncated.raw").write_bytes(frame[: len(frame) // 2])
    cases = [
        ("no board", {"left": paths["blank"], "right": paths["right"]}),
        ("half a board", {"left": paths["half"], "right": paths["right"]}),
        ("wrong corner count (12x8 for 13x8)", {"left": paths["left"], "right": paths["right"], "board": "12x8"}),
        ("wrong corner count (14x9 for 13x8)", {"left": paths["left"], "right": paths["right"], "board": "14x9"}),
        ("truncated raw frame", {"xb3_raw": workdir / "bad_truncated.raw"}),
        ("mismatched image sizes", {"left": paths["small"], "right": paths["right"]}),
        ("left and right swapped", {"left": paths["right"], "right": paths["left"]}),
    ]
    out = []
    for label, kwargs in cases:
        t0 = time.perf_counter()
        try:
            triangulate_files(**kwargs)
            out.append({"case": label, "error": None, "message": "ACCEPTED", "seconds": time.perf_counter() - t0})
        except Exception as exc:  # the point: what is raised, and that it is one line
            out.append({"case": label, "error": type(exc).__name__, "message": str(exc),
                        "seconds": time.perf_counter() - t0})
    return out


def visp_case() -> dict | None:
    if not VISP.is_dir():
        return None
    k = np.array([[607.5931396484375, 0.0, 323.46282958984375], [0.0, 607.574951171875, 243.25529479980469], [0, 0, 1.0]])
    board = BoardGeometry((9, 6), 23.6)
    postures, per_image = [], []
    for i in range(1, 9):
        image = cv2.imread(str(VISP / f"franka_image-{i}.png"), cv2.IMREAD_GRAYSCALE)
        t0 = time.perf_counter()
        det = detect_board(image, board, what=f"franka_image-{i}.png")
        target2cam, rms_px = board_pose_from_corners(det.corners_px, board, k)
        per_image.append({"image": i, "corners": int(len(det.corners_px)), "reprojection_rms_px": rms_px,
                          "distance_mm": float(np.linalg.norm(target2cam[:3, 3])), "detect_pnp_s": time.perf_counter() - t0})
        v = np.array(yaml.safe_load((VISP / f"franka_pose_rPe_{i}.yaml").read_text())["data"], float).ravel()
        tool0 = np.eye(4)
        tool0[:3, :3] = Rotation.from_rotvec(v[3:]).as_matrix()
        tool0[:3, 3] = v[:3] * 1000
        postures.append(Posture(index=i - 1, tool0_in_base=tool0, target_in_camera=target2cam))
    result = calibrate_session(Session(setup="eye_in_hand", target=board, postures=postures), "mcb")
    x = result.x
    # Sensitivity of the check to the orientation rule: image 3 read turned by 180 deg.
    image = cv2.imread(str(VISP / "franka_image-3.png"), cv2.IMREAD_GRAYSCALE)
    turned_pose, _ = board_pose_from_corners(detect_board(image, board).alternatives[0], board, k)
    turned = [Posture(p.index, tool0_in_base=p.tool0_in_base, target_in_camera=turned_pose if p.index == 2 else p.target_in_camera)
              for p in postures]
    d_org_turned = calibrate_session(Session(setup="eye_in_hand", target=board, postures=turned), "mcb").metrics["d_org_mm"]
    out = {"images": per_image, "method": "mcb", "camera_pose": {"parent": "tool0", **pose_from_transform(x)},
           "theta_u_rad": Rotation.from_matrix(x[:3, :3]).as_rotvec().tolist(), "d_org_mm": result.metrics["d_org_mm"],
           "d_back_mm": result.metrics["d_back_mm"], "d_org_with_image_3_turned_mm": d_org_turned, "opencv": {}}
    hand = [p.tool0_in_base for p in postures]
    tgt = [p.target_in_camera for p in postures]
    for name in ("tsai", "park"):
        reference = solve_opencv(hand, tgt, name)
        r, t = reference[:3, :3], reference[:3, 3]
        out["opencv"][name] = {"position_mm": t.ravel().tolist(), "theta_u_rad": Rotation.from_matrix(r).as_rotvec().tolist(),
                               "delta_mm": float(np.linalg.norm(t.ravel() - x[:3, 3])),
                               "delta_deg": float(np.degrees(Rotation.from_matrix(r.T @ x[:3, :3]).magnitude()))}
    ref_t, ref_r = np.array([53.46, -9.52, -45.10]), Rotation.from_rotvec([-0.02347, -0.07939, 1.57459])
    out["visp_reference"] = {"position_mm": ref_t.tolist(), "delta_mm": float(np.linalg.norm(x[:3, 3] - ref_t)),
                             "delta_deg": float(np.degrees((ref_r.inv() * Rotation.from_matrix(x[:3, :3])).magnitude()))}
    return out


def markdown(res: dict) -> str:
    lines = []
    for key, title in (("accuracy", "nominal XB3 model (no distortion)"), ("distortion", "XB3 model with lens distortion")):
        a = res.get(key)
        if not a:
            continue
        lines += [f"### Corner accuracy, {title}: {a['postures']} postures", "",
                  "| distance (mm) | postures | tilt (deg) | PNG pair RMS (mm) | PNG max (mm) | raw XB3 RMS (mm) | raw max (mm) |",
                  "|---|---|---|---|---|---|---|"]
        for r in a["by_distance"]:
            lines.append(f"| {r['bin_mm']} | {r['postures']} | {r['tilt_deg']} | {r['png_rms_mm']:.3f} | {r['png_max_mm']:.3f} | "
                         f"{r['raw_rms_mm']:.3f} | {r['raw_max_mm']:.3f} |")
        lines += [f"| **all** | {a['postures']} | | **{a['png_rms_mm']:.3f}** | | **{a['raw_rms_mm']:.3f}** | |", "",
                  f"Worst posture RMS: PNG {a['worst_posture_png_rms_mm']:.3f} mm, raw {a['worst_posture_raw_rms_mm']:.3f} mm. "
                  f"Canonical order correct in every view: PNG {a['canonical_order_png']}, raw (left, centre, right) "
                  f"{a['canonical_order_raw']}. Median rectified row disagreement {a['row_disagreement_png_px_median']:.3f} px.", "",
                  "| runtime_s (decode + detect + triangulate) | median | p95 | max |", "|---|---|---|---|"]
        for k, v in a["runtime_s"].items():
            lines.append(f"| {'PNG pair' if k == 'png' else 'raw XB3 frame'} | {1000 * v['median']:.1f} ms | "
                         f"{1000 * v['p95']:.1f} ms | {1000 * v['max']:.1f} ms |")
        lines.append("")
    rej = res.get("rejections")
    if rej:
        lines += ["### Bad input (each refused with one line; `handeye triangulate` exits 1)", "",
                  "| input | error | message | time |", "|---|---|---|---|"]
        for r in rej:
            lines.append(f"| {r['case']} | {r['error']} | {r['message']} | {1000 * r['seconds']:.0f} ms |")
        lines.append("")
    m = res.get("mock_session")
    if m:
        lines += ["### Mock session", "",
                  f"{m['postures']} grabs (3 sensors rendered, packed, decoded) + triangulation: **{m['total_s']:.1f} s** "
                  f"(grab median {1000 * m['grab_median_s']:.0f} ms, triangulation median {1000 * m['triangulate_median_s']:.0f} ms); "
                  f"corner RMS {m['rms_mm']:.3f} mm.", ""]
    v = res.get("visp")
    if v:
        p = v["camera_pose"]
        lines += ["### Real images (ViSP, Franka eye-in-hand, 8 photographs, 9x6 corners, 23.6 mm)", "",
                  "| image | corners | PnP reprojection RMS (px) | board distance (mm) |", "|---|---|---|---|"]
        for im in v["images"]:
            lines.append(f"| {im['image']} | {im['corners']} | {im['reprojection_rms_px']:.3f} | {im['distance_mm']:.0f} |")
        pos = ", ".join(f"{c:.2f}" for c in p["position_mm"])
        q = ", ".join(f"{c:.5f}" for c in p["quaternion_wxyz"])
        tu = ", ".join(f"{c:.4f}" for c in v["theta_u_rad"])
        lines += ["", f"mcb: cam2tool0 position ({pos}) mm, quaternion (w, x, y, z) ({q}), θu ({tu}) rad; "
                  f"**d_org = {v['d_org_mm']:.2f} mm**, d_back = {v['d_back_mm']:.2f} mm. (With image 3's board read "
                  f"turned by 180 deg, d_org would be {v['d_org_with_image_3_turned_mm']:.1f} mm.)", "",
                  "| comparison | Δ position (mm) | Δ rotation (deg) |", "|---|---|---|"]
        for name, o in v["opencv"].items():
            lines.append(f"| OpenCV calibrateHandEye {name} (same board poses) | {o['delta_mm']:.2f} | {o['delta_deg']:.2f} |")
        r = v["visp_reference"]
        lines.append(f"| ViSP 2018 tutorial eMc (other session, plausibility only) | {r['delta_mm']:.1f} | {r['delta_deg']:.1f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--postures-per-bin", type=int, default=6, help="postures per 100 mm distance bin (5 bins)")
    parser.add_argument("--session-postures", type=int, default=30)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", help="write the figures here")
    args = parser.parse_args(argv)
    board = PrintedBoard()
    model = nominal_xb3_model()
    res = {"machine": {"python": sys.version.split()[0], "opencv": cv2.__version__, "numpy": np.__version__,
                       "platform": platform.platform(), "cpus": __import__("os").cpu_count()}}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        res["accuracy"] = accuracy(model, board, args.postures_per_bin, args.seed, work, "nominal")
        res["distortion"] = distortion_case(board, max(1, args.postures_per_bin // 2), args.seed + 1, work)
        res["rejections"] = rejections(model, board, work)
    res["mock_session"] = mock_session(model, board, args.session_postures, args.seed + 2)
    res["visp"] = visp_case()
    print(markdown(res))
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
