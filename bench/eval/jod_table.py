#!/usr/bin/env python3
"""JOD tables from `fsot eval` results.json files: one table per file, display
and TAA setting, scenes as rows, methods as columns, mean +- 95% interval (and
FLIP after TAA where measured).

    python3 bench/eval/jod_table.py RESULTS.json...
"""
import json
import sys


def main():
    for path in sys.argv[1:]:
        records = json.load(open(path))
        scenes, methods, displays, sigmas = [], [], [], []
        for r in records:
            for key, seen in (("scene", scenes), ("method", methods), ("display", displays), ("sigma", sigmas)):
                if r[key] not in seen:
                    seen.append(r[key])
        for display in displays:
            for sigma in sigmas:
                for taa in (True, False):
                    table(path, records, scenes, methods, display, sigma, taa)


def table(path, records, scenes, methods, display, sigma, taa):
    cells = {(r["scene"], r["method"]): r for r in records
             if r["display"] == display and r["sigma"] == sigma and r["taa"] == taa}
    if not cells:
        return
    print(f"\n{path}: JOD on {display}, sigma {sigma}, {'with' if taa else 'without'} TAA\n")
    print("| scene | " + " | ".join(methods) + " |")
    print("| --- " * (len(methods) + 1) + "|")
    for s in scenes:
        row = []
        for m in methods:
            r = cells.get((s, m))
            row.append("" if r is None else f"{r['jod']:.3f} +- {r['jod_ci95']:.3f}")
        print(f"| {s} | " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
