#!/usr/bin/env python3
"""One method against others in `fsot eval` results.json: per display, TAA
setting and scene, the method's JOD, pRelMSE (the column's sigma, and the
display's eye where measured) and FLIP (after TAA, where
measured) beside each other method's, and the verdict: ahead or behind where
the 95% intervals do not overlap, else level.

    python3 bench/eval/compare.py RESULTS.json METHOD OTHER...
"""
import json
import sys


def verdict(a, a_ci, b, b_ci, higher_better):
    if a - a_ci > b + b_ci:
        return "ahead" if higher_better else "behind"
    if a + a_ci < b - b_ci:
        return "behind" if higher_better else "ahead"
    return "level"


def jod(r):
    if r.get("jod") is None or r.get("jod_ci95") is None:
        return "n/a"
    return f"{r['jod']:.3f} +- {r['jod_ci95']:.3f}"


def main():
    path, method, others = sys.argv[1], sys.argv[2], sys.argv[3:]
    records = json.load(open(path))
    displays = list(dict.fromkeys(r["display"] for r in records))
    scenes = list(dict.fromkeys(r["scene"] for r in records))
    sigmas = list(dict.fromkeys(r["sigma"] for r in records))
    for display, sigma, taa in ((d, s, t) for d in displays for s in sigmas for t in (True, False)):
        at = {
            (r["scene"], r["method"]): r
            for r in records
            if r["display"] == display and r["sigma"] == sigma and r["taa"] == taa
        }
        if not any(k[1] == method for k in at):
            continue
        of_sigma = f", sigma {sigma}" if len(sigmas) > 1 else ""
        print(f"\n{method} on {display}{of_sigma}, {'with' if taa else 'without'} TAA\n")
        head = ["scene", f"{method} JOD"] + [f"{o} JOD" for o in others]
        judges = [("jod", "jod_ci95", True, "JOD"), ("prelmse", "prelmse_ci95", False, "pRelMSE")]
        if any(r.get("prelmse_display") is not None for r in at.values()):
            judges.append(("prelmse_display", "prelmse_display_ci95", False, "pRelMSE (display's eye)"))
        if taa and any(r.get("flip") is not None for r in at.values()):
            judges.append(("flip", "flip_ci95", False, "FLIP"))
        head += [f"vs {o}: {j[3]}" for o in others for j in judges]
        print("| " + " | ".join(head) + " |")
        print("|" + " --- |" * len(head))
        counts = {}
        for s in scenes:
            m = at.get((s, method))
            if m is None:
                continue
            row = [s, jod(m)]
            row += [jod(at[(s, o)]) if (s, o) in at else "" for o in others]
            for o in others:
                r = at.get((s, o))
                for key, ci, hb, name in judges:
                    # A value the JSON could not hold (NaN, infinity: null) is no verdict.
                    if r is None or any(x.get(k) is None for x in (m, r) for k in (key, ci)):
                        row.append("")
                        continue
                    v = verdict(m[key], m[ci], r[key], r[ci], hb)
                    counts.setdefault((o, name), {}).setdefault(v, 0)
                    counts[(o, name)][v] += 1
                    row.append(v)
            print("| " + " | ".join(row) + " |")
        for (o, name), c in counts.items():
            print(f"- vs {o} by {name}: " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))


if __name__ == "__main__":
    main()
