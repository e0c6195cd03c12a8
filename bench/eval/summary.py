#!/usr/bin/env python3
"""One line per method, display and TAA setting from an `fsot eval` JSON: the
geometric mean over the scenes of pRelMSE as a ratio to white noise's, the mean
JOD, and the scenes counted.

Usage: bench/eval/summary.py RESULTS.json [METHOD...]
"""
import collections
import json
import math
import sys

records = json.load(open(sys.argv[1]))
wanted = sys.argv[2:]
white = {(r["scene"], r["display"], r["taa"]): r["prelmse"] for r in records if r["method"] == "white"}
cells = collections.defaultdict(list)
order = []
for r in records:
    if wanted and r["method"] not in wanted:
        continue
    key = (r["method"], r["display"], r["taa"])
    if key not in cells:
        order.append(key)
    cells[key].append((r["prelmse"] / white[(r["scene"], r["display"], r["taa"])], r["jod"]))
print("| method | display | TAA | scenes | pRelMSE x white (geometric mean) | JOD (mean) |")
print("| --- | --- | --- | ---: | ---: | ---: |")
for method, display, taa in sorted(order, key=lambda k: (k[1], not k[2], k[0])):
    v = cells[(method, display, taa)]
    g = math.exp(sum(math.log(a) for a, _ in v) / len(v))
    j = sum(b for _, b in v) / len(v)
    print(f"| {method} | {display} | {'yes' if taa else 'no'} | {len(v)} | {g:.3f} | {j:.2f} |")
