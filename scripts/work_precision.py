#!/usr/bin/env python3
"""Work-precision diagrams of the integrators (issue 30) from the CSV of the
`work_precision` example (integration alone: no output files, no energy
watch), one SVG per scene with two panels — tip error against wall time and
against right-hand sides — one curve per method, plus the Markdown table.

    cargo build --release -p softrod --example work_precision
    target/release/examples/work_precision --repeat 3 > out/wp.csv
    python3 scripts/work_precision.py out/wp.csv [--before out/wp_before.csv] [--images docs/images]

`--before`: a second CSV (an earlier commit) drawn dashed beside the first.
Plain Python (no plotting library): the SVG is written by hand.
"""
import csv
import math
import sys
from pathlib import Path

COLORS = {"esdirk": "#1f77b4", "esdirk5": "#ff7f0e", "radau5": "#d62728", "rosenbrock": "#2ca02c",
          "generalized-alpha": "#9467bd", "dopri5": "#8c564b"}
TITLES = {"planar": "planar release (cantilever_gravity, 8 pieces, 1 s)",
          "3d": "3-D release (32 pieces, all strains, 0.3 s)",
          "steel": "steel_wire (5 pieces, 0.5 s)"}


def load(path):
    with open(path) as f:
        return [r for r in csv.DictReader(f) if r.get("status") == "ok"]


def panel(rows_sets, xkey, x0, y0, w, h, xlabel):
    """One log-log panel: curves per (method, dashed)."""
    pts = [(float(r[xkey]), float(r["error_m"])) for rows, _ in rows_sets for r in rows]
    pts = [p for p in pts if p[0] > 0 and p[1] > 0]
    if not pts:
        return ""
    lx = [math.log10(p[0]) for p in pts]
    ly = [math.log10(p[1]) for p in pts]
    xa, xb = math.floor(min(lx)), math.ceil(max(lx))
    ya, yb = math.floor(min(ly)), math.ceil(max(ly))
    sx = lambda v: x0 + (math.log10(v) - xa) / max(xb - xa, 1) * w
    sy = lambda v: y0 + h - (math.log10(v) - ya) / max(yb - ya, 1) * h
    out = [f'<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="none" stroke="#888"/>']
    for e in range(xa, xb + 1):
        x = x0 + (e - xa) / max(xb - xa, 1) * w
        out.append(f'<line x1="{x:.1f}" y1="{y0}" x2="{x:.1f}" y2="{y0 + h}" stroke="#eee"/>')
        out.append(f'<text x="{x:.1f}" y="{y0 + h + 14}" font-size="10" text-anchor="middle">1e{e}</text>')
    for e in range(ya, yb + 1):
        y = y0 + h - (e - ya) / max(yb - ya, 1) * h
        out.append(f'<line x1="{x0}" y1="{y:.1f}" x2="{x0 + w}" y2="{y:.1f}" stroke="#eee"/>')
        out.append(f'<text x="{x0 - 4}" y="{y + 3:.1f}" font-size="10" text-anchor="end">1e{e}</text>')
    out.append(f'<text x="{x0 + w / 2}" y="{y0 + h + 30}" font-size="11" text-anchor="middle">{xlabel}</text>')
    out.append(f'<text x="{x0 - 38}" y="{y0 + h / 2}" font-size="11" text-anchor="middle" '
               f'transform="rotate(-90 {x0 - 38} {y0 + h / 2})">max tip error [m]</text>')
    for rows, dashed in rows_sets:
        for method in dict.fromkeys(r["method"] for r in rows):
            c = [(float(r[xkey]), float(r["error_m"])) for r in rows if r["method"] == method]
            c = [p for p in c if p[0] > 0 and p[1] > 0]
            if not c:
                continue
            col = COLORS.get(method, "#000")
            d = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in c)
            dash = ' stroke-dasharray="4 3"' if dashed else ""
            out.append(f'<polyline points="{d}" fill="none" stroke="{col}" stroke-width="1.5"{dash}/>')
            for x, y in c:
                out.append(f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="2.5" fill="{col}"/>')
    return "\n".join(out)


def svg(scene, rows_sets):
    W, H = 900, 400
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif">',
             f'<rect width="{W}" height="{H}" fill="white"/>',
             f'<text x="{W / 2}" y="18" font-size="13" text-anchor="middle">{TITLES.get(scene, scene)}: '
             'work-precision (integration alone)</text>',
             panel(rows_sets, "wall_s", 70, 40, 330, 290, "wall time [s]"),
             panel(rows_sets, "rhs", 520, 40, 330, 290, "right-hand sides")]
    methods = list(dict.fromkeys(r["method"] for rows, _ in rows_sets for r in rows))
    for i, m in enumerate(methods):
        x = 70 + i * 170
        parts.append(f'<line x1="{x}" y1="{H - 22}" x2="{x + 20}" y2="{H - 22}" stroke="{COLORS.get(m, "#000")}" stroke-width="2"/>')
        parts.append(f'<text x="{x + 25}" y="{H - 18}" font-size="11">{m}</text>')
    if len(rows_sets) > 1:
        parts.append(f'<text x="{W - 10}" y="{H - 18}" font-size="11" text-anchor="end">dashed: before</text>')
    parts.append("</svg>")
    return "\n".join(parts)


def main():
    args = [a for a in sys.argv[1:]]
    opt = lambda k: args[args.index(k) + 1] if k in args else None
    before = opt("--before")
    images = Path(opt("--images") or "docs/images")
    csv_path = [a for i, a in enumerate(args) if not a.startswith("--") and (i == 0 or not args[i - 1].startswith("--"))][0]
    rows = load(csv_path)
    old = load(before) if before else []
    print("| scene | method | setting | wall s | steps | rejected | Newton | Jacobians | factorizations | rhs | max tip error m |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['scene']} | {r['method']} | {r['setting']} | {float(r['wall_s']):.4f} | {r['steps']} | {r['rejected']} | "
              f"{r['newton']} | {r['jacobians']} | {r['factorizations']} | {r['rhs']} | {float(r['error_m']):.2e} |")
    images.mkdir(parents=True, exist_ok=True)
    for scene in dict.fromkeys(r["scene"] for r in rows):
        sets = [([r for r in rows if r["scene"] == scene], False)]
        if old:
            sets.append(([r for r in old if r["scene"] == scene], True))
        (images / f"work_precision_{scene}.svg").write_text(svg(scene, sets))


if __name__ == "__main__":
    main()
