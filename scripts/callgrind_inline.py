#!/usr/bin/env python3
"""Attributes a callgrind profile's instructions to source lines through
inlined frames, where `callgrind_annotate` charges nearly everything of an
inlined hot loop to `core::ops::arith` (docs/performance.md, "Per-point
kernel cost").

    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=cg.out BIN
    python3 scripts/callgrind_inline.py cg.out BIN [--file algorithms/chain.rs] [--top 40]

Each instruction's self cost goes to the innermost inlined frame whose file
path contains `--file` (default: the innermost frame in this repository),
found with `llvm-addr2line -i`. Needs valgrind and llvm-addr2line.
"""
import argparse
import collections
import json
import os
import re
import subprocess

ap = argparse.ArgumentParser()
ap.add_argument("profile")
ap.add_argument("binary")
ap.add_argument("--file", default=None, help="attribute to the innermost frame in this file")
ap.add_argument("--top", type=int, default=40)
args = ap.parse_args()

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
names, cur, addr, skip = {}, None, 0, False
costs = collections.Counter()
binary_name = os.path.basename(args.binary)
for line in open(args.profile):
    line = line.rstrip("\n")
    m = re.match(r"^(c?)ob=\((\d+)\)(?: (.*))?$", line)
    if m:
        if m.group(3):
            names[m.group(2)] = m.group(3)
        if not m.group(1):
            cur = names.get(m.group(2))
        continue
    if line.startswith("calls="):
        skip = True  # the next cost line is the call's inclusive cost
        continue
    if not line or line[0] not in "0123456789+-*":
        continue
    parts = line.split()
    a = parts[0]
    if a.startswith("0x"):
        addr = int(a, 16)
    elif a[0] in "+-":
        d = int(a[1:], 0)
        addr += d if a[0] == "+" else -d
    if skip:
        skip = False
        continue
    if cur and cur.endswith(binary_name) and len(parts) >= 3:
        costs[addr] += int(parts[2])

total = sum(costs.values())
addrs = sorted(costs)
out = subprocess.run(
    ["llvm-addr2line", "-e", args.binary, "-i", "-f", "-C", "--output-style=JSON"],
    input="\n".join(hex(a) for a in addrs) + "\n",
    capture_output=True,
    text=True,
    check=True,
).stdout.strip("\n").split("\n")
agg = collections.Counter()
for a, js in zip(addrs, out):
    frames = json.loads(js)["Symbol"]
    ours = [f for f in frames if f["FileName"].startswith(root)]
    if args.file:
        ours = [f for f in ours if args.file in f["FileName"]]
    f = ours[0] if ours else (frames[0] if frames else None)
    if f and f["FileName"]:
        name = f["FileName"]
        key = f"{os.path.relpath(name, root) if name.startswith(root) else name}:{f['Line']}"
    else:
        key = "?"
    agg[key] += costs[a]
print(f"total {total:,} instructions in {binary_name}")
for k, v in agg.most_common(args.top):
    print(f"{v:>14,} {100 * v / total:5.1f}%  {k}")
