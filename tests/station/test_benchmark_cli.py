import csv

from handeye.station.cli import main


def test_benchmark_smoke(tmp_path, capsys):
    out = tmp_path / "b"
    code = main(["benchmark", "-o", str(out), "--sweep", "sigma_cam", "--sigma-cam", "0,4", "--trials", "1",
                 "--methods", "mcb,robust,park,opencv_tsai", "--no-plots"])
    assert code == 0
    rows = list(csv.DictReader(open(out / "results.csv")))
    methods = {r["method"] for r in rows}
    assert {"truth", "mcb", "robust", "park"} <= methods
    noise_free = [r for r in rows if r["value"] == "0.0" and r["method"] in ("mcb", "robust", "park")]
    assert all(float(r["rotation_error_deg"]) < 1e-6 and float(r["translation_error_mm"]) < 1e-4 for r in noise_free)
    noisy = [r for r in rows if r["value"] == "4.0" and r["method"] == "mcb"]
    assert 0 < float(noisy[0]["rotation_error_deg"]) < 1.0
    summary = (out / "summary.md").read_text()
    assert "| mcb |" in summary and "rotation error" in summary


def test_benchmark_rejects_bad_values(tmp_path, capsys):
    assert main(["benchmark", "-o", str(tmp_path / "b"), "--postures", "2.5", "--sweep", "postures"]) == 2  # a usage error
    assert "whole numbers" in capsys.readouterr().err


def test_calibrate_accepts_every_classic_name(tmp_path, capsys):
    from handeye.calibration.classic import CLASSIC_METHODS

    path = tmp_path / "s"
    assert main(["simulate", "-o", str(path), "--postures", "6"]) == 0
    for name in CLASSIC_METHODS:
        assert main(["calibrate", str(path), "--method", name, "--quiet", "--json", str(tmp_path / f"{name}.json")]) == 0
    assert main(["calibrate", str(path), "--method", "nonsense"]) == 1
    assert "unknown method 'nonsense'" in capsys.readouterr().err
