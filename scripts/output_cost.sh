#!/usr/bin/env bash
# What `softrod run` spends besides the run itself, per shipped example:
# the whole process's wall time against the run's own (`wall_seconds` of
# summary.json: integration and streaming the CSV rows), the difference
# being start-up, the figures, the 3-D view and the archive (issue 27).
#
#   bash scripts/output_cost.sh [SOFTROD_BIN]     (default target/release/softrod)
#
# Prints a Markdown table; best of three runs of each example.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-target/release/softrod}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
echo "| example | process (s) | run (s) | rest (s) | rest / run |"
echo "|---|---|---|---|---|"
for scene in examples/*.toml; do
    name="$(basename "$scene" .toml)"
    python3 - "$bin" "$scene" "$out/$name" <<'PY'
import json, subprocess, sys, time
bin_, scene, out = sys.argv[1:]
best = None
for _ in range(3):
    t0 = time.perf_counter()
    subprocess.run([bin_, "run", scene, "--out", out, "--quiet"], check=True,
                   stdout=subprocess.DEVNULL)
    process = time.perf_counter() - t0
    run = json.load(open(f"{out}/summary.json")).get("wall_seconds", float("nan"))
    if best is None or process < best[0]:
        best = (process, run)
process, run = best
rest = process - run
name = scene.split("/")[-1][:-5]
print(f"| {name} | {process:.3f} | {run:.3f} | {rest:.3f} | {rest / run:.2f} |")
PY
done
