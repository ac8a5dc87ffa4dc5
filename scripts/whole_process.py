#!/usr/bin/env python3
"""The whole process of `softrod run` on the planar release (issue 30): a
fresh process from the scene to every written output file, timed from
outside, binaries interleaved within each round, fastest of `--rounds`; the
tip error is the largest distance over the output rows from a Radau IIA
rtol 1e-10, atol 1e-12 run of the same scene (the first binary's).

    python3 scripts/whole_process.py --bin before=OLD/softrod --bin after=target/release/softrod \\
        --settings esdirk:1e-3:1e-6,esdirk:1e-4:1e-7,esdirk5:1e-3:1e-6 --rounds 30

Plain Python (no NumPy). Each run writes into a fresh directory (removed
before, untimed). Prints a Markdown table.
"""
import argparse
import csv
import json
import math
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def scene(base: str, integrator: str, rtol: str, atol: str, path: Path) -> Path:
    t = re.sub(r"^integrator = .*$", f'integrator = "{integrator}"', base, flags=re.M)
    t = re.sub(r"^rtol = .*$", f"rtol = {float(rtol)!r}", t, flags=re.M)
    t = re.sub(r"^atol = .*$", f"atol = {float(atol)!r}", t, flags=re.M)
    path.write_text(t)
    return path


def tips(out: Path) -> list[list[float]]:
    rows = list(csv.reader(open(out / "trajectory.csv")))
    i = rows[0].index("tip_x")
    return [[float(x) for x in r[i:i + 3]] for r in rows[1:]]


def run(binary: str, sc: Path, out: Path) -> float:
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    subprocess.run([binary, "run", str(sc), "--out", str(out), "--quiet"], check=True)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", action="append", required=True, help="NAME=PATH")
    ap.add_argument("--settings", default="esdirk:1e-3:1e-6,esdirk:1e-4:1e-7,esdirk5:1e-3:1e-6")
    ap.add_argument("--scene", default=str(ROOT / "examples" / "cantilever_gravity.toml"))
    ap.add_argument("--rounds", type=int, default=10)
    a = ap.parse_args()
    bins = dict(b.split("=", 1) for b in a.bin)
    base = Path(a.scene).read_text()
    work = Path(tempfile.mkdtemp())
    first = next(iter(bins.values()))
    run(first, scene(base, "radau5", "1e-10", "1e-12", work / "ref.toml"), work / "ref")
    ref = tips(work / "ref")
    settings = [s.split(":") for s in a.settings.split(",")]
    best: dict = {}
    facts: dict = {}
    for k in range(a.rounds):
        for s in settings:
            sc = scene(base, *s, work / "scene.toml")
            for name, b in bins.items():
                out = work / f"out_{name}"
                dt = run(b, sc, out)
                key = (tuple(s), name)
                best[key] = min(best.get(key, math.inf), dt)
                if k == 0:
                    e = max(math.dist(p, q) for p, q in zip(tips(out), ref))
                    w = json.load(open(out / "summary.json"))
                    facts[key] = (e, w["steps"], w["rhs_evaluations"])
    print("| setting | binary | tip error [m] | steps | rhs | whole process [s] |")
    print("|---|---|---|---|---|---|")
    for s in settings:
        for name in bins:
            e, st, rhs = facts[(tuple(s), name)]
            print(f"| {s[0]} rtol {s[1]} atol {s[2]} | {name} | {e:.1e} | {st} | {rhs} "
                  f"| {best[(tuple(s), name)]:.3f} |")
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
