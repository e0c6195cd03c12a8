#!/usr/bin/env python3
"""The time-quality curves of bench/convergence/time-quality.sh's output folder as
an SVG: per problem, fsot's objective as a fraction of white noise's against the
process's wall time (log scale), the old binary's iteration counts and the new
binary's budgets as two lines. Where bench/convergence/rescore.sh has scored the
masks (objective-by-score.tsv), the objective is that one binary's for both.

    bench/convergence/plot.py OUT_DIR > curves.svg
"""
import csv
import math
import sys
from pathlib import Path

out_dir = Path(sys.argv[1])
runs = list(csv.DictReader(open(out_dir / "runs.tsv"), delimiter="\t"))
rescored = out_dir / "objective-by-score.tsv"
if rescored.exists():
    scores = {r["mask"]: r["objective_x_white"] for r in csv.DictReader(open(rescored), delimiter="\t")}
    for r in runs:
        r["objective_x_white"] = scores[f"{r['problem']}-{r['binary']}-{r['what']}"]
problems = list(dict.fromkeys(r["problem"] for r in runs))
W, H, PAD = 300, 220, 45
x_lo, x_hi = math.log10(0.1), math.log10(1000.0)
colours = {"old": "#d62728", "new": "#1f77b4"}
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W * len(problems)}" height="{H + 30}" font-family="sans-serif" font-size="11">']
out.append(f'<rect width="{W * len(problems)}" height="{H + 30}" fill="white"/>')
for k, problem in enumerate(problems):
    mine = [r for r in runs if r["problem"] == problem]
    ys = [float(r["objective_x_white"]) for r in mine]
    y_lo, y_hi = min(ys) - 0.01, max(ys) + 0.01
    x0 = k * W

    def px(s):
        return x0 + PAD + (math.log10(max(s, 0.1)) - x_lo) / (x_hi - x_lo) * (W - PAD - 10)

    def py(v):
        return 10 + (y_hi - v) / (y_hi - y_lo) * (H - PAD)

    out.append(f'<rect x="{x0 + PAD}" y="10" width="{W - PAD - 10}" height="{H - PAD}" fill="none" stroke="#888"/>')
    for s in (0.1, 1, 10, 100, 1000):
        out.append(f'<text x="{px(s):.1f}" y="{H - PAD + 24}" text-anchor="middle">{s:g} s</text>')
    for v in (y_lo + 0.01, (y_lo + y_hi) / 2, y_hi - 0.01):
        out.append(f'<text x="{x0 + PAD - 4}" y="{py(v) + 4:.1f}" text-anchor="end">{v:.2f}</text>')
    out.append(f'<text x="{x0 + W / 2 + 10}" y="{H + 22}" text-anchor="middle">{problem}</text>')
    for binary, colour in colours.items():
        points = sorted((float(r["process_s"]), float(r["objective_x_white"])) for r in mine if r["binary"] == binary)
        if points:
            path = " ".join(f"{px(s):.1f},{py(v):.1f}" for s, v in points)
            out.append(f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-width="2"/>')
            for s, v in points:
                out.append(f'<circle cx="{px(s):.1f}" cy="{py(v):.1f}" r="3" fill="{colour}"/>')
out.append('<text x="50" y="24" fill="#d62728">old: iteration counts from white noise</text>')
out.append('<text x="50" y="38" fill="#1f77b4">new: --budget, animated start</text>')
out.append("</svg>")
print("\n".join(out))
