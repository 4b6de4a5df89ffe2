"""Appends measurements to `bench/results/NAME.csv` as the script that measured them
runs: the columns of docs/BENCHMARKS.md's "Records" (date, commit, machine, load,
command, measurement, case, quantity, value). The Rust examples write the same rows
(`examples/shared/record.rs`).

Rows are appended only where HYDRORATTLE_BENCH_MACHINE names the machine (an id of the
page's "Machines" table); without it nothing is recorded, so a trial run leaves the
records alone.

From a script:

    rows = record.Recorder("helix25", "python3 bench/peer/compare.py ...")
    rows.row("measurement", "case", "quantity", "12.5 us")
    rows.finish()

From a shell script, one row, or many as tab-separated lines of MEASUREMENT, CASE,
QUANTITY and VALUE on the standard input (`-`); `--exact` leaves the load empty, for
counts no load changes (instructions under QEMU's -icount, bytes):

    python3 bench/record.py NAME COMMAND MEASUREMENT CASE QUANTITY VALUE
    python3 bench/record.py --exact NAME COMMAND - <rows.tsv
"""

import csv
import datetime
import io
import os
import pathlib
import subprocess
import sys

MACHINE = "HYDRORATTLE_BENCH_MACHINE"
HEADER = ["date", "commit", "machine", "load", "command", "measurement", "case",
          "quantity", "value"]
ROOT = pathlib.Path(__file__).resolve().parent.parent


def load():
    """The one-minute load average (Linux), or None."""
    try:
        return float(pathlib.Path("/proc/loadavg").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None


class Recorder:
    """The rows of one run, appended to `bench/results/{name}.csv` by `finish`."""

    def __init__(self, name, command, exact=False):
        self.file = ROOT / "bench" / "results" / f"{name}.csv"
        self.command = command
        self.machine = os.environ.get(MACHINE) or None
        self.load_at_start = None if exact else load()
        self.rows = []

    def row(self, measurement, case, quantity, value):
        """One cell of a measured table: the table, its row, its column, the value."""
        self.rows.append([measurement, case, quantity, value])

    def finish(self):
        """Appends the rows (load: the one-minute average at the start and the end)."""
        if self.machine is None:
            print(f"not recorded: set {MACHINE} to this machine's id in docs/BENCHMARKS.md "
                  f"to append these rows to {self.file}", file=sys.stderr)
            return
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short=7", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        a, b = self.load_at_start, load()
        if a is None:
            span = ""
        elif b is None or f"{a:.1f}" == f"{b:.1f}":
            span = f"{a:.1f}"
        else:
            span = f"{min(a, b):.1f}-{max(a, b):.1f}"
        date = datetime.datetime.now(datetime.timezone.utc).date().isoformat()
        text = io.StringIO()
        out = csv.writer(text, lineterminator="\n")
        if not self.file.exists():
            out.writerow(HEADER)
        for r in self.rows:
            out.writerow([date, commit, self.machine, span, self.command, *r])
        # One write of whole lines: a row is never left half written.
        with open(self.file, "a", encoding="utf-8") as f:
            f.write(text.getvalue())
        print(f"recorded {len(self.rows)} rows in {self.file}", file=sys.stderr)


def main(argv):
    exact = argv[1:2] == ["--exact"]
    args = argv[2:] if exact else argv[1:]
    if len(args) == 3 and args[2] == "-":
        cells = [line.rstrip("\n").split("\t") for line in sys.stdin if line.strip()]
    elif len(args) == 6:
        cells = [args[2:6]]
    else:
        sys.exit(__doc__)
    if any(len(c) != 4 for c in cells):
        sys.exit("each row needs 4 tab-separated fields: MEASUREMENT CASE QUANTITY VALUE")
    rows = Recorder(args[0], args[1], exact)
    for c in cells:
        rows.row(*c)
    rows.finish()


if __name__ == "__main__":
    main(sys.argv)
