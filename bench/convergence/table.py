#!/usr/bin/env python3
"""The time-quality table of bench/convergence/time-quality.sh's output folder:
for each problem and mask, the process time, iterations and objective
(runs.tsv), and from `fsot eval --quick` under TAA: pRelMSE's geometric mean
ratio to white noise over the scenes, the mean JOD, and in how many scenes the
mask is ahead of (+) or behind (-) the published FAST and STBN masks with the
95% intervals apart, by JOD and by pRelMSE. Where bench/convergence/rescore.sh
has scored the masks (objective-by-score.tsv), a column gives that one binary's
objective, on its fixed slices, for old and new alike.

    bench/convergence/table.py OUT_DIR
"""
import csv
import json
import math
import sys
from pathlib import Path

out = Path(sys.argv[1])
runs = list(csv.DictReader(open(out / "runs.tsv"), delimiter="\t"))
rescored = out / "objective-by-score.tsv"
scores = {r["mask"]: r for r in csv.DictReader(open(rescored), delimiter="\t")} if rescored.exists() else {}
scorer = f" | objective ({next(iter(scores.values()))['scored_by']}'s score)" if scores else ""


def verdict(mine, peer, key, higher_better):
    """+1 ahead beyond the intervals, -1 behind beyond them, 0 level."""
    a, da, b, db = mine[key], mine[key + "_ci95"], peer[key], peer[key + "_ci95"]
    if higher_better:
        a, b = -a, -b
    if a + da < b - db:
        return 1
    if a - da > b + db:
        return -1
    return 0


def counts(records, name, peer, key, higher_better):
    mine = {r["scene"]: r for r in records if r["method"] == name and r["taa"]}
    theirs = {r["scene"]: r for r in records if r["method"] == peer and r["taa"]}
    v = [verdict(mine[s], theirs[s], key, higher_better) for s in mine]
    return f"+{v.count(1)} ={v.count(0)} -{v.count(-1)}"


print(f"| problem | binary | made by | process s | iterations | objective x white{scorer} | pRelMSE x white (TAA, geo. mean) | JOD (TAA, mean) | JOD vs FAST | pRelMSE vs FAST | JOD vs STBN |")
print("| --- | --- | --- | ---: | ---: | ---: |" + (" ---: |" if scores else "") + " ---: | ---: | --- | --- | --- |")
for problem in dict.fromkeys(r["problem"] for r in runs):
    records = json.load(open(out / f"eval-{problem}.json"))
    white = {r["scene"]: r["prelmse"] for r in records if r["method"] == "white" and r["taa"]}
    for peer in ["published-fast", "published-stbn"]:
        rs = [r for r in records if r["method"] == peer and r["taa"]]
        geo = math.exp(sum(math.log(r["prelmse"] / white[r["scene"]]) for r in rs) / len(rs))
        jod = sum(r["jod"] for r in rs) / len(rs)
        print(f"| {problem} | published | {peer} | | | |{' |' if scores else ''} {geo:.3f} | {jod:.3f} | | | |")
    for run in runs:
        if run["problem"] != problem:
            continue
        name = f"{run['binary']}-{run['what']}"
        rs = [r for r in records if r["method"] == name and r["taa"]]
        geo = math.exp(sum(math.log(r["prelmse"] / white[r["scene"]]) for r in rs) / len(rs))
        jod = sum(r["jod"] for r in rs) / len(rs)
        print(
            f"| {problem} | {run['binary']} | {run['what']} | {run['process_s']} | {run['iterations']} "
            f"| {run['objective_x_white']}"
            + (f" | {scores[f'{problem}-{name}']['objective_x_white']}" if scores else "")
            + f" | {geo:.3f} | {jod:.3f} "
            f"| {counts(records, name, 'published-fast', 'jod', True)} "
            f"| {counts(records, name, 'published-fast', 'prelmse', False)} "
            f"| {counts(records, name, 'published-stbn', 'jod', True)} |"
        )
