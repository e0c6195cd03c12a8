#!/usr/bin/env python3
"""The table of bench/convergence/quarter-seeds.sh's output folder: per problem
and seed, the old binary's 1000 iterations against the new binary's quarter
budget (process seconds, iterations, objective x white noise, and from `fsot
eval --quick` under TAA pRelMSE's geometric mean ratio to white over the scenes,
with pRelMSE's own eye, sigma 2.1, and with the eye of the display judged on),
then the means over seeds and the new mean's distance from the old one. Where
bench/convergence/rescore.sh has scored the masks (objective-by-score.tsv), the
objective is that one binary's, on its fixed slices, for old and new alike.

    bench/convergence/quarter-table.py OUT_DIR
"""
import csv
import json
import math
import statistics
import sys
from pathlib import Path

out = Path(sys.argv[1])
runs = list(csv.DictReader(open(out / "runs.tsv"), delimiter="\t"))
rescored = out / "objective-by-score.tsv"
scores = {r["mask"]: r for r in csv.DictReader(open(rescored), delimiter="\t")} if rescored.exists() else {}


def geo(records, name, key):
    white = {r["scene"]: r[key] for r in records if r["method"] == "white" and r["taa"]}
    rs = [r for r in records if r["method"] == name and r["taa"]]
    return math.exp(sum(math.log(r[key] / white[r["scene"]]) for r in rs) / len(rs))


scorer = f"objective ({next(iter(scores.values()))['scored_by']}'s score)" if scores else "objective"
cols = ["process s", "iterations", scorer, "pRelMSE (sigma 2.1)", "pRelMSE (display's eye)", "JOD"]
print("| problem | made by | seed | " + " | ".join(cols) + " |")
print("| --- | --- | --- |" + " ---: |" * len(cols))
for problem in dict.fromkeys(r["problem"] for r in runs):
    records = json.load(open(out / f"eval-{problem}.json"))
    table = {}
    for run in (r for r in runs if r["problem"] == problem):
        name = f"{run['binary']}-s{run['seed']}"
        jods = [r["jod"] for r in records if r["method"] == name and r["taa"]]
        objective = scores[f"{problem}-{name}"]["objective_x_white"] if scores else run["objective_x_white"]
        row = [float(run["process_s"]), int(run["iterations"]), float(objective),
               geo(records, name, "prelmse"), geo(records, name, "prelmse_display"), sum(jods) / len(jods)]
        table.setdefault(run["binary"], []).append(row)
        what = "1000 iterations" if run["binary"] == "old" else "a quarter's budget"
        print(f"| {problem} | {what} | {run['seed']} | {row[0]:.2f} | {row[1]} | {row[2]:.3f} "
              f"| {row[3]:.4f} | {row[4]:.4f} | {row[5]:.3f} |")
    means = {b: [statistics.mean(c) for c in zip(*rows)] for b, rows in table.items()}
    for b in ["old", "new"]:
        m = means[b]
        what = "1000 iterations" if b == "old" else "a quarter's budget"
        print(f"| {problem} | {what} | mean | {m[0]:.2f} | {m[1]:.0f} | {m[2]:.4f} | {m[3]:.4f} | {m[4]:.4f} | {m[5]:.3f} |")
    o, n = means["old"], means["new"]
    print(f"| {problem} | new against old | | {n[0] / o[0]:.3f} x | | {100 * (n[2] / o[2] - 1):+.1f}% "
          f"| {100 * (n[3] / o[3] - 1):+.1f}% | {100 * (n[4] / o[4] - 1):+.1f}% | {n[5] - o[5]:+.3f} |")
