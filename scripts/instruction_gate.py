#!/usr/bin/env python3
"""The instruction-count gate of the dynamics' hot paths (docs/performance.md,
"Instruction-count gate").

    python3 scripts/instruction_gate.py            # check against the baseline
    python3 scripts/instruction_gate.py --update   # after an intended change

Builds the dynamics' timing example (release profile, baseline SSE2 copies:
valgrind cannot decode some AVX2 encodings) and counts, under callgrind, the
instructions of one call of each hot path at N = 10 pieces on the bench's
seeded state: (count at N_ITER = k − count at N_ITER = 0) / k, exact and
independent of the machine's load. Fails (exit 1) when a path needs more
than `--tolerance` (default 1 %) above `scripts/instruction_baseline.json`,
naming it; reports paths that got cheaper (then `--update` records them).
Counts depend on the compiler: with another rustc than the baseline's the
gate reports and passes (record a new baseline with that compiler).
Needs valgrind (Debian's package).
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BASELINE = os.path.join(ROOT, "scripts", "instruction_baseline.json")

# name: (environment of fd_timing, iterations). N = 10 pieces, all six
# strains unless BASIS says otherwise, the criterion bench's random state.
CASES = {
    "forward dynamics, six strains": ({"WHAT": "fd"}, 200),
    "forward dynamics, planar": ({"WHAT": "fd", "BASIS": "planar"}, 400),
    "forward dynamics, revolute joint (tree)": ({"WHAT": "fd", "JOINT": "revolute"}, 200),
    "inverse dynamics": ({"WHAT": "id"}, 400),
    "mass matrix": ({"WHAT": "mm"}, 200),
    "factor + solve of M + aK + bD": ({"WHAT": "shifted"}, 200),
    "analytic pair dtau/dq, dtau/dqdot": ({"WHAT": "did"}, 20),
}


def rustc_version() -> str:
    return subprocess.run(["rustc", "--version"], capture_output=True, text=True,
                          check=True).stdout.strip()


def build() -> str:
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "-p", "softrod-dynamics",
         "--no-default-features", "--example", "fd_timing"],
        cwd=ROOT, check=True,
    )
    meta = subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps"],
                          cwd=ROOT, capture_output=True, text=True, check=True)
    target = json.loads(meta.stdout)["target_directory"]
    return os.path.join(target, "release", "examples", "fd_timing")


def instructions(binary: str, env: dict[str, str], iters: int, scratch: str) -> int:
    out = os.path.join(scratch, f"cg.{iters}.out")
    full = dict(os.environ, STATE="bench", N_PIECES="10", N_ITER=str(iters), **env)
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", binary],
                   env=full, check=True, capture_output=True)
    with open(out) as f:
        for line in f:
            m = re.match(r"^(?:summary|totals):\s+(\d+)", line)
            if m:
                return int(m.group(1))
    raise RuntimeError(f"no instruction total in {out}")


def measure(binary: str) -> dict[str, float]:
    counts = {}
    with tempfile.TemporaryDirectory() as scratch:
        for name, (env, iters) in CASES.items():
            base = instructions(binary, env, 0, scratch)
            total = instructions(binary, env, iters, scratch)
            counts[name] = (total - base) / iters
    return counts


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--update", action="store_true", help="record the counts as the baseline")
    ap.add_argument("--tolerance", type=float, default=0.01,
                    help="allowed relative increase (default 0.01)")
    args = ap.parse_args()
    if shutil.which("valgrind") is None:
        print("instruction_gate: valgrind is not installed (apt-get install valgrind)",
              file=sys.stderr)
        return 2
    rustc = rustc_version()
    counts = measure(build())
    if args.update:
        with open(BASELINE, "w") as f:
            json.dump({"rustc": rustc, "instructions per call": counts}, f, indent=2)
            f.write("\n")
        for name, c in counts.items():
            print(f"{name}: {c:,.0f}")
        print(f"baseline written: {os.path.relpath(BASELINE, ROOT)}")
        return 0
    with open(BASELINE) as f:
        baseline = json.load(f)
    worse = []
    print("| path (N = 10) | baseline | now | change |\n|---|---|---|---|")
    for name, c in counts.items():
        b = baseline["instructions per call"].get(name)
        if b is None:
            print(f"| {name} | — | {c:,.0f} | new (run --update) |")
            continue
        change = c / b - 1.0
        print(f"| {name} | {b:,.0f} | {c:,.0f} | {100 * change:+.2f} % |")
        if change > args.tolerance:
            worse.append(f"{name}: {c:,.0f} instructions per call, {100 * change:+.2f} % "
                         f"over the baseline {b:,.0f}")
    if baseline["rustc"] != rustc:
        print(f"instruction_gate: the baseline was counted with {baseline['rustc']}, this is "
              f"{rustc}: counts are not comparable; not checked (run --update with this compiler)")
        return 0
    if worse:
        print("instruction_gate: FAILED — more instructions than the baseline allows "
              f"(+{100 * args.tolerance:g} %):", file=sys.stderr)
        for w in worse:
            print(f"  {w}", file=sys.stderr)
        print("If the increase is intended (more physics), say why in the commit and run "
              "scripts/instruction_gate.py --update.", file=sys.stderr)
        return 1
    print(f"instruction_gate: every path within +{100 * args.tolerance:g} % of the baseline")
    return 0


if __name__ == "__main__":
    sys.exit(main())
