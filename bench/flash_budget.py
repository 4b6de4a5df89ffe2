"""Fails where a firmware binary's flash grew more than a tolerance over its last record.

    python3 bench/flash_budget.py [--tolerance 0.01] RECORDS.csv ROWS.tsv

ROWS.tsv holds the measured table as firmware/ci.sh writes it (tab-separated
MEASUREMENT, CASE, QUANTITY, VALUE); RECORDS.csv the records (bench/results/m4.csv).
Each case's `flash` is compared with the last record of the same measurement and case:
more than the tolerance above it (1 % by default) fails, naming the binary, both sizes
and the record's commit. A case with no record passes. A deliberate growth (a new
capability the firmware runs) is recorded by running with HYDRORATTLE_FLASH_GROWTH set
to its reason: the check then reports and passes, and the new rows become the budget.
"""

import csv
import os
import sys


def number(text):
    """A recorded size: digits, possibly grouped by commas or spaces."""
    digits = text.replace(",", "").replace(" ", "")
    return int(digits) if digits.isdigit() else None


def last_records(path):
    """(measurement, case) -> (flash, commit) of the last `flash` row of each."""
    last = {}
    with open(path, newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            size = number(row["value"])
            if row["quantity"] == "flash" and size is not None:
                last[(row["measurement"], row["case"])] = (size, row["commit"])
    return last


def main(argv):
    tolerance = 0.01
    if argv[1:2] == ["--tolerance"]:
        tolerance = float(argv[2])
        argv = argv[:1] + argv[3:]
    if len(argv) != 3:
        sys.exit(__doc__)
    last = last_records(argv[1])
    over = []
    with open(argv[2], encoding="utf-8") as f:
        for line in f:
            cells = line.rstrip("\n").split("\t")
            if len(cells) != 4 or cells[2] != "flash":
                continue
            measurement, case, _, value = cells
            size = number(value)
            record = last.get((measurement, case))
            if size is None or record is None:
                continue
            budget, commit = record
            change = (size - budget) / budget
            print(f"{case:32} flash {size:7} against {budget:7} ({commit}): {change:+.2%}")
            if change > tolerance:
                over.append(f"{case}: {size} bytes, {change:+.2%} over {budget} ({commit})")
    if not over:
        return
    reason = os.environ.get("HYDRORATTLE_FLASH_GROWTH")
    text = "\n  ".join(over)
    if reason:
        print(f"flash over budget, accepted ({reason}):\n  {text}")
        return
    sys.exit(f"FLASH OVER BUDGET (more than {tolerance:.0%} over the last record in "
             f"{argv[1]}):\n  {text}\nFind what added the bytes (arm-none-eabi-nm --size-sort -S "
             "against the last record's build); a deliberate growth is recorded with "
             "HYDRORATTLE_FLASH_GROWTH=reason.")


if __name__ == "__main__":
    main(sys.argv)
