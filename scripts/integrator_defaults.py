#!/usr/bin/env python3
"""Measures the default integrator setting against the alternatives.

    cargo build --release -p softrod-cli
    python3 scripts/integrator_defaults.py [target/release/softrod]
    python3 scripts/integrator_defaults.py --rtol-only   # the error-tracks-rtol table

For each example (and a 3-D, 32-piece, all-strain release), runs `softrod run`
with esdirk and rosenbrock at several tolerances and prints the wall time,
steps and the largest tip distance over the run (samples every output_every)
from a Radau IIA run at rtol 1e-10. Prints a Markdown table
(docs/defaults.md holds its last output).
"""
import csv
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ARGS = [a for a in sys.argv[1:] if not a.startswith("--")]
BIN = ARGS[0] if ARGS else str(REPO / "target/release/softrod")
RELEASE_3D = """[world]
gravity = [0.0, 0.0, -9.81]

[[rod]]
name = "arm"
length = 0.5
pieces = 32
strains = "all"
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }
"""
CASES = [
    ("cantilever_gravity (planar, 8 pieces)", (REPO / "examples/cantilever_gravity.toml").read_text(), 1.0, 0.01),
    ("3-D release, 32 pieces, all strains", RELEASE_3D, 0.3, 0.01),
    ("steel_wire", (REPO / "examples/steel_wire.toml").read_text(), 0.5, 2e-3),
    ("tapered_tentacle", (REPO / "examples/tapered_tentacle.toml").read_text(), 2.0, 0.01),
    ("three_section_arm", (REPO / "examples/three_section_arm.toml").read_text(), 1.5, 0.01),
]
SETTINGS = [("esdirk", 1e-3, 1e-6), ("esdirk", 1e-4, 1e-7), ("esdirk", 1e-6, 1e-9),
            ("rosenbrock", 1e-3, 1e-6), ("rosenbrock", 1e-4, 1e-7), ("rosenbrock", 1e-6, 1e-9)]


def run(tmp, text, run_table, tag):
    cut = text.find("[run]")
    scene = Path(tmp) / f"{tag}.toml"
    scene.write_text((text if cut < 0 else text[:cut]) + "\n[run]\n" + run_table + "\n")
    out = Path(tmp) / tag
    start = time.perf_counter()
    subprocess.run([BIN, "run", str(scene), "--out", str(out), "--quiet"], check=False)
    wall = time.perf_counter() - start
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "trajectory.csv") as f:
        rows = list(csv.reader(f))[1:]
    return wall, summary, [tuple(float(v) for v in r[1:4]) for r in rows]


def distance(a, b):
    if len(a) != len(b):
        return float("nan")
    return max(max(abs(x - y) for x, y in zip(p, r)) for p, r in zip(a, b))


def rtol_only():
    """The error-tracks-rtol table: 1 s of the planar and the 3-D release with
    only `rtol` in `[run]` (the default integrator, and the atol the scene
    then gets), against Radau IIA at rtol 1e-10."""
    print("| scene | rtol | wall s | steps | rejected | max tip error m | error / rtol | status |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for k, (name, text, _, every) in enumerate(CASES[:2]):
            common = f"duration = 1.0\noutput_every = {every}\n"
            _, s, ref = run(tmp, text, common + 'integrator = "radau5"\nrtol = 1e-10\natol = 1e-12', f"ref{k}")
            assert s["status"] == "ok", s
            for j, rtol in enumerate([1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]):
                wall, s, tip = run(tmp, text, common + f"rtol = {rtol}", f"r{k}_{j}")
                err = distance(tip, ref)
                print(f"| {name} | {rtol:.0e} | {wall:.2f} | {s['steps']} | {s['rejected_steps']} | "
                      f"{err:.2e} | {err / rtol:.2f} | {s['status']} |", flush=True)


def main():
    if "--rtol-only" in sys.argv:
        rtol_only()
        return
    print("| scene | integrator | rtol | atol | wall s | steps | rejected | max tip error m | status |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for k, (name, text, duration, every) in enumerate(CASES):
            common = f"duration = {duration}\noutput_every = {every}\n"
            _, s, ref = run(tmp, text, common + 'integrator = "radau5"\nrtol = 1e-10\natol = 1e-12', f"ref{k}")
            assert s["status"] == "ok", s
            for j, (integ, rtol, atol) in enumerate(SETTINGS):
                wall, s, tip = run(tmp, text, common + f'integrator = "{integ}"\nrtol = {rtol}\natol = {atol}', f"c{k}_{j}")
                print(f"| {name} | {integ} | {rtol:.0e} | {atol:.0e} | {wall:.2f} | {s['steps']} | "
                      f"{s['rejected_steps']} | {distance(tip, ref):.2e} | {s['status']} |", flush=True)


if __name__ == "__main__":
    main()
