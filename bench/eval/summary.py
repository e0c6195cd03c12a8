#!/usr/bin/env python3
"""One line per method, display, sigma and TAA setting from an `fsot eval`
JSON: the geometric mean over the scenes of pRelMSE as a ratio to white noise's
(of the same scene, display, sigma and setting), the mean JOD, and the scenes
counted. The sigma column shows only where the records hold more than one.

Usage: bench/eval/summary.py RESULTS.json [METHOD...]
"""
import collections
import json
import math
import sys

records = json.load(open(sys.argv[1]))
wanted = sys.argv[2:]
white = {(r["scene"], r["display"], r["sigma"], r["taa"]): r["prelmse"] for r in records if r["method"] == "white"}
sigmas = list(dict.fromkeys(r["sigma"] for r in records))
cells = collections.defaultdict(list)
order = []
for r in records:
    if wanted and r["method"] not in wanted:
        continue
    at = (r["scene"], r["display"], r["sigma"], r["taa"])
    if at not in white:
        sys.exit(f"summary.py: no white noise record for {at}: pRelMSE has no ratio to white")
    key = (r["method"], r["display"], r["sigma"], r["taa"])
    if key not in cells:
        order.append(key)
    cells[key].append((r["prelmse"] / white[at], r["jod"]))
sigma_head = " sigma |" if len(sigmas) > 1 else ""
print(f"| method | display |{sigma_head} TAA | scenes | pRelMSE x white (geometric mean) | JOD (mean) |")
print(f"| --- | --- |{' ---: |' if sigmas[1:] else ''} --- | ---: | ---: | ---: |")
for method, display, sigma, taa in sorted(order, key=lambda k: (k[1], -k[2], not k[3], k[0])):
    v = cells[(method, display, sigma, taa)]
    g = math.exp(sum(math.log(a) for a, _ in v) / len(v))
    j = sum(b for _, b in v) / len(v)
    of_sigma = f" {sigma} |" if len(sigmas) > 1 else ""
    print(f"| {method} | {display} |{of_sigma} {'yes' if taa else 'no'} | {len(v)} | {g:.3f} | {j:.2f} |")
