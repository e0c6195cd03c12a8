#!/usr/bin/env python3
"""FLIP after TAA from `fsot eval` records: per display and scene, a method's
mean FLIP error beside others' (+- the 95% interval; lower is better) and the
verdict, ahead or behind where the intervals do not overlap, else level.

    python3 bench/eval/flip_table.py RESULTS.json METHOD OTHER...
"""
import json
import sys

from compare import verdict


def main():
    if len(sys.argv) < 4:
        raise SystemExit("usage: flip_table.py RESULTS.json METHOD OTHER...")
    path, method, others = sys.argv[1], sys.argv[2], sys.argv[3:]
    with open(path) as f:
        records = [r for r in json.load(f) if r["taa"] and r.get("flip") is not None]
    scenes = list(dict.fromkeys(r["scene"] for r in records))
    displays = list(dict.fromkeys(r["display"] for r in records))
    at = {(r["scene"], r["method"], r["display"]): r for r in records}
    shown = lambda r: f"{r['flip']:.5f} +- {r['flip_ci95']:.5f}"
    print("| scene | display | " + " | ".join([method] + others) + " | " + " | ".join(f"vs {o}" for o in others) + " |")
    print("|" + " --- |" * (2 + 1 + 2 * len(others)))
    for d in displays:
        for s in scenes:
            m = at.get((s, method, d))
            rs = [at.get((s, o, d)) for o in others]
            if m is None or None in rs:
                continue
            cells = [shown(m)] + [shown(r) for r in rs] + [verdict(m["flip"], m["flip_ci95"], r["flip"], r["flip_ci95"], False) for r in rs]
            print(f"| {s} | `{d}` | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
