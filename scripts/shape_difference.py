#!/usr/bin/env python3
"""Largest distance between two runs' centrelines (docs/performance.md).

Usage: scripts/shape_difference.py REFERENCE_DIR RUN_DIR [RUN_DIR ...]

Reads each run directory's ``shape.csv`` (``softrod run``'s output: the
centreline points ``x, y, z`` of every rod at every output time) and prints,
per run, the largest distance in metres from the reference's point of the
same rod, arc length and time, over all output times and at the last one.
Both runs must have the same rods, pieces and output times; rows are matched
by ``(t, rod, s)`` to 1e-12. Standard library only.
"""

import csv
import math
import sys


def points(run_dir):
    """{(t, rod, s): (x, y, z)} of a run directory's shape.csv."""
    out = {}
    with open(f"{run_dir}/shape.csv", newline="") as f:
        for row in csv.DictReader(f):
            key = (round(float(row["t"]), 12), row["rod"], round(float(row["s"]), 12))
            out[key] = (float(row["x"]), float(row["y"]), float(row["z"]))
    return out


def main(argv):
    if len(argv) < 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    ref = points(argv[1])
    for run_dir in argv[2:]:
        run = points(run_dir)
        missing = set(ref) ^ set(run)
        if missing:
            print(f"{run_dir}: {len(missing)} points not in both runs", file=sys.stderr)
            return 1
        t_last = max(k[0] for k in ref)
        worst = last = 0.0
        for key, p in ref.items():
            d = math.dist(p, run[key])
            worst = max(worst, d)
            if key[0] == t_last:
                last = max(last, d)
        print(f"{run_dir}: largest distance {worst:.3g} m over all outputs, {last:.3g} m at t = {t_last:g} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
