"""Layouts of hand-eye logs as other tools write them: right / refused / wrong over generated logs,
and the time of the whole `handeye import` command on a 100-posture log.

    python benchmarks/import_layouts/bench.py [--logs 1000] [--postures 100]

Each log is a noisy synthetic station (``tests/layout_logs.py``: 8-30 postures, 0.3 mm and 0.05 deg
of board-pose noise, eye-in-hand or eye-to-hand) written in one of the layouts in turn (tagged rows,
P + three C rows, matrices over rows, matrices in sections with count lines, one file per side,
camera-calibration rows per image, rows with extra columns), with random tag words, separators,
rotation conventions, units, pose directions and decoys. *right*: the session holds the true poses
and set-up; *refused*: a one-line refusal naming a flag; *wrong*: anything else (a session that is
not the truth, or a refusal without a flag). Then a 100-posture tagged log is imported with the
`handeye import` command in a fresh process (start-up included), median of 3.
"""

from __future__ import annotations

import argparse
import collections
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

from layout_logs import LAYOUTS, station, write_log, same_as_truth  # noqa: E402

from handeye.base.errors import SessionError  # noqa: E402
from handeye.station.importers import read_any  # noqa: E402


def count(logs: int, folder: Path) -> dict:
    tally = collections.defaultdict(collections.Counter)
    examples = collections.defaultdict(list)
    for seed in range(logs):
        layout = LAYOUTS[seed % len(LAYOUTS)]
        st = station(seed, n=8 + seed % 23)
        written = write_log(folder / f"{seed}", st, layout, seed)
        try:
            session = read_any(written.paths if len(written.paths) > 1 else written.paths[0])
            verdict = "right" if same_as_truth(session, st) else "wrong"
            message = "" if verdict == "right" else str(session.extra["import"]["notes"][:1])
        except SessionError as exc:
            verdict = "refused" if "pass --" in str(exc) else "wrong"
            message = str(exc)
        tally[layout][verdict] += 1
        if verdict != "right" and len(examples[layout]) < 3:
            examples[layout].append(f"seed {seed} ({written.words}): {verdict}: {message[:200]}")
    return tally, examples


def command_time(postures: int, folder: Path, repeats: int = 3) -> float:
    st = station(12345, n=postures, setup="eye_in_hand")
    written = write_log(folder / "big", st, "tag_rows", 7)
    times = []
    for k in range(repeats):
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "handeye.station", "import", *map(str, written.paths), "-o",
                               str(folder / f"out{k}")], capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        if done.returncode != 0:
            raise SystemExit(f"handeye import failed: {done.stderr.strip()}")
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=int, default=1000)
    parser.add_argument("--postures", type=int, default=100)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        tally, examples = count(args.logs, Path(tmp))
        elapsed = time.perf_counter() - start
        total = collections.Counter()
        print("| layout | right | refused | wrong |\n|---|---|---|---|")
        for layout in LAYOUTS:
            t = tally[layout]
            total.update(t)
            print(f"| {layout} | {t['right']} | {t['refused']} | {t['wrong']} |")
        print(f"| all {sum(total.values())} | {total['right']} | {total['refused']} | {total['wrong']} |")
        print(f"({elapsed:.0f} s for the {args.logs} imports in one process)")
        for layout, lines in examples.items():
            for line in lines:
                print(f"  {layout}: {line}")
        print(f"handeye import of a {args.postures}-posture tagged log (whole command, median of 3): "
              f"{command_time(args.postures, Path(tmp)):.2f} s")


if __name__ == "__main__":
    main()
