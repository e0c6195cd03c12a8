#!/usr/bin/env python3
"""The GPU's time-quality table from bench/gpu/measure.sh's log (the
optimize and curve sections) and, where the masks came back and were judged,
`fsot eval --quick`'s JSON: for each tile, the 1000-iteration run from white
noise and the runs under each budget, with the process's seconds (the step's
wall time), the iterations, the objective as a fraction of white noise's, how
far past the budget the run ended, and under TAA pRelMSE's geometric mean ratio
to the published FAST mask's over the scenes, the mean JOD, and in how many
scenes the mask is ahead of (+), level with (=) or behind (-) the published
FAST and STBN masks by JOD and by pRelMSE, the 95% intervals apart.

    bench/gpu/curve-table.py LOG [EVAL_JSON]

A judged mask is named in the eval as gpu-budget-B (B the budget, e.g. 1s) or
gpu-1000it.
"""
import json
import math
import re
import sys

log = open(sys.argv[1]).read()
records = json.load(open(sys.argv[2])) if len(sys.argv) > 2 else []

step = re.compile(r"^### (\S+fsot optimize .*?--size (\S+) .*?--out \S+/gpu-\S+?-ptaa(-budget-(\S+?))?\.exr) \(at")
wrote = re.compile(r"(\d+) iterations in ([\d.]+) s \(vulkan\); objective \S+ -> \S+ \(([\d.]+) x white noise\)")
ended = re.compile(r"budget \S+ s: the run ended ([\d.]+) s after the process started \(([+-][\d.]+) s\)")
wall = re.compile(r"^wall ([\d.]+) s, exit (\d+)")

rows = []
current = None
for line in log.splitlines():
    m = step.match(line)
    if m and "--kernel perceptual-taa" in line and "--dims 2" in line and "--until" not in line \
            and "--deterministic" not in line:
        current = {"size": m.group(2), "budget": m.group(4)}
        continue
    if current is None:
        continue
    if m := wrote.search(line):
        current.update(iterations=int(m.group(1)), objective=float(m.group(3)))
    elif m := ended.search(line):
        current.update(ended=float(m.group(1)), past=m.group(2))
    elif m := wall.match(line):
        current.update(wall=float(m.group(1)))
        rows.append(current)
        current = None


def verdict(a, b, key, higher_better):
    x, dx, y, dy = a[key], a[key + "_ci95"], b[key], b[key + "_ci95"]
    if higher_better:
        x, y = -x, -y
    return 1 if x + dx < y - dy else (-1 if x - dx > y + dy else 0)


def judged(name):
    taa = [r for r in records if r["taa"]]
    mine = {r["scene"]: r for r in taa if r["method"] == name}
    if not mine:
        return None
    peers = {p: {r["scene"]: r for r in taa if r["method"] == p} for p in ("published-fast", "published-stbn")}
    fast = peers["published-fast"]
    ratio = math.exp(sum(math.log(mine[s]["prelmse"] / fast[s]["prelmse"]) for s in mine) / len(mine))
    jod = sum(r["jod"] for r in mine.values()) / len(mine)
    cells = []
    for p in ("published-fast", "published-stbn"):
        for key, hb in (("jod", True), ("prelmse", False)):
            v = [verdict(mine[s], peers[p][s], key, hb) for s in mine]
            cells.append(f"+{v.count(1)} ={v.count(0)} -{v.count(-1)}")
    return f"{ratio:.3f} | {jod:.3f} | " + " | ".join(cells)


print("| tile | run | process s | iterations | objective x white | past budget s"
      " | pRelMSE / FAST | JOD | JOD vs FAST | pRelMSE vs FAST | JOD vs STBN | pRelMSE vs STBN |")
print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- | --- | --- |")
for r in rows:
    name = f"gpu-budget-{r['budget']}" if r["budget"] else "gpu-1000it"
    run = f"`--budget {r['budget']}`" if r["budget"] else "`--iterations 1000` (white start)"
    j = judged(name) if r["size"] == "128x128x30" else None
    print(f"| {r['size']} | {run} | {r['wall']:.2f} | {r['iterations']} | {r['objective']:.3f} | "
          f"{r.get('past', '-')} | " + (j or "- | - | - | - | - | -") + " |")
