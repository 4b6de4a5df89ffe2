"""Runs a criterion benchmark and appends each benchmark's median to
bench/results/criterion.csv (bench/record.py; HYDRORATTLE_BENCH_MACHINE names the
machine, as for every record).

    python3 bench/criterion.py cargo bench --bench kernel -- '^step/'

Criterion writes `target/criterion/<id>/new/{benchmark,estimates}.json` for every
benchmark it ran; those written during this run are the rows (case: the benchmark's
id; quantity: median; value in the unit the time reads best in).
"""

import json
import os
import pathlib
import shlex
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import record  # noqa: E402


def readable(ns):
    for unit, scale in (("s", 1e9), ("ms", 1e6), ("us", 1e3)):
        if ns >= scale:
            return f"{ns / scale:.3g} {unit}"
    return f"{ns:.3g} ns"


def main(argv):
    if not argv:
        sys.exit(__doc__)
    command = shlex.join(argv)
    rows = record.Recorder("criterion", command)
    start = time.time()
    subprocess.run(argv, cwd=record.ROOT, check=True)
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", record.ROOT / "target"))
    for estimates in sorted((target / "criterion").glob("**/new/estimates.json")):
        if estimates.stat().st_mtime < start:
            continue
        bench = json.loads((estimates.parent / "benchmark.json").read_text())
        median = json.loads(estimates.read_text())["median"]["point_estimate"]
        rows.row("criterion median", bench["full_id"], "median", readable(median))
    rows.finish()


if __name__ == "__main__":
    main(sys.argv[1:])
